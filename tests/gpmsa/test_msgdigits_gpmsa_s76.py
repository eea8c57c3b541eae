"""Messages that compare a value with a bound or range give the value with the digits that tell
it from the bound (``gpmsa.errors.numbers_text``): a value just past the bound never reads as
the bound itself.

Before: each printed a fixed 3 or 6 (12) significant digits, so 1 + 1e-9 against (0, 1) read
"1 lies outside (0, 1)", and two experiments' reach 1 and 1 + 1e-9 read "1" and "1"."""

import re
from types import SimpleNamespace

import numpy as np
import pytest
from _calib_cases import categorical_emulator, one_t_emulator

from gpmsa import DomainWarning, GPMSAError, SimData
from gpmsa.calibration import calibrator
from gpmsa.calibration.calibrate import _theta_options
from gpmsa.calibration.observations import Fit, _observations, warn_if_outside
from gpmsa.cli import calibrate as cli_calibrate
from gpmsa.model import fixed_elements
from gpmsa.model.basis import given_basis
from gpmsa.model.data import RANGE_COVER_MIN
from gpmsa.model.priors import GammaPrior, Priors
from gpmsa.model.problem import MAX_STD_OBS, _check_discrepancy_scales, check_x_obs

NEAR = 1 + 1e-9


def _message(fn, *args) -> str:
    with pytest.raises(GPMSAError) as info:
        fn(*args)
    return str(info.value)


@pytest.mark.parametrize(
    ("name", "index", "value", "says"),
    [
        ("theta", (0,), NEAR, "= 1.000000001 lies outside its prior's bounds (0, 1) (unit scale)"),
        ("lamWOs", (0,), 1e5 * NEAR, "= 100000.0001 lies outside its prior's bounds (60, 100000)"),
        ("lamWOs", (0,), 60 * (1 - 1e-9), "= 59.99999994 lies outside its prior's bounds (60, "),
    ],
)
def test_a_held_element_just_past_its_prior_bound_is_told_from_it(name, index, value, says):
    assert says in _message(fixed_elements.check_values, name, {index: value}, Priors())


def test_a_held_element_off_a_level_by_a_hair_is_told_from_it():
    levels = [np.array([0.0, 0.5, 1.0])]
    msg = _message(fixed_elements.check_values, "theta", {(0,): 0.5 + 1e-9}, Priors(), levels)
    assert "= 0.500000001 lies outside its levels [0.0, 0.5, 1.0]" in msg


def test_ordinary_held_element_messages_read_as_before():
    msg = _message(fixed_elements.check_values, "lamWOs", {(0,): 1e6}, Priors())
    assert "lamWOs[0] = 1e+06 lies outside its prior's bounds (60, 100000) (zero" in msg
    msg = _message(fixed_elements.check_values, "theta", {(0,): 1.5}, Priors())
    assert "theta[0] = 1.5 lies outside its prior's bounds (0, 1) (unit scale) (zero" in msg


def test_two_reaches_that_differ_read_different():
    msg = _message(_check_discrepancy_scales, "linear", [np.array([0.0, 1.0]), np.array([NEAR])])
    assert "(experiment 0: 1, experiment 1: 1.000000001)" in msg
    msg = _message(_check_discrepancy_scales, "linear", [np.array([0.0, 1.0]), np.array([2.0])])
    assert "(experiment 0: 1, experiment 1: 2)" in msg  # as before


def test_x_obs_just_past_the_margin_reads_past_it():
    msg = _message(check_x_obs, np.array([[0.5], [1.1 + 1e-9]]), ("v",))
    assert "x_obs column v reaches 0.5..1.100000001 on the unit scale" in msg
    assert "allowed [-0.1, 1.1]" in msg
    msg = _message(check_x_obs, np.array([[0.5], [1.3]]), ("v",))
    assert "x_obs column v reaches 0.5..1.3 on the unit scale" in msg  # as before


def test_y_obs_just_beyond_max_std_obs_reads_beyond_it():
    obs = SimpleNamespace(z=np.array([MAX_STD_OBS * (1 + 1e-6)]))
    msg = _message(_observations, None, obs, None, ("", ""), None, ((), (), ()))
    assert re.search(r"y_obs lies 1000001 standard deviations .* allowed at most 1e\+06", msg)
    obs = SimpleNamespace(z=np.array([1.3e199]))
    assert "y_obs lies 1.3e+199 standard" in _message(
        _observations, None, obs, None, ("", ""), None, ((), (), ())
    )


def test_outside_sds_just_past_the_limit_reads_past_it():
    with pytest.warns(UserWarning) as caught:
        warn_if_outside(Fit(5.0 * (1 + 1e-6), 0.0))
        warn_if_outside(Fit(7.25, 0.0))
    first, second = (str(w.message) for w in caught)
    assert "y_obs lies 5.000005 predictive sds from the nearest emulator" in first
    assert "(more than 5)" in first
    assert "y_obs lies 7.25 predictive sds from the nearest emulator" in second  # as before


def test_a_categorical_start_off_a_level_by_a_hair_is_told_from_it():
    emu = categorical_emulator()
    msg = _message(_theta_options, emu, None, [1 + 2e-9])
    assert re.search(r"training levels \[.*\], got 1\.000000002$", msg)
    assert re.search(
        r"training levels \[.*\], got 1\.5$", _message(_theta_options, emu, None, [1.5])
    )


def test_cli_fixed_just_outside_the_design_range_reads_outside_it():
    emu = one_t_emulator()[0]
    hi = float(emu.standardizer.t_max[0])
    value = float(np.nextafter(hi, np.inf))
    msg = _message(cli_calibrate._check_held, emu, ("t",), "t", value)
    shown, rng = re.search(r"--fixed t=(\S+) cannot be held: .* open range \((.*)\)$", msg).groups()
    assert float(shown) == value and float(rng.split(", ")[1]) == hi
    assert shown != rng.split(", ")[1]
    msg = _message(cli_calibrate._check_held, emu, ("t",), "t", 9.0)
    assert msg == "--fixed t=9 cannot be held: give a value inside the design's open range " + (
        f"({float(emu.standardizer.t_min[0]):.12g}, {hi:.12g})"
    )


def test_cli_fixed_lamos_just_past_its_prior_bound_reads_past_it():
    emu = SimpleNamespace(priors=Priors(lamOs=GammaPrior(1.0, 1e-3, 0.0, 1e4)))
    msg = _message(cli_calibrate._check_held, emu, ("t",), "lamOs", 1e4 * NEAR)
    assert msg == ("--fixed lamOs=10000.00001 cannot be held: give a value inside its prior's "
                   "bounds (0, 10000)")  # fmt: skip
    msg = _message(cli_calibrate._check_held, emu, ("t",), "lamOs", 1e4 + 1e-9)
    assert msg.startswith("--fixed lamOs=10000.000000001 cannot be held")  # (.12g: "10000")
    msg = _message(cli_calibrate._check_held, one_t_emulator()[0], ("t",), "lamOs", -1.0)
    assert msg == (
        "--fixed lamOs=-1 cannot be held: give a value inside its prior's bounds (0, inf)"
    )  # fmt: skip (as before)


def test_a_basis_just_past_the_orthogonality_tolerance_reads_past_it():
    K = np.array([[1.0, 1.001e-8], [0.0, 1.0], [0.0, 0.0]])
    msg = _message(given_basis, K, 3)
    assert "diagonal 1.001e-08 of the largest diagonal element, tolerance 1e-08)" in msg
    msg = _message(given_basis, np.array([[1.0, 0.5], [0.0, 1.0], [0.0, 0.0]]), 3)
    assert "diagonal 0.4 of the largest diagonal element, tolerance 1e-08)" in msg  # as before


def test_a_design_just_under_the_range_cover_reads_under_it():
    rng = np.random.default_rng(3)
    x, t = rng.uniform(size=(20, 1)), rng.uniform(200.0, 600.0, size=(20, 1))
    lo, hi = float(t.min()), float(t.max())
    for cover, says in ((RANGE_COVER_MIN * (1 - 1e-6), "], 0.0999999 of its t_range ["),
                        (0.05, "], 0.05 of its t_range [")):  # fmt: skip
        t_range = {"t0": (lo, lo + (hi - lo) / cover)}
        with pytest.warns(DomainWarning) as caught:
            SimData(x=x, t=t, y=x[:, 0] + t[:, 0], t_range=t_range)
        assert says in str(caught[0].message) and "(less than 0.1)" in str(caught[0].message)


UNDER = "node spacings (fewer than"


@pytest.mark.parametrize(
    ("warn", "args", "says"),
    [
        (calibrator._warn_if_unresolved, ((1.4999,), ("t",), 30), f"spans 1.4999 {UNDER} 1.5)"),
        (calibrator._warn_if_level_unresolved, ((1.4999, 9.0), ("t", "k"), 30),
         f"spans 1.4999 {UNDER} 1.5)"),
        (calibrator._warn_if_ridge, ((0.4999, 9.0), ("t", "k"), 30), f"spans 0.4999 {UNDER} 0.5)"),
        (calibrator._warn_if_unresolved, ((1.2,), ("t",), 30), f"spans 1.2 {UNDER} 1.5)"),
    ],
)  # fmt: skip
def test_a_width_just_under_the_grid_limit_reads_under_it(warn, args, says):
    with pytest.warns(UserWarning) as caught:
        warn(*args)
    assert says in str(caught[0].message)


def test_a_width_just_under_the_grid_limit_at_float_reads_under_it():
    marginal = SimpleNamespace(density=np.array([0.0, 1.0, 0.0]), nodes=np.array([0.0, 1.0, 2.0]))
    emu = SimpleNamespace(t_names=["t"], t_units=[""])
    with pytest.warns(UserWarning, match=r"spanning 1\.4999 node spacings \(fewer than 1\.5\)"):
        calibrator._warn_at_float(1.4999, marginal, emu)


def test_a_prior_just_narrower_than_the_grid_reads_narrower(monkeypatch):
    monkeypatch.setattr(calibrator, "narrowest_sd", lambda table, n_grid, q: 0.2799)
    with pytest.warns(UserWarning, match=r"spans 0\.2799 node spacings \(fewer than 0\.28\)"):
        calibrator._warn_if_narrow_prior(np.zeros(3), 3, 1)
    monkeypatch.setattr(calibrator, "narrowest_sd", lambda table, n_grid, q: 0.123)
    with pytest.warns(UserWarning, match=r"spans 0\.12 node spacings \(fewer than 0\.28\)"):
        calibrator._warn_if_narrow_prior(np.zeros(3), 3, 1)  # as before
