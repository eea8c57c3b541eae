"""SimData(y_scale="columnwise"): each output element standardised by its own sd (SEPIA's
standardize_y(scale='columnwise')), for outputs of different units in one functional output."""

import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.cli.main import main
from gpmsa.model.transforms import Standardizer

S = np.linspace(0.0, 1.0, 10)
THETA = 0.6


def simulate(x, t):
    """10 elements in metres (scale 1e-3), then 10 in newtons (scale 1e3)."""
    x, t = np.atleast_1d(x)[:, None], np.atleast_1d(t)[:, None]
    a = 1e-3 * (np.sin(3 * x + 2 * S) * t + x * t * S**2)
    b = 1e3 * (np.cos(2 * x * (S + 0.3)) + 0.5 * t * x * S)
    return np.hstack([a, b])


def data(y_scale: str) -> gpmsa.SimData:
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=40), rng.uniform(size=40)
    return gpmsa.SimData(
        x=x, t=t, y=simulate(x, t), x_names=["x"], t_names=["t"], y_scale=y_scale,
        y_units=["m"] * 10 + ["N"] * 10,
    )  # fmt: skip


@pytest.fixture(scope="module")
def emus():
    return {k: gpmsa.fit(data(k), n_iter=150, seed=0) for k in ("scalar", "columnwise")}


@pytest.fixture(scope="module")
def obs():
    rng = np.random.default_rng(1)
    x = np.linspace(0.15, 0.85, 4)
    noise = np.r_[np.full(10, 1e-5), np.full(10, 10.0)]  # 1 % of each block's scale
    return x[:, None], simulate(x, THETA) + noise * rng.standard_normal((4, 20))


def block_errors(emu) -> tuple[float, float]:
    """Held-out rms error of each block relative to its spread."""
    rng = np.random.default_rng(2)
    x, t = rng.uniform(0.1, 0.9, 20), rng.uniform(0.1, 0.9, 20)
    y = simulate(x, t)
    err = np.sqrt(np.mean((emu.predict_mean(x[:, None], t[:, None]) - y) ** 2, axis=0))
    err = err / y.std(axis=0)
    return float(err[:10].mean()), float(err[10:].mean())


def test_columnwise_scaling_emulates_the_small_block(emus):
    small_scalar, big_scalar = block_errors(emus["scalar"])
    small, big = block_errors(emus["columnwise"])
    assert small_scalar > 0.5  # one sd over all: the newtons fill the PCA (measured 0.89)
    assert small < 0.05 and big < 0.05  # measured 0.010 and 0.023
    assert big_scalar < 0.2  # measured 0.09
    std = emus["columnwise"].standardizer
    assert std.columnwise and std.y_sd.shape == (20,)
    np.testing.assert_allclose(std.y_sd, data("columnwise").y.std(axis=0, ddof=1), rtol=1e-12)


def test_calibration_recovers_theta_from_each_block(emus, obs):
    x_obs, y_obs = obs
    emu = emus["columnwise"]
    post = gpmsa.Calibrator(emu).update(x_obs, y_obs)
    assert abs(post.mean("t") - THETA) < 3 * post.sd("t") and post.sd("t") < 0.01
    mcmc = gpmsa.calibrate(emu, x_obs=x_obs, y_obs=y_obs, n_samples=300, n_burn=100, seed=1)
    assert abs(mcmc.mean("t") - THETA) < 0.02
    grid = np.arange(10.0)  # the metres alone, on their own index, with their precisions
    small = gpmsa.ObsData(x=x_obs, y=y_obs[:, :10], index=grid, precision=[np.full(10, 1e10)] * 4)
    post = gpmsa.Calibrator(emu).update(small)
    assert abs(post.mean("t") - THETA) < 0.02 and post.sd("t") < 0.01  # measured 0.596 +- 0.004
    scalar = gpmsa.Calibrator(emus["scalar"]).update(small)
    assert scalar.sd("t") > 5 * post.sd("t")  # one sd: the metres barely reach the basis


def test_predictions_are_native_per_element(emus, obs):
    emu = emus["columnwise"]
    x_obs, y_obs = obs
    mean, var = emu.predict(x_obs, np.full((4, 1), THETA))
    draws = gpmsa.emulator_prediction(emu, x_obs, [[THETA]], draws=False, seed=0)
    np.testing.assert_allclose(draws.mean(), mean, rtol=1e-9)
    np.testing.assert_allclose(draws.var(), var, rtol=1e-9)
    data_obs = gpmsa.ObsData(x=x_obs, y=y_obs)
    post = gpmsa.Calibrator(emu).update(x_obs, y_obs)
    full = gpmsa.full_prediction(emu, data_obs, x_obs, posterior=post, n_draws=20, seed=0)
    truth = simulate(x_obs[:, 0], THETA)
    rel = np.abs(full.mean("eta") - truth) / data("columnwise").y.std(axis=0)
    assert rel.max() < 0.1
    assert np.all(np.sqrt(full.var("y")[:, :10]) < 1e-4)  # metres: not the newtons' noise
    cal = gpmsa.predictive.calibrated_predict(emu, post, x_obs, noise=True)
    assert np.all(np.sqrt(cal.var[:, :10]) < 1e-4) and np.all(np.sqrt(cal.var[:, 10:]) > 1.0)
    cv = gpmsa.cross_validate(emu, draws=False)
    assert np.median(np.abs(cv.mean - cv.y)[:, :10] / np.sqrt(cv.var[:, :10])) < 3
    sens = gpmsa.sensitivity(emu, draws=False, main_effect_grid=5)
    metres = sens.main_effect[0, :, :10]  # (grid, element, input), native
    assert np.abs(metres).max() < 1e-2 and np.ptp(metres, axis=0).max() > 1e-4


def test_columnwise_file_round_trips_and_is_checked(emus, tmp_path, capsys):
    emu = emus["columnwise"]
    back = gpmsa.load(emu.save(tmp_path / "cw.gpmsa"))
    assert back.model_sha256 == emu.model_sha256
    np.testing.assert_array_equal(back.standardizer.y_sd, emu.standardizer.y_sd)
    x, t = [[0.3]], [[0.4]]
    np.testing.assert_array_equal(back.predict(x, t)[1], emu.predict(x, t)[1])
    main(["info", str(tmp_path / "cw.gpmsa")])
    assert "output scale:    columnwise" in capsys.readouterr().out
    manifest, arrays = emu.to_record()
    bad = dict(arrays, y_sd=arrays["y_sd"] * np.r_[1.01, np.ones(19)])
    with pytest.raises(gpmsa.EmulatorFileError, match=r"arrays/y_sd: \[0\] = .*column 0"):
        gpmsa.Emulator.from_record(manifest, bad)
    with pytest.raises(gpmsa.EmulatorFileError, match=r"arrays/y_sd: has shape \[5\]"):
        gpmsa.Emulator.from_record(manifest, dict(arrays, y_sd=arrays["y_sd"][:5]))
    scalar = emus["scalar"].to_record()[1]  # one sd beside columnwise weights: refused
    with pytest.raises(gpmsa.EmulatorFileError, match=r"arrays/w: differs from the projection"):
        gpmsa.Emulator.from_record(manifest, dict(arrays, y_sd=scalar["y_sd"]))


def test_default_and_scalar_output_unchanged():
    sim = data("scalar")
    assert gpmsa.SimData(x=sim.x, t=sim.t, y=sim.y).y_scale == "scalar"
    assert isinstance(Standardizer.from_sim(sim).y_sd, float)
    rng = np.random.default_rng(3)
    x, t = rng.uniform(size=12), rng.uniform(size=12)
    prm = {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [1e3], "lamWOs": [1e3]}
    one = [gpmsa.Emulator.from_params(gpmsa.SimData(x=x, t=t, y=x + t, y_scale=k), prm)
           for k in ("scalar", "columnwise")]  # fmt: skip
    assert one[0].model_sha256 == one[1].model_sha256  # one column: its sd is the one sd


def test_standardizer_on_another_grid():
    sim = data("columnwise")
    std = Standardizer.from_sim(sim)
    g = np.array([0.5, 3.0, 12.0])
    sd = np.interp(g, sim.grid, std.y_sd)
    y = np.array([1e-3, 2e-3, 500.0])
    np.testing.assert_allclose(std.y_to_std(y, g), (y - std.mean_on(g)) / sd)
    np.testing.assert_allclose(std.y_from_std(std.y_to_std(y, g), g), y)
    np.testing.assert_allclose(std.var_from_std(np.ones(3), g), sd**2)
    lam = np.diag([1e8, 1e8, 1e-2])
    np.testing.assert_allclose(std.precision_to_std(lam, g), np.diag(sd) @ lam @ np.diag(sd))


def test_bad_y_scale_is_refused():
    sim = data("scalar")
    with pytest.raises(gpmsa.GPMSAError, match="y_scale must be one of"):
        gpmsa.SimData(x=sim.x, t=sim.t, y=sim.y, y_scale="column")
    y = sim.y.copy()
    y[:, 3] = 2.5
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        gpmsa.SimData(x=sim.x, t=sim.t, y=y)  # one sd over all: a constant element is fine
    with pytest.raises(gpmsa.GPMSAError, match="y column 'y3' is constant"):
        gpmsa.SimData(x=sim.x, t=sim.t, y=y, y_scale="columnwise")


def test_plots_take_each_elements_scale(emus, obs):
    emu = emus["columnwise"]
    fig = gpmsa.plots.pc_basis(emu, max_pc=1)
    np.testing.assert_allclose(
        fig.axes[0].lines[0].get_ydata(), emu.standardizer.y_sd * emu.K[:, 0]
    )
    fig = gpmsa.plots.obs_projection(emu, gpmsa.ObsData(x=obs[0], y=obs[1]), max_pc=1)
    runs = fig.axes[-1].lines[0].get_ydata()  # what the basis misses of run 0, native
    assert np.abs(runs[:10]).max() < 1e-4  # metres
