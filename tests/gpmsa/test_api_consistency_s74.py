"""Session 74's walkthrough of the API: three inconsistencies a new user met.

- ``Calibrator.update(..., extrapolate=True)`` was a TypeError: the option lived on the
  constructor only, so an online calibration whose x_obs moved outside the design needed a new
  Calibrator. ``update`` (and ``log_likelihood_grid``) now take it per call, None meaning the
  constructor's setting, under the library's rule (within 10 % of a column's width a warning,
  beyond a GPMSAError unless True).
- ``Emulator.theta_summary`` took no ``level=`` and had only the keys "q2.5", "q50", "q97.5",
  where ``Posterior.summary(level)`` names its interval's ends by their percentages and has
  "median", "n_draws", ...: it now takes the same ``level=`` and adds ``Posterior.summary``'s
  keys, the old ones kept as they were.
- A categorical theta's codes were floats in ``Posterior.info["levels"]`` ([0.0, 1.0, 2.0])
  and ints in ``emu.categorical`` and ``info["level_offsets"]`` ([0, 1, 2]): now ints
  everywhere, the codes as the design gives them.
"""

import warnings

import numpy as np
import pytest
from _calib_cases import categorical_emulator, road_emulator, road_obs

import gpmsa
from gpmsa.calibration.observations import theta_levels_native

# --- Calibrator.update(extrapolate=) -------------------------------------------------------------


@pytest.fixture(scope="module")
def road():
    return road_emulator()


def _far_x(emu) -> list[list[float]]:
    """An x_obs 20 % of v's width above its domain (beyond the 10 % margin)."""
    lo, hi = emu.domain["v"]
    return [[hi + 0.2 * (hi - lo)]]


def test_update_takes_extrapolate_per_call(road):
    _, yo = road_obs()
    far = _far_x(road)
    cal = gpmsa.Calibrator(road, seed=0)
    with pytest.raises(gpmsa.GPMSAError, match="extrapolate=True"):
        cal.update(far, yo)  # the constructor's setting (False): refused
    with pytest.warns(gpmsa.ExtrapolationWarning, match="x_obs v="):
        post = cal.update(far, yo, extrapolate=True)
    with pytest.warns(gpmsa.ExtrapolationWarning):
        ref = gpmsa.Calibrator(road, seed=0, extrapolate=True).update(far, yo, seed=1)
    with pytest.warns(gpmsa.ExtrapolationWarning):
        again = cal.update(far, yo, extrapolate=True, seed=1)
    assert again.mean("GD") == ref.mean("GD") and again.sd("GD") == ref.sd("GD")
    assert np.isfinite(post.mean("GD"))
    assert cal.extrapolate is False  # the constructor's setting is not changed by a call


def test_update_extrapolate_false_overrides_the_constructor(road):
    _, yo = road_obs()
    cal = gpmsa.Calibrator(road, extrapolate=True)
    with pytest.raises(gpmsa.GPMSAError, match="extrapolate=True"):
        cal.update(_far_x(road), yo, extrapolate=False)
    with pytest.warns(gpmsa.ExtrapolationWarning):
        cal.update(_far_x(road), yo)  # None: the constructor's True


def test_update_extrapolate_within_the_margin_warns_either_way(road):
    _, yo = road_obs()
    lo, hi = road.domain["v"]
    near = [[hi + 0.05 * (hi - lo)]]
    cal = gpmsa.Calibrator(road)
    for flag in (None, False, True):
        with pytest.warns(gpmsa.ExtrapolationWarning):
            cal.update(near, yo, extrapolate=flag)


def test_log_likelihood_grid_takes_extrapolate(road):
    _, yo = road_obs()
    cal = gpmsa.Calibrator(road)
    with pytest.raises(gpmsa.GPMSAError, match="extrapolate=True"):
        cal.log_likelihood_grid(_far_x(road), yo)
    with pytest.warns(gpmsa.ExtrapolationWarning):
        _, ll = cal.log_likelihood_grid(_far_x(road), yo, extrapolate=True)
    assert np.all(np.isfinite(ll))


def test_update_extrapolate_on_the_mcmc_path(road):
    _, yo = road_obs()
    cal = gpmsa.Calibrator(road, method="mcmc", seed=0,
                           mcmc_options={"n_samples": 200, "n_burn": 50})  # fmt: skip
    with pytest.raises(gpmsa.GPMSAError, match="extrapolate=True"):
        cal.update(_far_x(road), yo)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        post = cal.update(_far_x(road), yo, extrapolate=True)
    assert post.samples["GD"].size == 150  # n_samples - n_burn


@pytest.mark.parametrize("bad", ["yes", 1, 0.0])
def test_update_extrapolate_must_be_a_flag(road, bad):
    with pytest.raises(gpmsa.GPMSAError, match="extrapolate must be True or False"):
        gpmsa.Calibrator(road).update(*road_obs(), extrapolate=bad)


# --- Emulator.theta_summary(level=) --------------------------------------------------------------


@pytest.fixture(scope="module")
def joint():
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(25, 1)), rng.uniform(size=(25, 1))
    data = gpmsa.SimData(x=x, t=t, y=x + t, x_names=["x"], t_names=["t"])
    obs = gpmsa.ObsData(x=[[0.2], [0.8]], y=[[0.5], [1.1]])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gpmsa.fit(data, obs, n_iter=60, tune=False, seed=0, n_chains=2)


def test_theta_summary_keeps_its_old_keys_and_values(joint):
    col = np.asarray(joint.calibration["theta_native"])[:, 0]
    q = np.quantile(col, [0.025, 0.5, 0.975])
    old = {"mean": float(col.mean()), "sd": float(col.std(ddof=1)), "q2.5": float(q[0]),
           "q50": float(q[1]), "q97.5": float(q[2])}  # fmt: skip
    for s in (joint.theta_summary(), joint.theta_summary(level=0.9)):
        assert {k: s["t"][k] for k in old} == old  # bit for bit, at any level


def test_theta_summary_has_posterior_summarys_keys(joint):
    post = gpmsa.calibration_posterior(joint)
    for level in (0.9, 0.5, 0.99):
        new = joint.theta_summary(level=level)["t"]
        ref = post.summary(level)["t"]
        lo, hi = gpmsa.calibration.posterior.quantile_keys(level)
        for k in (lo, "median", hi, "n_draws"):
            assert new[k] == ref[k], k
    default = joint.theta_summary()["t"]  # level 0.95: its ends are the old keys
    assert default["median"] == default["q50"]
    assert default["q2.5"] == pytest.approx(post.summary(0.95)["t"]["q2.5"], rel=1e-12)
    assert default["n_draws"] == post.samples["t"].size
    assert {"q5", "q95"} <= set(joint.theta_summary(0.9)["t"])


@pytest.mark.parametrize("bad", [0.0, 1.0, 95, "0.9", True])
def test_theta_summary_checks_level_as_posterior_summary(joint, bad):
    with pytest.raises(gpmsa.GPMSAError, match="level must be a number in"):
        joint.theta_summary(level=bad)


# --- categorical codes: one type -----------------------------------------------------------------


def _all_ints(codes: dict) -> bool:
    return all(type(v) is int for lv in codes.values() for v in lv)


def test_info_levels_are_the_designs_integer_codes():
    emu = categorical_emulator()
    assert emu.categorical == {"t0": (0, 1, 2)}
    post = gpmsa.Calibrator(emu, seed=0).update([[0.5]], [[1.5]])
    assert post.info["levels"] == {"t0": [0, 1, 2]} and _all_ints(post.info["levels"])
    assert _all_ints(theta_levels_native(emu))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mc = gpmsa.calibrate(emu, [[0.5]], [[1.5]], n_samples=200, n_burn=50, seed=0)
    assert mc.info["levels"] == {"t0": [0, 1, 2]} and _all_ints(mc.info["levels"])


def test_info_levels_float_records_still_read():
    """A Posterior built by hand (or before session 74) with float codes reads as before."""
    draws = np.array([0.0, 1.0, 1.0, 2.0, 1.0])
    for codes in ([0.0, 1.0, 2.0], [0, 1, 2]):
        post = gpmsa.Posterior({"k": draws}, info={"levels": {"k": codes}})
        assert post.quantile("k", 0.3) == 1.0 and post.summary()["k"]["median"] == 1.0
