"""Models without known inputs (p = 0): the GP correlates over t only (SEPIA's dummy-x case).

Toys: a scalar y = sin(3 t) on t in [0.55, 1.0] (one-to-one there: 3 t lies past pi / 2) and a
functional y(s) = sin(3 t + s) on s in [0, 1]; the observations are generated at t* = 0.6.
"""

import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.backends import available
from gpmsa.cli.main import main

T_STAR = 0.6
GRID = np.linspace(0.0, 1.0, 10)


@pytest.fixture(scope="module")
def scalar_emu():
    rng = np.random.default_rng(0)
    t = rng.uniform(0.55, 1.0, size=(20, 1))
    y = np.sin(3 * t) + 0.002 * rng.standard_normal((20, 1))
    return gpmsa.fit(gpmsa.SimData(t=t, y=y), n_iter=300, seed=0)


@pytest.fixture(scope="module")
def functional_data():
    rng = np.random.default_rng(1)
    t = rng.uniform(0.0, 1.0, size=(25, 1))
    y = np.sin(3 * t + GRID) + 0.005 * rng.standard_normal((25, GRID.size))
    return gpmsa.SimData(t=t, y=y, index=GRID)


@pytest.fixture(scope="module")
def functional_emu(functional_data):
    return gpmsa.fit(functional_data, n_iter=300, seed=0)


def y_star(noise: float = 0.0) -> np.ndarray:
    """One observation (1, 10) of the functional toy at t*."""
    return np.sin(3 * T_STAR + GRID)[None, :] + noise


# --- data ---------------------------------------------------------------------------------------
def test_simdata_without_x_has_p_zero():
    t = np.linspace(0.0, 1.0, 12)[:, None]
    data = gpmsa.SimData(t=t, y=np.sin(3 * t))
    assert data.p == 0 and data.x.shape == (12, 0) and data.x_names == ()
    empty = gpmsa.SimData(x=np.empty((12, 0)), t=t, y=np.sin(3 * t))
    assert empty.p == 0 and empty.x_units == ()
    positional = gpmsa.SimData(t, t**2, np.sin(3 * t))  # SimData(x, t, y) as before
    assert (positional.p, positional.q) == (1, 1)


def test_simdata_still_needs_t_and_y():
    t = np.linspace(0.0, 1.0, 12)[:, None]
    with pytest.raises(gpmsa.GPMSAError, match=r"SimData needs t \(m, q\) and y \(m, l_sim\)"):
        gpmsa.SimData(t=t)
    with pytest.raises(gpmsa.GPMSAError, match="x_names must have 0 entries"):
        gpmsa.SimData(t=t, y=np.sin(3 * t), x_names=["a"])


def test_a_dummy_x_column_is_refused_with_the_way_to_leave_it_out():
    """SEPIA's users fill in x = 0.5 for a simulator without known inputs; here a constant
    column is refused, and the message says to leave x out."""
    t = np.linspace(0.0, 1.0, 12)[:, None]
    with pytest.raises(gpmsa.GPMSAError) as err:
        gpmsa.SimData(x=np.full((12, 1), 0.5), t=t, y=np.sin(3 * t))
    assert str(err.value) == (
        "design column x[:, 0] is constant (0.5); every input must vary (a dummy x, as SEPIA's 0.5 "
        "for a simulator without known inputs: leave x out, SimData(t=..., y=...))"
    )
    with pytest.raises(gpmsa.GPMSAError, match=r"constant \(0.5\); every input must vary$"):
        gpmsa.SimData(x=t, t=np.full((12, 1), 0.5), y=np.sin(3 * t))


def test_obsdata_without_x_rows_are_replicates():
    obs = gpmsa.ObsData(y=np.vstack([y_star(), y_star(0.01)]))
    assert obs.n == 2 and obs.x.shape == (2, 0)
    assert gpmsa.ObsData(y=y_star()[0]).n == 1  # a 1-D y is one experiment
    assert gpmsa.ObsData(x=np.empty((2, 0)), y=obs.y).digest() == obs.digest()
    with pytest.raises(gpmsa.GPMSAError, match=r"ObsData needs y \(n, l_obs\)"):
        gpmsa.ObsData()


# --- calibration ---------------------------------------------------------------------------------
def test_scalar_calibration_recovers_t_star(scalar_emu):
    y_obs = [[np.sin(3 * T_STAR)]]
    mcmc = gpmsa.calibrate(scalar_emu, y_obs=y_obs, n_samples=3000, n_burn=500, seed=1)
    grid = gpmsa.Calibrator(scalar_emu).update(y_obs=y_obs)
    mean, sd = grid.mean("t0"), grid.sd("t0")
    assert sd < 0.05  # informative: the toy is one-to-one on the design
    assert abs(mean - T_STAR) < 3 * sd
    # the MCMC agrees with the exact grid posterior within its Monte-Carlo error (ESS >= 100)
    assert abs(mcmc.mean("t0") - mean) < 3 * sd / np.sqrt(100)


def test_functional_calibration_recovers_t_star(functional_emu):
    post = gpmsa.calibrate(functional_emu, y_obs=y_star(), n_samples=2000, n_burn=500, seed=1)
    assert post.sd("t0") < 0.02
    assert abs(post.mean("t0") - T_STAR) < 3 * post.sd("t0")
    cal = gpmsa.Calibrator(functional_emu)
    grid = cal.update(y_obs=y_star())
    assert abs(grid.mean("t0") - T_STAR) < 3 * grid.sd("t0")
    nodes, ll = cal.log_likelihood_grid(y_obs=y_star())
    assert abs(nodes[np.argmax(ll)] - T_STAR) < 2 * (nodes[1] - nodes[0])


def test_x_obs_none_equals_empty_columns(functional_emu):
    y_obs = np.vstack([y_star(), y_star(0.01)])  # two replicates of the one experiment
    kw = {"n_samples": 400, "n_burn": 100, "seed": 3}
    a = gpmsa.calibrate(functional_emu, y_obs=y_obs, **kw)
    b = gpmsa.calibrate(functional_emu, np.empty((2, 0)), y_obs, **kw)
    np.testing.assert_array_equal(a.samples["t0"], b.samples["t0"])
    assert abs(a.mean("t0") - T_STAR) < 3 * a.sd("t0") + 0.005  # + the replicates' offset


def test_calibration_refusals(functional_emu, scalar_emu):
    with pytest.raises(gpmsa.GPMSAError, match=r"y_obs is required: .*give the outputs by name"):
        gpmsa.Calibrator(functional_emu).update(y_star())  # positional: that is x_obs
    with pytest.raises(gpmsa.GPMSAError, match=r"y_obs is required: .*native units$"):
        gpmsa.Calibrator(functional_emu).update()
    with pytest.raises(gpmsa.GPMSAError, match=r"x_obs must have shape \(n, 0\)"):
        gpmsa.calibrate(scalar_emu, [[0.5]], [[0.9]], n_samples=10, n_burn=0)
    rng = np.random.default_rng(2)
    x, t = rng.uniform(size=(15, 1)), rng.uniform(size=(15, 1))
    with_x = gpmsa.Emulator.from_params(
        gpmsa.SimData(x=x, t=t, y=x + t),
        {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [1e4], "lamWOs": [1e4]},
    )
    msg = r"x_obs is required: the emulator has p = 1 known input\(s\) \['x0'\]"
    with pytest.raises(gpmsa.GPMSAError, match=msg):
        gpmsa.calibrate(with_x, y_obs=[[1.0]], n_samples=10, n_burn=0)
    with pytest.raises(gpmsa.GPMSAError, match=msg):
        gpmsa.Calibrator(with_x).update(y_obs=[[1.0]])


# --- prediction and files -----------------------------------------------------------------------
def test_predictions_at_t_only(functional_emu):
    t_new = np.array([[0.2], [0.6], [0.8]])
    mean, var = functional_emu.predict(None, t_new)
    same = functional_emu.predict(np.empty((3, 0)), t_new)
    np.testing.assert_array_equal(mean, same[0])
    truth = np.sin(3 * t_new + GRID)
    assert np.max(np.abs(mean - truth)) < 0.03
    assert np.all(np.abs(mean - truth) < 5 * np.sqrt(var))
    pred = gpmsa.emulator_prediction(functional_emu, None, t_new, n_draws=20, seed=0)
    draws_mean = functional_emu.predict(None, t_new, draws=True, n_draws=20)[0]
    np.testing.assert_allclose(pred.mean(), draws_mean, rtol=0, atol=1e-12)


def test_calibrated_prediction_without_x(functional_emu):
    post = gpmsa.Calibrator(functional_emu).update(y_obs=y_star())
    pred = gpmsa.predictive.calibrated_predict(functional_emu, post)
    assert pred.mean.shape == (1, GRID.size)
    assert np.max(np.abs(pred.mean[0] - y_star()[0])) < 0.03


def test_save_load_round_trip(functional_emu, tmp_path, capsys):
    path = functional_emu.save(tmp_path / "p0.gpmsa")
    loaded = gpmsa.load(path)
    assert loaded.p == 0 and loaded.x_unit.shape == (25, 0) and loaded.x_names == ()
    assert main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "p=0, q=1" in out and "known inputs:    none\n" in out
    t_new = [[0.3], [0.7]]
    for draws in (False, True):
        a = functional_emu.predict(None, t_new, draws=draws)
        b = loaded.predict(None, t_new, draws=draws)
        np.testing.assert_array_equal(a[0], b[0])
        np.testing.assert_array_equal(a[1], b[1])


# --- joint fit ------------------------------------------------------------------------------------
def test_joint_fit_with_replicates_and_discrepancy(functional_data, tmp_path):
    obs = gpmsa.ObsData(y=np.vstack([y_star(-0.005), y_star(0.005)]))
    emu = gpmsa.fit(functional_data, obs, n_iter=400, seed=0, discrepancy="constant")
    post = gpmsa.calibration_posterior(emu)
    assert "lamVz" in post.names and not any(n.startswith("betaV") for n in post.names)
    assert abs(post.mean("t0") - T_STAR) < 3 * post.sd("t0")
    loaded = gpmsa.load(emu.save(tmp_path / "joint.gpmsa"))
    np.testing.assert_array_equal(gpmsa.calibration_posterior(loaded).samples["t0"],
                                  post.samples["t0"])  # fmt: skip
    a = gpmsa.full_prediction(emu, obs, None, n_draws=10, seed=4)
    b = gpmsa.full_prediction(loaded, obs, None, n_draws=10, seed=4)
    np.testing.assert_array_equal(a.y, b.y)
    assert np.max(np.abs(a.mean("y")[0] - y_star()[0])) < 0.05


def test_plot_over_x_refused(scalar_emu):
    obs = gpmsa.ObsData(y=[[np.sin(3 * T_STAR)]])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        post = gpmsa.calibrate(scalar_emu, y_obs=obs.y, discrepancy="constant",
                               n_samples=200, n_burn=50, seed=1)  # fmt: skip
    pred = gpmsa.full_prediction(scalar_emu, obs, None, posterior=post, discrepancy="constant",
                                 n_draws=10, seed=0)  # fmt: skip
    pytest.importorskip("matplotlib")
    with pytest.raises(gpmsa.GPMSAError, match=r"against a known input.*has none \(p = 0"):
        gpmsa.plots.prediction_bands(pred)


# --- backends -------------------------------------------------------------------------------------
@pytest.mark.parametrize("backend", ["torch", pytest.param("pyro", marks=pytest.mark.slow)])
def test_generic_backends_calibrate_p_zero(scalar_emu, backend):
    if backend not in available():
        pytest.skip(f"{backend} not installed")
    y_obs = [[np.sin(3 * T_STAR)], [np.sin(3 * T_STAR) + 0.002]]
    # torch: 10 tuning rounds (one chain's default: 50, 6 s): over seeds 0-11 the mean within
    # 0.5 sd of T_STAR
    rounds = {"tune_rounds": 10} if backend == "torch" else {}
    post = gpmsa.calibrate(scalar_emu, y_obs=y_obs, n_samples=300, n_burn=100, seed=1,
                           backend=backend, discrepancy="constant", **rounds)  # fmt: skip
    assert "lamVz" in post.names
    assert abs(post.mean("t0") - T_STAR) < 3 * post.sd("t0")


def test_fit_study_of_models_without_known_inputs_takes_a_discrepancy(tmp_path):
    """Session 62: fit_study with p = 0 models and a discrepancy failed reshaping betaV's
    (chains, draws, 0, G) draws ("cannot reshape array of size 0"); gpmsa.fit took it."""
    t = np.linspace(0.05, 0.95, 12)[:, None]
    sim = gpmsa.SimData(t=t, y=np.exp(1.5 * t), t_names=["t"])
    obs = gpmsa.ObsData(y=[[float(np.exp(0.6)) + 0.1], [float(np.exp(0.6)) + 0.08]])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # 60 sweeps
        study = gpmsa.fit_study([sim, sim], [obs, obs], shared=["t"], discrepancy="constant",
                                n_iter=60, n_keep=20, tune=False, seed=0)  # fmt: skip
        alone = gpmsa.fit(sim, obs, discrepancy="constant", n_iter=60, tune=False, seed=0)
    names = gpmsa.calibration_posterior(alone).names
    assert study.member_posterior(0).names == names == ("t", "lamOs", "lamVz")
    back = gpmsa.load_study(study.save(tmp_path / "s.gpmsa"))
    np.testing.assert_array_equal(
        back.member_posterior(1).samples["lamVz"], study.member_posterior(1).samples["lamVz"]
    )
