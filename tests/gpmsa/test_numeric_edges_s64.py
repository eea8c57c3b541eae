"""Numerically awkward data (session 64): outputs at float64's resolution, a rank-deficient
design, and the outside-the-emulator check's false alarms on noisy scalar data and coarse grids.

The simulator is linear, y = x + 2 t, so the calibration posterior is known: with n scalar
observations and lamOs ~ Gamma(a, b) integrated out, p(t | y) ~ (b + SS(t) / 2)^-(a + n / 2)
(standardised units; the emulator's own variance is small here).
"""

import warnings
from functools import cache

import numpy as np
import pytest
from _calib_cases import road_emulator, road_obs

import gpmsa
from gpmsa import GPMSAError, OutsideEmulatorWarning
from gpmsa.calibration.observations import OUTSIDE_SDS


def _design(m=60, q=1, seed=0):
    rng = np.random.default_rng(seed)
    return rng.random((m, 1)), rng.random((m, q))


@cache
def _linear_emulator():
    x, t = _design()
    sim = gpmsa.SimData(x=x, t=t, y=x + 2 * t)
    return gpmsa.fit(sim, n_iter=1000, seed=0)


def _exact(emu, xo, yo):
    """Mean and sd of t's posterior from the simulator itself (lamOs integrated out)."""
    std, prior = emu.standardizer, emu.priors.lamOs
    tg = np.linspace(std.t_min[0], std.t_max[0], 4001)
    u = (yo[:, 0] - std.y_mean[0]) / std.y_sd
    eta = (xo[:, 0][None, :] + 2 * tg[:, None] - std.y_mean[0]) / std.y_sd
    ss = ((u[None, :] - eta) ** 2).sum(axis=1)
    logp = -(prior.a + u.size / 2) * np.log(prior.b + ss / 2)
    p = np.exp(logp - logp.max())
    p /= np.trapezoid(p, tg)
    mean = np.trapezoid(p * tg, tg)
    return mean, np.sqrt(np.trapezoid(p * (tg - mean) ** 2, tg))


# --- outputs at float64's resolution ---------------------------------------------------------
@pytest.mark.parametrize("scale, offset", [(1e-7, 1e9), (1e-14, 1.0)])
def test_output_spread_at_float64_resolution_is_refused(scale, offset):
    """y = 1e9 + 1e-7 f kept 3 distinct values of 30 runs and calibrated silently
    (t 0.26 +- 0.12 / 0.33 +- 0.15 against 0.31 +- 0.02)."""
    x, t = _design(30)
    with pytest.raises(GPMSAError, match=r"y varies by only sd .*float64's resolution.*offset"):
        gpmsa.SimData(x=x, t=t, y=(x + 2 * t) * scale + offset)


@pytest.mark.parametrize("scale, offset", [(1e-12, 0.0), (1e12, 0.0), (1.0, 1e9), (1e-3, 1e9)])
def test_output_scales_and_offsets_that_float64_holds_are_accepted(scale, offset):
    x, t = _design(30)
    sim = gpmsa.SimData(x=x, t=t, y=(x + 2 * t) * scale + offset)
    assert sim.y.shape == (30, 1)


# --- a rank-deficient design ------------------------------------------------------------------
def test_collinear_parameter_columns_are_refused():
    """t1 = 2 t0 + 1: the runs lie on a line of the (t0, t1) box and calibration over the box
    read the emulator's prior mean off it (t0 0.32 +- 0.17 against 0.31 +- 0.02 alone)."""
    x, t = _design(30)
    t2 = np.column_stack([t, 2 * t + 1])
    with pytest.raises(GPMSAError, match=r"design columns a, b are linearly dependent"):
        gpmsa.SimData(x=x, t=t2, y=x + 2 * t, t_names=["a", "b"])
    with pytest.raises(GPMSAError, match=r"design columns v, a are linearly dependent"):
        gpmsa.SimData(x=x, t=3 * x - 1, y=x + 2 * t, x_names=["v"], t_names=["a"])


def test_duplicated_and_spread_designs_are_accepted():
    x, t = _design(30, q=2)
    y = x + t.sum(axis=1, keepdims=True)
    sim = gpmsa.SimData(x=np.vstack([x, x[:5]]), t=np.vstack([t, t[:5]]), y=np.vstack([y, y[:5]]))
    assert sim.m == 35


# --- the outside check on noisy scalar observations ------------------------------------------
@pytest.mark.parametrize("n, noise", [(5, 0.1), (10, 0.1), (30, 0.05)])
def test_noisy_scalar_observations_inside_the_range_do_not_warn(n, noise):
    """Observations of the simulator plus noise (7-13% of the outputs' sd) read 7.6-10.9 sds
    'outside what the emulator has seen, theta falls back towards its prior' (one theta for
    all data against the emulator's sd alone), while the posterior was the exact one, 0.005-0.02
    of the range wide."""
    emu = _linear_emulator()
    rng = np.random.default_rng(5)
    xo = np.linspace(0.05, 0.95, n)[:, None]
    yo = xo + 0.6 + noise * rng.standard_normal((n, 1))
    with warnings.catch_warnings():
        warnings.simplefilter("error", OutsideEmulatorWarning)
        grid = gpmsa.Calibrator(emu).update(xo, yo)
        mc = gpmsa.calibrate(emu, xo, yo, seed=1, n_samples=3000, n_burn=500)
    assert grid.info["outside_sds"] < OUTSIDE_SDS
    assert mc.info["outside_sds"] == pytest.approx(grid.info["outside_sds"], rel=1e-6)
    mean, sd = _exact(emu, xo, yo)  # the emulator's variance (ignored there) widens it a little
    assert grid.sd("t0") == pytest.approx(sd, rel=0.35)
    assert abs(grid.mean("t0") - mean) < grid.sd("t0")  # the emulator's own error
    assert abs(mc.mean("t0") - grid.mean("t0")) < 0.5 * grid.sd("t0")


def test_scalar_observations_beyond_the_range_still_warn():
    emu = _linear_emulator()
    xo = np.linspace(0.05, 0.95, 10)[:, None]
    yo = xo + 0.6
    yo[3] += 5.0  # one datum beyond every theta's output at its x
    with pytest.warns(OutsideEmulatorWarning, match="predictive sds"):
        post = gpmsa.Calibrator(emu).update(xo, yo)
    assert post.info["outside_sds"] > 100
    with pytest.warns(OutsideEmulatorWarning):
        gpmsa.Calibrator(emu).update(xo, yo + 1e3)


def test_single_observation_distance_unchanged():
    """One datum: the smallest over theta of its distance, as before (road case, f = 40)."""
    emu = road_emulator()
    with pytest.warns(OutsideEmulatorWarning):
        post = gpmsa.Calibrator(emu).update(road_obs()[0], [[40.0]])
    assert post.info["outside_sds"] == pytest.approx(35.7747, rel=1e-5)


# --- the outside check on a coarse Calibrator grid -------------------------------------------
@pytest.mark.parametrize("n_grid", [3, 9])
def test_coarse_calibrator_grid_gives_the_default_distance(n_grid):
    """n_grid=3 read an observation at t = 0.3 as 34 sds outside (the nearest node 0.5)."""
    emu = _linear_emulator()
    base = gpmsa.Calibrator(emu).update([[0.5]], [[1.1]])
    with warnings.catch_warnings():
        warnings.simplefilter("error", OutsideEmulatorWarning)
        coarse = gpmsa.Calibrator(emu, n_grid=n_grid).update([[0.5]], [[1.1]])
    assert coarse.info["outside_sds"] == pytest.approx(base.info["outside_sds"], rel=1e-9)


def test_observation_just_beyond_the_range_says_the_posterior_piles_at_the_bound():
    """y_obs 0.1 above the outputs at x = 0.5 (8.8 sds): the posterior piles at t's upper
    bound (mean 0.94, 5% quantile 0.80 of [0.01, 0.995]), which the warning did not say (only
    that theta falls back towards its prior)."""
    emu = _linear_emulator()
    hi = float(emu.standardizer.t_max[0])
    with pytest.warns(OutsideEmulatorWarning, match="piles up at the theta bound") as rec:
        post = gpmsa.Calibrator(emu).update([[0.5]], [[0.5 + 2 * hi + 0.1]])
    assert len(rec) == 1
    assert post.quantile("t0", 0.05) > 0.7 and post.hdi("t0", 0.9)[1] == pytest.approx(hi)
