"""Discrepancy precision groups (GPM/SA's lamVzGroup): the likelihood against a dense formula,
every backend, the names, records, files and the refusals."""

import contextlib
import functools
import io
import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa import GPMSAError
from gpmsa.cli.main import main
from gpmsa.model.discrepancy import check_groups, groups_of, sample_names, to_samples
from gpmsa.model.likelihood import IncrementalLikelihood, log_likelihood
from gpmsa.model.problem import prepare

GRID = np.linspace(0.0, 1.0, 10)
BASIS = np.column_stack([np.ones(GRID.size), GRID, GRID**2])
GROUPS = [0, 1, 1]


def _simulator(x, t):
    return np.sin(3.0 * GRID[None] * (1.0 + x)) + t * (1.0 + GRID[None])


@functools.cache
def _data(offset: float = 0.3, seed: int = 0):
    rng = np.random.default_rng(seed)
    x, t = rng.uniform(size=(30, 1)), rng.uniform(size=(30, 1))
    data = gpmsa.SimData(x=x, t=t, y=_simulator(x, t), x_names=["x"], t_names=["t"], index=GRID)
    xo = np.linspace(0.1, 0.9, 5)[:, None]
    yo = _simulator(xo, 0.4) + offset * np.sin(2 * xo) + 0.02 * rng.standard_normal((5, 10))
    return data, gpmsa.ObsData(x=xo, y=yo)


@functools.cache
def _emulator():
    data, _ = _data()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gpmsa.fit(data, n_iter=600, seed=0)


def _grouped_fit(n_iter: int):
    """A joint fit of the toy with BASIS in GROUPS."""
    data, obs = _data()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gpmsa.fit(data, obs, n_iter=n_iter, tune=False, seed=0, discrepancy=BASIS,
                         discrepancy_groups=GROUPS)  # fmt: skip


def _kernel(a, b, beta):
    return np.exp(-np.sum(beta * (a[:, None, :] - b[None, :, :]) ** 2, axis=-1))


def _dense_loglik(problem, prm) -> float:
    """log N([z; w]; 0, Sigma) (constants dropped) with the joint covariance written out: the v
    block of basis vector k has R(x; betaV[:, g_k]) / lamVz[g_k]."""
    obs, m, p_u = problem.obs, problem.m, problem.p_u
    n, p_v = obs.n, obs.p_v
    zt = problem.zt
    xt = np.hstack([obs.x, np.tile(prm["theta"], (n, 1))])
    nv, nu = n * p_v, n * p_u
    size = nv + nu + m * p_u
    sig = np.zeros((size, size))
    for k, g in enumerate(GROUPS):
        sl = slice(k * n, (k + 1) * n)
        sig[sl, sl] = _kernel(obs.x, obs.x, prm["betaV"][:, g]) / prm["lamVz"][g]
    for j in range(p_u):
        beta, lam = prm["betaU"][:, j], prm["lamUz"][j]
        su = slice(nv + j * n, nv + (j + 1) * n)
        sw = slice(nv + nu + j * m, nv + nu + (j + 1) * m)
        nug = 1 / (problem.lam_sim[j] * prm["lamWOs"][0]) + 1 / prm["lamWs"][j]
        sig[su, su] = _kernel(xt, xt, beta) / lam + np.eye(n) / prm["lamWs"][j]
        sig[su, sw] = _kernel(xt, zt, beta) / lam
        sig[sw, su] = sig[su, sw].T
        sig[sw, sw] = _kernel(zt, zt, beta) / lam + nug * np.eye(m)
    sig[: nv + nu, : nv + nu] += obs.sig_obs / prm["lamOs"][0]
    z = np.concatenate([obs.z, problem.w.T.ravel()])
    sign, logdet = np.linalg.slogdet(sig)
    assert sign > 0
    return -0.5 * logdet - 0.5 * z @ np.linalg.solve(sig, z)


def _grouped_problem():
    data, obs = _data()
    return prepare(data, obs, discrepancy=BASIS, discrepancy_groups=GROUPS).problem


def _random_params(problem, rng):
    prm = {k: np.array(v, dtype=float) for k, v in problem.init.items()}
    prm["theta"] = rng.uniform(0.2, 0.8, prm["theta"].shape)
    prm["betaV"] = rng.uniform(0.1, 3.0, prm["betaV"].shape)
    prm["lamVz"] = rng.uniform(1.0, 300.0, prm["lamVz"].shape)
    prm["lamOs"] = rng.uniform(50.0, 500.0, 1)
    prm["betaU"] = rng.uniform(0.1, 2.0, prm["betaU"].shape)
    return prm


def test_grouped_model_has_a_betaV_column_and_a_lamVz_per_group():
    problem = _grouped_problem()
    assert problem.init["betaV"].shape == (1, 2) and problem.init["lamVz"].shape == (2,)
    assert problem.obs.block_groups == (0, 1, 1) and problem.obs.n_groups == 2


def test_likelihoods_match_the_dense_formula():
    problem = _grouped_problem()
    rng = np.random.default_rng(4)
    for _ in range(3):
        prm = _random_params(problem, rng)
        want = _dense_loglik(problem, prm)
        np.testing.assert_allclose(log_likelihood(problem, prm), want, rtol=1e-9)
        np.testing.assert_allclose(IncrementalLikelihood(problem, prm).loglik, want, rtol=1e-9)


def test_incremental_proposals_of_each_group_match_the_dense_formula():
    problem = _grouped_problem()
    rng = np.random.default_rng(5)
    prm = _random_params(problem, rng)
    inc = IncrementalLikelihood(problem, prm)
    for name, idx, value in [("lamVz", (1,), 3.0), ("betaV", (0, 1), 0.2), ("lamVz", (0,), 90.0),
                             ("betaV", (0, 0), 2.5), ("theta", (0,), 0.6)]:  # fmt: skip
        got = inc.propose(name, idx, value)
        inc.accept()
        prm[name] = prm[name].copy()
        prm[name][idx] = value
        np.testing.assert_allclose(got, _dense_loglik(problem, prm), rtol=1e-9)


def test_torch_likelihood_matches_numpy_with_groups():
    torch = pytest.importorskip("torch")
    tb = pytest.importorskip("gpmsa.backends.torch_backend")
    problem = _grouped_problem()
    rng = np.random.default_rng(6)
    chains = [_random_params(problem, rng) for _ in range(3)]
    with tb.torch_threads(1):
        state = tb.BatchState(problem, 3, torch.float64, "cpu")
        state.reset({k: torch.as_tensor(np.stack([c[k] for c in chains])) for k in chains[0]})
        got = state.log_post().numpy()
    from gpmsa.model.likelihood import log_posterior

    np.testing.assert_allclose(got, [log_posterior(problem, c) for c in chains], rtol=1e-9)


def test_equal_group_parameters_give_the_one_group_likelihood():
    data, obs = _data()
    one = prepare(data, obs, discrepancy=BASIS).problem
    grouped = _grouped_problem()
    prm = _random_params(one, np.random.default_rng(7))
    same = dict(prm, betaV=np.repeat(prm["betaV"], 2, axis=1), lamVz=np.repeat(prm["lamVz"], 2))
    assert log_likelihood(grouped, same) == pytest.approx(log_likelihood(one, prm), rel=1e-12)


@pytest.mark.parametrize(
    ("groups", "match"),
    [
        ([0, True, True], "must be integers"),  # np.asarray would read it as [0, 1, 1]
        ([0, -1, -1], "must be >= 0"),
        ([0, 2, 2], r"2 groups numbered up to 2"),
        ([0, 10**30, 1], "numbered up to"),
        ([0, 1], "one group per discrepancy basis vector: 3"),
        ([[0, 1, 1]], "one group per discrepancy basis vector"),
        ([1, 2, 2], "counts from 1: subtract 1"),
        ([0, 2, 2], "number the groups 0 .. G-1"),
        ([0.0, 1.0, 1.0], "must be integers"),
        ([True, False, False], "must be integers"),
        ("011", "sequence of 3 integers"),
    ],
)
def test_bad_groups_are_refused_by_name(groups, match):
    with pytest.raises(GPMSAError, match=match):
        check_groups(groups, 3)


def test_groups_without_a_discrepancy_are_refused_everywhere():
    data, obs = _data()
    with pytest.raises(GPMSAError, match="needs a discrepancy basis"):
        gpmsa.fit(data, obs, n_iter=10, discrepancy_groups=[0])
    with pytest.raises(GPMSAError, match="needs a discrepancy basis"):
        gpmsa.calibrate(_emulator(), obs, n_samples=10, n_burn=1, discrepancy_groups=[0])


def test_all_in_group_zero_is_the_default_model():
    assert check_groups([0, 0, 0], 3) is None
    data, obs = _data()
    a = prepare(data, obs, discrepancy=BASIS, discrepancy_groups=[0, 0, 0]).problem
    assert a.init["lamVz"].shape == (1,) and a.obs.v_groups is None


def test_names_one_group_unchanged_several_indexed():
    assert sample_names(1, 1) == (["betaV"], ["lamVz"])
    assert sample_names(2, 1) == (["betaV[0]", "betaV[1]"], ["lamVz"])
    assert sample_names(2, 2) == (
        ["betaV[0,0]", "betaV[1,0]", "betaV[0,1]", "betaV[1,1]"], ["lamVz[0]", "lamVz[1]"]
    )  # fmt: skip
    beta = np.arange(12.0).reshape(3, 2, 2)
    out = to_samples(beta, np.ones((3, 2)))
    np.testing.assert_array_equal(out["betaV[1,0]"], beta[:, 1, 0])
    assert groups_of(out, 2) == 2
    with pytest.raises(GPMSAError, match="not those of a discrepancy"):
        groups_of({k: v for k, v in out.items() if k != "lamVz[1]"}, 2)


@pytest.mark.parametrize("name", ["lamVz[0]", "betaV[0,1]"])
def test_group_names_are_reserved(name):
    with pytest.raises(GPMSAError, match="reserved name"):
        rng = np.random.default_rng(0)
        gpmsa.SimData(x=rng.random((6, 1)), t=rng.random((6, 1)), y=rng.random((6, 1)),
                      t_names=[name])  # fmt: skip


def test_joint_fit_records_groups_saves_and_predicts(tmp_path):
    data, obs = _data()
    emu = _grouped_fit(100)
    assert emu.calibration["betaV"].shape[1:] == (1, 2)
    assert emu.settings["discrepancy_groups"] == GROUPS
    emu.save(tmp_path / "e.gpmsa")
    back = gpmsa.load(tmp_path / "e.gpmsa")
    post = gpmsa.calibration_posterior(back)
    assert post.names == ("t", "lamOs", "betaV[0,0]", "betaV[0,1]", "lamVz[0]", "lamVz[1]")
    pred = gpmsa.full_prediction(back, obs, [[0.5]], discrepancy=BASIS, seed=0)
    assert pred.delta.shape == (80, 1, 10) and np.all(np.isfinite(pred.y))
    with pytest.raises(
        GPMSAError, match=r"\[0, 0, 1\] .* differs from the calibration's \[0, 1, 1"
    ):
        gpmsa.full_prediction(back, obs, [[0.5]], discrepancy=BASIS, discrepancy_groups=[0, 0, 1])
    with pytest.raises(GPMSAError, match="2 discrepancy precision group"):
        gpmsa.full_prediction(back, obs, [[0.5]], discrepancy=BASIS, discrepancy_groups=None)


def test_group_of_each_vector_sets_its_prediction_prior():
    """With the data of one experiment and two groups of very different precisions the new
    point's v components take each its own group's prior variance."""
    emu = _emulator()
    _, obs = _data()
    post = gpmsa.calibrate(emu, obs, discrepancy=BASIS, discrepancy_groups=GROUPS, n_samples=40,
                           n_burn=0, tune=False, seed=0)  # fmt: skip
    samples = dict(post.samples)
    samples["lamVz[0]"] = np.full(40, 1e-2)  # group 0 (the constant) vague
    samples["lamVz[1]"] = np.full(40, 1e6)  # group 1 (slope, curvature) held near zero
    fixed = gpmsa.Posterior(samples, info=post.info)
    pred = gpmsa.full_prediction(emu, obs, [[0.99]], posterior=fixed, discrepancy=BASIS, seed=0)
    var = pred.cov[:, 0].diagonal(axis1=-2, axis2=-1).mean(axis=0)
    assert var[0] > 1e3 * max(var[1], var[2])


@pytest.mark.parametrize("backend", ["numpy", "torch"])
def test_calibrate_backends_sample_each_groups_precision(backend):
    """A constant offset and no slope: the constant's group takes a small lamVz, the slope and
    curvature's group a large one (numpy: 3.2 against 1,000 here). Over seeds 0-11 the medians
    were 2.0-4.0 against 140-1,000 (numpy) and 2.4-3.7 against 350-1,030 (torch); one group
    for the three vectors gives one lamVz."""
    if backend != "numpy":
        pytest.importorskip("torch")
    emu = _emulator()
    _, obs = _data()
    post = gpmsa.calibrate(emu, obs, discrepancy=BASIS, discrepancy_groups=GROUPS,
                           n_samples=300, n_burn=100, seed=1, backend=backend,
                           tune_rounds=5)  # fmt: skip
    assert post.info["discrepancy_groups"] == GROUPS
    lam0, lam1 = (float(np.median(post.samples[k])) for k in ("lamVz[0]", "lamVz[1]"))
    assert lam0 < 30 and lam1 > 10 * lam0
    pred = gpmsa.full_prediction(emu, obs, [[0.5]], posterior=post, discrepancy=BASIS, seed=0)
    assert np.all(np.isfinite(pred.delta))


def test_pyro_samples_a_grouped_discrepancy():
    pytest.importorskip("pyro")
    emu = _emulator()
    _, obs = _data()
    post = gpmsa.calibrate(emu, obs, discrepancy=BASIS, discrepancy_groups=GROUPS,
                           n_samples=12, n_burn=4, seed=0, backend="pyro", n_warmup=8)  # fmt: skip
    assert {"lamVz[0]", "lamVz[1]", "betaV[0,0]", "betaV[0,1]"} <= set(post.names)
    assert all(np.all(post.samples[k] > 0) for k in ("lamVz[0]", "lamVz[1]"))


def test_study_members_carry_their_groups():
    data, obs = _data()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        study = gpmsa.fit_study([data, data], [obs, obs], shared=["t"], n_iter=60, tune=False,
                                seed=0, discrepancy=BASIS, discrepancy_groups=GROUPS)  # fmt: skip
    post = study.member_posterior(1)
    assert post.info["discrepancy_groups"] == GROUPS and "lamVz[1]" in post.names
    pred = gpmsa.full_prediction(study.members[1], obs, [[0.5]], posterior=post,
                                 discrepancy=BASIS, seed=0)  # fmt: skip
    assert np.all(np.isfinite(pred.y))


def test_calibrated_predict_refuses_noise_with_grouped_discrepancy_draws():
    emu = _emulator()
    _, obs = _data()
    post = gpmsa.calibrate(emu, obs, discrepancy=BASIS, discrepancy_groups=GROUPS, n_samples=20,
                           n_burn=0, tune=False, seed=0)  # fmt: skip
    with pytest.raises(GPMSAError, match="has discrepancy draws"):
        gpmsa.predictive.calibrated_predict(emu, post, [[0.5]], noise=True)


def test_gpmsa_info_shows_the_groups_and_betaU_layout(tmp_path):
    emu = _grouped_fit(40)
    path = emu.save(tmp_path / "e.gpmsa")
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        main(["info", str(path)])
    text = out.getvalue()
    assert "discrepancy:     given, precision groups [0, 1, 1]" in text
    assert f"posterior betaU (2 x {emu.p_u}, row by row)" in text


def test_gpmsa_info_of_a_study_shows_each_models_groups(tmp_path):
    data, obs = _data()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        study = gpmsa.fit_study([data, data], [obs, obs], shared=["t"], n_iter=40, tune=False,
                                seed=0, discrepancy=BASIS, discrepancy_groups=GROUPS)  # fmt: skip
    path = study.save(tmp_path / "st")
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        main(["info", str(path)])
    assert out.getvalue().count("discrepancy given, precision groups [0, 1, 1]") == 2
