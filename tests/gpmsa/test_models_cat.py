"""Categorical inputs, a mean basis, fixed parameters and theta constraints (issue 16);
docs/categorical-and-constraints.md."""

import json
import warnings
import zipfile

import numpy as np
import pytest

import gpmsa
from gpmsa.io.container import read_raw, write_raw
from gpmsa.model.likelihood import IncrementalLikelihood, log_likelihood
from gpmsa.model.problem import prepare

SHIFT = {0: 0.0, 1: 1.0, 2: -0.7}


def truth(x, t):
    """sin(3 x0) + t + a shift by the level of the categorical x1."""
    x, t = np.atleast_2d(x), np.atleast_2d(t)
    return np.sin(3 * x[:, 0]) + t[:, 0] + np.array([SHIFT[int(v)] for v in x[:, 1]])


def cat_data(m=45, seed=1):
    rng = np.random.default_rng(seed)
    x = np.column_stack([rng.random(m), np.arange(m) % 3])
    t = rng.random((m, 1))
    return gpmsa.SimData(x, t, truth(x, t), x_names=["s", "kind"], t_names=["k"],
                         x_categorical=["kind"])  # fmt: skip


@pytest.fixture(scope="module")
def cat_emulator():
    return gpmsa.fit(cat_data(), n_iter=400, seed=3)


def test_correlation_is_rho_between_levels():
    from gpmsa.model.correlation import correlation

    a = np.array([[0.0], [0.5], [1.0]])
    R = correlation(a, None, np.array([2.0]), np.array([True]))
    rho = np.exp(-0.5)
    assert np.allclose(R, np.where(np.eye(3) > 0, 1.0, rho))


def test_incremental_likelihood_matches_dense_with_categorical_and_mean_basis():
    sim = cat_data(30)
    obs = gpmsa.ObsData(np.array([[0.3, 1], [0.6, 2]]), np.array([1.2, 1.9]))
    for mb in (None, "linear"):
        pr = prepare(sim, obs, mean_basis=mb).problem
        params = {k: v.copy() for k, v in pr.init.items()}
        inc = IncrementalLikelihood(pr, params)
        assert inc.loglik == pytest.approx(log_likelihood(pr, params), rel=1e-10)
        for name, idx, val in (("betaU", (1, 0), 0.7), ("theta", (0,), 0.3)):
            ll = inc.propose(name, idx, val)
            inc.accept()
            params[name][idx] = val
            assert ll == pytest.approx(log_likelihood(pr, params), rel=1e-10)


def test_categorical_shift_recovered(cat_emulator):
    x = np.array([[0.5, 0], [0.5, 1], [0.5, 2]])
    t = np.full((3, 1), 0.5)
    mean, var = cat_emulator.predict(x, t)
    assert np.max(np.abs(mean[:, 0] - truth(x, t))) < 0.05
    assert cat_emulator.categorical == {"kind": (0, 1, 2)}
    # the level effect: differences between levels match the known shifts
    assert mean[1, 0] - mean[0, 0] == pytest.approx(1.0, abs=0.05)
    assert mean[2, 0] - mean[0, 0] == pytest.approx(-0.7, abs=0.05)


def test_unseen_level_refused(cat_emulator):
    with pytest.raises(gpmsa.GPMSAError, match="kind has level 3, never seen"):
        cat_emulator.predict([[0.5, 3]], [[0.5]])
    with pytest.raises(gpmsa.GPMSAError, match="kind has level 5"):
        gpmsa.calibrate(cat_emulator, [[0.5, 5]], [1.0], n_samples=10, n_burn=0, tune=False)
    with pytest.raises(gpmsa.GPMSAError, match="kind has level 4"):
        gpmsa.Calibrator(cat_emulator).update([[0.5, 4]], [[1.0]])
    with pytest.raises(gpmsa.GPMSAError, match="kind has level 7"):
        gpmsa.fit(cat_data(), gpmsa.ObsData([[0.5, 7]], [1.0]), n_iter=5, tune=False)


def test_non_integer_level_refused():
    with pytest.raises(gpmsa.GPMSAError, match="levels must be integers"):
        gpmsa.SimData(np.column_stack([np.linspace(0, 1, 8), np.linspace(0, 1, 8)]),
                      np.linspace(0, 1, 8), np.arange(8.0), x_categorical=[1])  # fmt: skip


def test_calibrate_continuous_theta_with_categorical_x(cat_emulator):
    x_obs = np.array([[0.2, 0], [0.5, 1], [0.8, 2]])
    y_obs = truth(x_obs, np.full((3, 1), 0.7))
    post = gpmsa.calibrate(cat_emulator, x_obs, y_obs, n_samples=1500, n_burn=300, seed=2)
    assert np.median(post.samples["k"]) == pytest.approx(0.7, abs=0.1)
    grid = gpmsa.Calibrator(cat_emulator).update(x_obs, y_obs)
    assert grid.mean("k") == pytest.approx(0.7, abs=0.1)
    back = gpmsa.calibrate(cat_emulator, x_obs, y_obs, n_samples=600, n_burn=100, seed=2,
                           fast=False)  # fmt: skip
    assert np.median(back.samples["k"]) == pytest.approx(0.7, abs=0.15)


def test_categorical_theta_is_calibrated_by_the_fast_sampler():
    rng = np.random.default_rng(0)
    x, t = rng.random(30), np.arange(30) % 3
    shift = np.array([0.0, 1.0, -0.7])
    sim = gpmsa.SimData(x, t, x + shift[t], t_categorical=[0])
    emu = gpmsa.Emulator.from_params(sim, {"betaU": [[1.0], [1.0]], "lamUz": [1.0],
                                           "lamWs": [1e3], "lamWOs": [1e3]})  # fmt: skip
    assert emu.predict([[0.5]], [[1]])[0].shape == (1, 1)
    x_obs = np.linspace(0.1, 0.9, 5)[:, None]
    y_obs = x_obs[:, 0] + shift[2] + 0.02 * rng.standard_normal(5)  # level 2
    post = gpmsa.calibrate(emu, x_obs, y_obs, n_samples=1500, n_burn=300, seed=1)
    draws = post.samples["t0"]
    assert set(np.unique(draws)) <= {0.0, 1.0, 2.0}  # only the levels, exactly
    assert np.mean(draws == 2.0) > 0.95
    # every level reachable: with data between levels 0 and 1 both are visited (no level
    # explains them: a warning, the check at the levels, session 67)
    y_mid = x_obs[:, 0] + 0.5
    with pytest.warns(gpmsa.OutsideEmulatorWarning):
        post = gpmsa.calibrate(emu, x_obs, y_mid, n_samples=1500, n_burn=300, seed=2)
    assert {0.0, 1.0} <= set(np.unique(post.samples["t0"]))
    post = gpmsa.calibrate(emu, x_obs, y_obs, n_samples=600, n_burn=100, seed=1,
                           constraint=lambda th: th[0] != 2)  # fmt: skip
    assert not np.any(post.samples["t0"] == 2.0)  # the constraint removes the level
    # the Calibrator's grid: a probability per level (session 73; it refused a categorical
    # theta; tests/gpmsa/test_calibrator_categorical_s73.py)
    kind = gpmsa.Calibrator(emu, seed=1).update(x_obs, y_obs).grids["t0"]
    assert kind.density[2] > 0.95


def _level_case():
    rng = np.random.default_rng(0)
    x, t = rng.random(30), np.arange(30) % 3
    shift = np.array([0.0, 1.0, -0.7])
    sim = gpmsa.SimData(x, t, x + shift[t], t_categorical=[0])
    x_obs = np.linspace(0.1, 0.9, 5)[:, None]
    return sim, x_obs, x_obs[:, 0] + 0.5  # between levels 0 (+0) and 1 (+1)


def test_categorical_theta_in_a_joint_fit_agrees_with_calibrate():
    """fit(obs=) samples a categorical theta by moves between its levels (uniform prior): the
    level probabilities match gpmsa.calibrate's fast sampler at the fitted emulator."""
    sim, x_obs, y_mid = _level_case()
    pr = prepare(sim, gpmsa.ObsData(x_obs, y_mid)).problem
    params = {k: v.copy() for k, v in pr.init.items()}
    assert params["theta"][0] in (0.0, 0.5, 1.0)  # starts at a level
    inc = IncrementalLikelihood(pr, params)
    for val in (1.0, 0.0):  # the incremental likelihood's categorical theta distance
        ll = inc.propose("theta", (0,), val)
        inc.accept()
        params["theta"][0] = val
        assert ll == pytest.approx(log_likelihood(pr, params), rel=1e-10)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        emu = gpmsa.fit(sim, gpmsa.ObsData(x_obs, y_mid), n_iter=3000, seed=1, n_chains=2)
    th = emu.calibration["theta_native"]
    assert set(np.unique(th)) <= {0.0, 1.0, 2.0}  # only the levels, exactly
    p_fit = np.mean(th == 1.0)
    with pytest.warns(gpmsa.OutsideEmulatorWarning):  # between the levels: none explains it
        post = gpmsa.calibrate(emu, x_obs, y_mid, n_samples=3000, n_burn=500, seed=2)
    p_cal = np.mean(post.samples["t0"] == 1.0)
    assert 0.3 < p_fit < 0.7 and abs(p_fit - p_cal) < 0.1, (p_fit, p_cal)  # measured .526/.518
    with pytest.raises(gpmsa.GPMSAError, match="theta_init: categorical calibration parameter"):
        gpmsa.fit(sim, gpmsa.ObsData(x_obs, y_mid), n_iter=5, theta_init=[0.5])
    with pytest.raises(gpmsa.GPMSAError, match="fixed theta: categorical"):
        gpmsa.fit(sim, gpmsa.ObsData(x_obs, y_mid), n_iter=5, fixed={"theta": [1.5]})
    fixed = gpmsa.fit(sim, gpmsa.ObsData(x_obs, y_mid), n_iter=20, fixed={"theta": [2]}, seed=0)
    assert np.all(fixed.calibration["theta_native"] == 2.0)
    obs = gpmsa.ObsData(x_obs, y_mid)  # a study takes it shared (session 72), not hierarchical
    with pytest.raises(gpmsa.GPMSAError, match=r"hierarchical parameter 't0' is categorical"):
        gpmsa.fit_study([sim, sim], [obs, obs], hierarchical=["t0"], n_iter=5)


def test_file_round_trip_and_edited_declaration(cat_emulator, tmp_path):
    path = cat_emulator.save(tmp_path / "cat.gpmsa")
    back = gpmsa.load(path)
    x, t = np.array([[0.3, 2], [0.9, 0]]), np.array([[0.2], [0.8]])
    assert np.array_equal(back.predict(x, t)[0], cat_emulator.predict(x, t)[0])
    assert back.categorical == cat_emulator.categorical
    manifest, arrays = read_raw(path)
    for edit in ({"kind": [0, 1, 2, 3]}, {"kind": [0, 2]}, {"s": [0, 1]}, {"kind": "all"}):
        bad = json.loads(json.dumps({k: v for k, v in manifest.items()
                                     if k not in ("arrays", "content_sha256")}))  # fmt: skip
        bad["model"]["categorical"] = edit
        for k in ("format", "schema_version", "library_version", "created_utc"):
            bad.pop(k, None)
        out = tmp_path / "edited.gpmsa"
        write_raw(out, bad, arrays)
        with pytest.raises(gpmsa.EmulatorFileError, match="model.categorical"):
            gpmsa.load(out)
    with zipfile.ZipFile(path) as zf:
        assert json.loads(zf.read("manifest.json"))["model"]["categorical"] == {"kind": [0, 1, 2]}


def _trend_data(m=30, seed=4):
    rng = np.random.default_rng(seed)
    x, t = rng.random(m), rng.random(m)
    x[:2], t[:2] = (0.0, 1.0), (1.0, 0.0)  # the design spans [0, 1] in native units
    return gpmsa.SimData(x, t, 3.0 * x + 2.0 * t + 0.05 * np.sin(9 * x))


def test_mean_basis_recovers_a_linear_trend_better(tmp_path):
    sim = _trend_data()
    xs = np.array([[1.08], [-0.05], [1.09]])  # extrapolation, where the mean matters
    ts = np.array([[0.5], [1.08], [1.09]])
    want = 3.0 * xs[:, 0] + 2.0 * ts[:, 0]
    errs = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for mb in (None, "linear"):
            emu = gpmsa.fit(sim, n_iter=300, seed=5, mean_basis=mb)
            errs[mb] = np.max(np.abs(emu.predict(xs, ts)[0][:, 0] - want))
            if mb:
                back = gpmsa.load(emu.save(tmp_path / "lin.gpmsa"))
                assert np.array_equal(back.predict(xs, ts)[0], emu.predict(xs, ts)[0])
                assert back.mean_basis.kind == "linear"
    assert errs["linear"] < 0.5 * errs[None]
    assert errs["linear"] < 0.1


def test_callable_mean_basis_cannot_be_saved(tmp_path):
    emu = gpmsa.fit(
        _trend_data(),
        n_iter=50,
        seed=1,
        mean_basis=lambda z: np.column_stack([np.ones(len(z)), z[:, 0]]),
    )
    assert emu.predict([[0.5]], [[0.5]])[0].shape == (1, 1)
    with pytest.raises(gpmsa.GPMSAError, match="callable mean_basis cannot be saved"):
        emu.save(tmp_path / "x.gpmsa")
    with pytest.raises(gpmsa.GPMSAError, match="mean_basis must be"):
        gpmsa.fit(_trend_data(), n_iter=5, mean_basis="quadratic")


def test_fixed_parameters():
    sim = _trend_data()
    emu = gpmsa.fit(sim, n_iter=60, seed=1, fixed={"lamWOs": 5e4, "lamUz": 2.0})
    assert np.all(emu.draws["lamWOs"] == 5e4) and np.all(emu.draws["lamUz"] == 2.0)
    assert emu.settings["fixed"] == {"lamUz": [2.0], "lamWOs": [5e4]}
    with pytest.raises(gpmsa.GPMSAError, match="unknown parameter 'lamFoo'"):
        gpmsa.fit(sim, n_iter=5, fixed={"lamFoo": 1.0})
    with pytest.raises(gpmsa.GPMSAError, match=r"fixed\['betaU'\] must be a scalar or have shape"):
        gpmsa.fit(sim, n_iter=5, fixed={"betaU": [1.0, 2.0, 3.0]})
    with pytest.raises(gpmsa.GPMSAError, match="outside its prior's bounds"):
        gpmsa.fit(sim, n_iter=5, fixed={"lamWOs": 1e6})
    with pytest.raises(gpmsa.GPMSAError, match="unknown parameter 'theta'"):
        gpmsa.fit(sim, n_iter=5, fixed={"theta": 0.5})


def below_diagonal(theta):
    """Allowed: theta below 0.6 (native units)."""
    return bool(theta[0] < 0.6)


def test_constraint_in_joint_fit_and_calibrate():
    sim = _trend_data()
    x_obs = np.array([[0.3], [0.7]])
    y_obs = 3.0 * x_obs[:, 0] + 2.0 * 0.65  # the data favour theta = 0.65: forbidden
    emu = gpmsa.fit(sim, gpmsa.ObsData(x_obs, y_obs), n_iter=400, seed=2,
                    constraint=below_diagonal)  # fmt: skip
    th = emu.calibration["theta_native"][:, 0]
    assert th.max() < 0.6 and th.max() > 0.5
    plain = gpmsa.fit(sim, n_iter=300, seed=2)
    post = gpmsa.calibrate(plain, x_obs, y_obs, n_samples=1500, n_burn=200, seed=1,
                           constraint=below_diagonal)  # fmt: skip
    t0 = plain.t_names[0]
    assert post.samples[t0].max() < 0.6 and post.samples[t0].max() > 0.5
    back = gpmsa.calibrate(plain, x_obs, y_obs, n_samples=400, n_burn=50, seed=1, fast=False,
                           constraint=below_diagonal)  # fmt: skip
    assert back.samples[t0].max() < 0.6
    cal = gpmsa.Calibrator(plain, constraint=below_diagonal)
    grid = cal.update(x_obs, y_obs)
    spacing = float(np.diff(cal.theta_grid[:2])[0])  # the grid density is linear between nodes
    assert grid.samples[t0].max() < 0.6 + spacing and grid.quantile(t0, 0.5) < 0.6


def test_constraint_rejecting_the_start():
    sim = _trend_data()
    obs = gpmsa.ObsData([[0.5]], [2.0])
    above = lambda th: bool(th[0] > 0.8)  # noqa: E731
    with pytest.raises(gpmsa.GPMSAError, match="constraint rejects the initial value"):
        gpmsa.fit(sim, obs, n_iter=5, constraint=above)
    emu = gpmsa.fit(sim, obs, n_iter=50, seed=1, constraint=above, theta_init=[0.9])
    assert emu.calibration["theta_native"].min() > 0.8
    with pytest.raises(gpmsa.GPMSAError, match="constraint rejects the initial value"):
        gpmsa.calibrate(emu, [[0.5]], [2.0], n_samples=10, n_burn=0, constraint=above)
    with pytest.raises(gpmsa.GPMSAError, match="need obs="):
        gpmsa.fit(sim, n_iter=5, constraint=above)
    with pytest.raises(gpmsa.GPMSAError, match="rejects the fixed value t0=0.5; fix theta inside"):
        gpmsa.fit(sim, obs, n_iter=5, constraint=above, fixed={"theta": 0.5})


def test_other_tools_and_the_torch_backend_take_the_extensions(cat_emulator):
    # gpmsa.sensitivity takes both (tests/gpmsa/test_sens_extensions_s71.py), and so do
    # emulator_prediction, full_prediction and cross_validate (test_predict_extensions_s71.py)
    assert gpmsa.sensitivity(cat_emulator, n_draws=2).names == ("s", "kind", "k")
    mean = gpmsa.emulator_prediction(cat_emulator, [[0.5, 1]], [[0.5]], n_draws=5).mean()
    assert np.allclose(mean, cat_emulator.predict([[0.5, 1]], [[0.5]], draws=True, n_draws=5)[0])
    # the torch backend samples them too (tests/gpmsa/test_backend_extensions_s71.py)
    pytest.importorskip("torch")
    emu = gpmsa.fit(cat_data(), n_iter=5, backend="torch", tune=False, warmup=0, seed=0)
    assert emu.categorical == {"kind": (0, 1, 2)} and np.all(np.isfinite(emu.draws["betaU"]))


def test_info_shows_categorical_and_mean_basis(cat_emulator, tmp_path, capsys):
    from gpmsa.cli.main import main

    path = cat_emulator.save(tmp_path / "cat.gpmsa")
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "categorical:     kind levels [0, 1, 2]" in out
    assert "mean basis:      zero (GPM/SA)" in out


def test_calibrate_reads_a_pandas_theta_init_by_its_labels_for_the_level_check():
    """A pandas theta_init is read by its labels (as theta_init_unit does), also where
    calibrate checks that a categorical element is one of its levels: a Series listing the
    continuous parameter first is not read by position."""
    pd = pytest.importorskip("pandas")
    rng = np.random.default_rng(3)
    level, cont = np.arange(24) % 2, rng.random(24)
    x = rng.random(24)
    sim = gpmsa.SimData(x, np.column_stack([level, cont]), x + level + cont,
                        t_categorical=[0])  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        emu = gpmsa.fit(sim, n_iter=200, seed=0)
    x_obs = np.array([[0.3], [0.6]])
    start = pd.Series({"t1": 0.4, "t0": 1.0})
    post = gpmsa.calibrate(emu, x_obs, x_obs[:, 0] + 1.4, n_samples=50, n_burn=10, seed=1,
                           theta_init=start)  # fmt: skip
    assert set(np.unique(post.samples["t0"])) <= {0.0, 1.0}
    with pytest.raises(gpmsa.GPMSAError, match="t0 must be one of its training levels"):
        gpmsa.calibrate(emu, x_obs, x_obs[:, 0] + 1.4, n_samples=50, n_burn=10, seed=1,
                        theta_init=pd.Series({"t1": 0.7, "t0": 0.4}))  # fmt: skip
