"""Bad input to the change-point filter's state, the Simplex law, the sensor checks and the
figures: refused with a ControlError naming the argument (they crashed deep inside numpy or
matplotlib, or gave garbage)."""

import numpy as np
import pytest
from control_doubles import plotted_run_and_track

from control import ChangePointFilter, ControlError, Simplex
from control.changepoint import mixture_posterior
from control.plotting import plot_gd_trace, plot_posterior_grid, plot_speed
from control.sensor_checks import (
    SensorLimits,
    lattice_stretch,
    level_jump,
    quietest_stretch,
    signal_fault,
    timing_fault,
)

GD = np.geomspace(200.0, 600.0, 121)


def test_a_state_of_a_filter_on_another_grid_is_refused_and_the_filter_kept():
    """restore() took a state of another grid silently: gd_mass then had 5 nodes on a 121-node
    grid, and the next update failed in numpy broadcasting."""
    f = ChangePointFilter(GD)
    f.update(np.zeros(GD.size), 1.0)
    before = f.gd_mass
    other = ChangePointFilter(np.geomspace(200.0, 600.0, 5))
    with pytest.raises(ControlError, match=r"state must be one taken by .* \(1, 121\)"):
        f.restore(other.state())
    with pytest.raises(ControlError, match="state must be one taken by"):
        f.restore("abc")  # ValueError: could not convert string to float
    with pytest.raises(ControlError, match="has_data 'yes'"):
        f.restore((*f.state()[:2], "yes"))
    np.testing.assert_array_equal(f.gd_mass, before)
    state = f.state()
    f.update(np.linspace(0.0, 3.0, GD.size), 1.0)
    f.restore(state)  # a state of its own still restores, exactly
    np.testing.assert_array_equal(f.gd_mass, before)


def test_weights_that_are_not_numbers_are_refused():
    f = ChangePointFilter(GD)
    with pytest.raises(ControlError, match="weights must be one finite positive number"):
        mixture_posterior([f, f], ["a", "b"])  # ValueError from numpy


@pytest.mark.parametrize("law", ["linear", "paper", "switch"])
def test_the_law_has_no_speed_for_a_gd_that_is_nan_or_not_a_number(law):
    s = Simplex(law=law)
    for bad in (np.nan, "300", None):  # NaN gave a NaN speed; "300" a TypeError
        with pytest.raises(ControlError, match="gd must be a real number"):
            s.performance_speed(bad)
    assert s.performance_speed(np.float64(250.0)) == s.performance_speed(250) == 2.0


def test_signal_fault_names_a_nan_and_refuses_a_block_that_is_not_1d():
    a = np.random.default_rng(0).standard_normal(125)
    assert signal_fault(a, SensorLimits()) == ""
    bad = a.copy()
    bad[5] = np.nan  # passed every check as healthy
    assert signal_fault(bad, SensorLimits()) == "1 sample(s) with non-finite accel"
    with pytest.raises(ControlError, match=r"accel must be a 1-D block .* \(25, 5\)"):
        signal_fault(a.reshape(25, 5), SensorLimits())  # "truth value ... is ambiguous"


def test_timing_fault_of_stamps_that_do_not_advance_is_a_reason_not_a_crash():
    n = 125
    reason = timing_fault(np.zeros(n), np.zeros(n), np.ones(n), 120.0, SensorLimits())
    assert reason == "time stamps that do not advance: the block's 125 stamps span 0 s"
    t = np.arange(n) / 120.0  # ZeroDivisionError before
    assert timing_fault(t, t, np.ones(n), 120.0, SensorLimits()) == ""


@pytest.mark.parametrize(
    "call, name",
    [
        (lambda a: quietest_stretch(a, 0), "stretch"),  # broadcasting ValueError
        (lambda a: quietest_stretch(a, 1), "stretch"),  # (nan, 0)
        (lambda a: level_jump(a, 1), "min_segment"),  # (inf, ...)
        (lambda a: lattice_stretch(a, 6.0), "stretch"),  # IndexError
    ],
)
def test_stretch_lengths_must_be_integers_of_two_samples_or_more(call, name):
    a = np.random.default_rng(1).standard_normal(125)
    with pytest.raises(ControlError, match=f"{name} must be an integer >= 2"):
        call(a)


def test_one_result_passed_alone_is_refused_with_the_fix():
    run, track = plotted_run_and_track()
    for plot in (plot_gd_trace, plot_speed):  # TypeError: object is not iterable
        with pytest.raises(ControlError, match=r"for one run pass \[result\]"):
            plot(run, track)
    with pytest.raises(ControlError, match="level must lie in"):
        plot_gd_trace([run], track, level=90)  # a legend of "9000% interval"


def test_the_posterior_grid_takes_a_generator_and_refuses_a_malformed_cell():
    cells = [(v, gd, np.full(10, gd)) for v in (1.0, 2.0) for gd in (300.0, 500.0)]
    assert len(plot_posterior_grid(c for c in cells).axes) == 4  # "Number of rows must be ..."
    for bad in ((1.0, np.ones(3)), ("fast", 300.0, np.ones(3)), (np.nan, 300.0, np.ones(3))):
        with pytest.raises(ControlError, match=r"cells\[0\] must be a \(v, true GD, draws\)"):
            plot_posterior_grid([bad])
    with pytest.raises(ControlError, match=r"cells\[0\]: the draws must be"):
        plot_posterior_grid([(1.0, "300", np.ones(3))])  # failed in the title's format
