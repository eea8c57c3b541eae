"""A user-supplied emulator basis (``fit(..., basis=)``, GPM/SA's ``Ksim``): checks, the
weight-scale warning, agreement with the PCA path, files, continuation and studies."""

import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.cli.main import main

GRID = np.linspace(0.0, 1.0, 25)


def _sim(m: int = 30, seed: int = 0, span: tuple = (0.0, 1.0)) -> gpmsa.SimData:
    rng = np.random.default_rng(seed)
    x, t = rng.uniform(*span, size=(m, 1)), rng.uniform(*span, size=(m, 1))
    y = np.sin(2 * np.pi * GRID[None, :] * (1 + t)) + x * GRID[None, :]
    return gpmsa.SimData(x=x, t=t, y=y, index=GRID, t_names=["t"])


def _obs() -> gpmsa.ObsData:
    y = np.sin(2 * np.pi * GRID * 1.4) + 0.5 * GRID
    return gpmsa.ObsData(x=[[0.5]], y=[y], index=GRID)


def _cosine_basis(sim: gpmsa.SimData, n: int) -> np.ndarray:
    """An orthogonal basis that is not the runs' PCA: cosines on the grid, orthogonalised and
    scaled to unit-variance weights."""
    raw = np.cos(np.pi * np.outer(GRID, np.arange(n)))
    q, _ = np.linalg.qr(raw)
    y_std = gpmsa.prepare(sim).standardizer.y_to_std(sim.y)
    return q * np.sqrt(np.mean((y_std @ q) ** 2, axis=0))


def _no_warnings(fn, *args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return fn(*args, **kwargs)


def _only_convergence_warning(fn, *args, **kwargs):
    """``fn(...)`` warning of nothing but its short chain (one chain is judged since session 76:
    these 200- and 600-sweep chains are flagged)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        out = fn(*args, **kwargs)
    assert {w.category for w in caught} == {gpmsa.ConvergenceWarning}, [
        str(w.message) for w in caught
    ]
    return out


def test_the_pca_basis_given_gives_the_pca_fit_bit_for_bit():
    sim = _sim()
    K = gpmsa.prepare(sim, n_pc=3).K
    pca = gpmsa.fit(sim, n_iter=200, seed=1, n_pc=3, tune=False)
    given = _only_convergence_warning(gpmsa.fit, sim, n_iter=200, seed=1, basis=K, tune=False)
    assert np.array_equal(given.K, pca.K)
    for k, v in pca.draws.items():
        assert np.array_equal(given.draws[k], v), k
    assert (pca.settings["basis"], given.settings["basis"]) == ("pca", "given")


def test_another_basis_is_used_as_given_and_predicts_held_out_runs():
    sim, held = _sim(), _sim(m=10, seed=5, span=(0.1, 0.9))
    K = _cosine_basis(sim, 8)
    emu = _only_convergence_warning(gpmsa.fit, sim, n_iter=600, seed=2, basis=K)
    assert np.array_equal(emu.K, K)
    assert not np.allclose(np.abs(emu.K[:, :3]), np.abs(gpmsa.prepare(sim, n_pc=3).K))
    pred = gpmsa.emulator_prediction(emu, x=held.x, t=held.t, seed=3)
    err = np.sqrt(np.mean((pred.mean() - held.y) ** 2))
    assert err < 0.1 * np.std(held.y), err  # a poor basis would leave the 25-value curves


@pytest.mark.parametrize(
    ("basis", "message"),
    [
        (np.ones(25), "2-D array"),
        (np.ones((24, 2)), "one row per simulation output value"),
        (np.eye(25)[:3], "SEPIA stores K as"),
        (np.full((25, 1), np.nan), "must be finite"),
        (np.column_stack([np.eye(25)[:, 0], np.zeros(25)]), r"column\(s\) \[1\] are zero"),
        (np.column_stack([np.eye(25)[:, 0], np.eye(25)[:, 0] + np.eye(25)[:, 1]]),
         "must be orthogonal"),
        (np.ones((25, 26)), "1 to 25 columns"),
        ([["a"] * 2] * 25, "numeric array"),
        (np.full((25, 1), 1e200), "too large to square"),
    ],
)  # fmt: skip
def test_a_bad_basis_is_refused_naming_why(basis, message):
    with pytest.raises(gpmsa.GPMSAError, match=message):
        gpmsa.fit(_sim(), n_iter=10, basis=basis)


def test_basis_and_n_pc_are_not_both_given():
    with pytest.raises(gpmsa.GPMSAError, match="n_pc .* or basis, not both"):
        gpmsa.prepare(_sim(), n_pc=2, basis=np.eye(25)[:, :2])


def test_a_scalar_output_takes_only_its_basis_of_one():
    rng = np.random.default_rng(0)
    sim = gpmsa.SimData(x=rng.uniform(size=(12, 1)), t=rng.uniform(size=(12, 1)),
                        y=rng.normal(size=(12, 1)))  # fmt: skip
    assert gpmsa.prepare(sim, basis=[[1.0]]).K.tolist() == [[1.0]]
    with pytest.raises(gpmsa.GPMSAError, match=r"scalar output's basis is \[\[1.0\]\]"):
        gpmsa.prepare(sim, basis=[[2.0]])


def test_weights_off_the_prior_scale_warn_naming_the_columns_and_the_cure():
    sim = _sim()
    K = _cosine_basis(sim, 4)
    scaled = K * np.array([1.0, 10.0, 1.0, 0.05])
    with pytest.warns(gpmsa.BasisWarning, match=r"column\(s\) \[1, 3\].*Multiply column j"):
        gpmsa.prepare(sim, basis=scaled)
    _no_warnings(gpmsa.prepare, sim, basis=K)  # the cure: unit-scale weights


def test_a_column_the_runs_do_not_use_is_named_to_leave_out():
    sim = _sim()  # every run is 0 at GRID[0]: the unit vector there holds none of their variation
    raw = np.column_stack([np.eye(25)[:, 0], np.cos(np.pi * np.outer(GRID, np.arange(4)))])
    q, _ = np.linalg.qr(raw)
    y_std = gpmsa.prepare(sim).standardizer.y_to_std(sim.y)
    assert np.all(y_std[:, 0] == 0.0)
    used = q[:, 1:] * np.sqrt(np.mean((y_std @ q[:, 1:]) ** 2, axis=0))
    with pytest.warns(gpmsa.BasisWarning, match=r"Column\(s\) \[4\] hold none"):
        gpmsa.prepare(sim, basis=np.column_stack([used, q[:, 0]]))


def test_the_weight_scale_is_judged_by_the_lamuz_prior_given():
    sim = _sim()
    K = _cosine_basis(sim, 4)
    tight = gpmsa.Priors(lamUz=gpmsa.GammaPrior(400.0, 4.0))  # lamUz ~ 100: weights' sd ~0.1
    with pytest.warns(gpmsa.BasisWarning, match=r"Gamma\(400, 4\)"):
        gpmsa.prepare(sim, basis=K, priors=tight)
    _no_warnings(gpmsa.prepare, sim, basis=K * 10.0, priors=tight)  # weights / 10


def test_a_given_basis_round_trips_and_info_names_it(tmp_path, capsys):
    sim = _sim()
    K = _cosine_basis(sim, 6)
    emu = gpmsa.fit(sim, n_iter=200, seed=1, basis=K)
    path = tmp_path / "given.gpmsa"
    emu.save(path)
    back = gpmsa.load(path)
    assert np.array_equal(back.K, K) and back.settings["basis"] == "given"
    capsys.readouterr()
    assert main(["info", str(path)]) == 0  # in process; python -m gpmsa: test_cli_module_and_info
    out = capsys.readouterr().out
    line = next(s for s in out.splitlines() if s.startswith("basis:"))
    y_std = emu.standardizer.y_to_std(sim.y)
    share = 1 - np.sum((y_std - emu.w @ K.T) ** 2) / np.sum(y_std**2)
    assert "given" in line and "6 vector(s)" in line and f"{share:.2%}" in line


def test_a_pca_file_shows_its_basis_share(tmp_path, capsys):
    sim = _sim()
    path = tmp_path / "pca.gpmsa"
    gpmsa.fit(sim, n_iter=100, seed=1, n_pc=2).save(path)
    capsys.readouterr()
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "basis:           PCA of the runs, 2 vector(s)" in out


def test_a_joint_fit_with_a_given_basis_continues_only_with_that_basis():
    sim, obs = _sim(), _obs()
    K = _cosine_basis(sim, 6)
    first = gpmsa.fit(sim, obs, n_iter=150, seed=3, basis=K, discrepancy="constant", tune=False)
    more = gpmsa.fit(sim, obs, n_iter=50, seed=4, basis=K, discrepancy="constant", init=first,
                     tune=False)  # fmt: skip
    assert more.settings["continued_from"] == first.model_sha256
    with pytest.raises(gpmsa.GPMSAError, match="another n_pc or basis"):
        gpmsa.fit(sim, obs, n_iter=50, seed=4, n_pc=6, discrepancy="constant", init=first)


def test_fit_study_takes_a_basis_per_model(tmp_path):
    sim, obs = _sim(), _obs()
    K = _cosine_basis(sim, 5)
    study = gpmsa.fit_study([sim, sim], [obs, obs], shared=["t"], n_iter=120, seed=1,
                            tune_rounds=3, basis=[K, None])  # fmt: skip
    first, second = study.members
    assert np.array_equal(first.K, K) and first.settings["basis"] == "given"
    assert second.settings["basis"] == "pca"
    assert np.array_equal(second.K, gpmsa.prepare(sim).K)
    study.save(tmp_path / "s.gpmsa")
    back = gpmsa.load_study(tmp_path / "s.gpmsa")
    assert np.array_equal(back.members[0].K, K)
    assert [m.settings["basis"] for m in back.members] == ["given", "pca"]
    every = gpmsa.fit_study([sim, sim], [obs, obs], shared=["t"], n_iter=60, seed=1,
                            tune_rounds=2, basis=K)  # fmt: skip
    assert all(np.array_equal(m.K, K) for m in every.members)
    with pytest.raises(gpmsa.GPMSAError, match="basis has 1 entries for 2 models"):
        gpmsa.fit_study([sim, sim], [obs, obs], n_iter=10, basis=[K])
    with pytest.raises(gpmsa.GPMSAError, match="basis must be None, a numpy array"):
        gpmsa.fit_study([sim, sim], [obs, obs], n_iter=10, basis="pca")
    with pytest.raises(gpmsa.GPMSAError, match="model 'model1'.*must be orthogonal"):
        gpmsa.fit_study([sim, sim], [obs, obs], n_iter=10, basis=[None, np.ones((25, 2))])


def test_fit_study_s_n_pc_sizes_the_pca_of_the_models_without_a_basis():
    """basis=[K, None] with n_pc=3: model 0 takes K, model 1 its PCA of 3 vectors (the
    docstring's "None: the model's PCA, as n_pc says"); n_pc beside a basis for every model
    is refused, as fit refuses it."""
    sim, obs = _sim(), _obs()
    K = _cosine_basis(sim, 5)
    study = gpmsa.fit_study([sim, sim], [obs, obs], shared=["t"], n_iter=40, seed=1,
                            tune_rounds=2, basis=[K, None], n_pc=3)  # fmt: skip
    first, second = study.members
    assert np.array_equal(first.K, K) and second.K.shape[1] == 3
    assert second.settings["n_pc"] == 3 and second.settings["basis"] == "pca"
    with pytest.raises(gpmsa.GPMSAError, match=r"n_pc .* or basis, not both; got n_pc=3"):
        gpmsa.fit_study([sim, sim], [obs, obs], n_iter=10, basis=K, n_pc=3)


def test_from_params_takes_a_basis():
    sim = _sim()
    K = _cosine_basis(sim, 3)
    params = {"betaU": np.full((2, 3), 0.5), "lamUz": np.ones(3), "lamWs": np.full(3, 1e3),
              "lamWOs": np.array([1e3])}  # fmt: skip
    emu = gpmsa.Emulator.from_params(sim, params, basis=K)
    assert np.array_equal(emu.K, K) and emu.settings["basis"] == "given"


def test_prepare_shows_each_basis_vector_s_share_of_the_runs_variance():
    sim = _sim()
    prep = gpmsa.prepare(sim, n_pc=3)
    y_std = prep.standardizer.y_to_std(sim.y)
    s = np.linalg.svd(y_std, compute_uv=False)
    assert np.allclose(prep.variance_shares, s[:3] ** 2 / np.sum(s**2), rtol=1e-10)
    given = gpmsa.prepare(sim, basis=_cosine_basis(sim, 5))
    left = np.sum((y_std - given.problem.w @ given.K.T) ** 2) / np.sum(y_std**2)
    assert np.sum(given.variance_shares) == pytest.approx(1.0 - left, rel=1e-10)
    text = repr(prep)
    assert "p_u=3 basis vectors" in text and f"{np.sum(prep.variance_shares):.3%}" in text
    assert len(text) < 300  # no arrays dumped
