"""Coverage of the credible intervals, now `control.metrics.interval_coverage` (it was computed
inline in the closed loop, and no test could tell an inclusive end from an exclusive one: a
mutant `<` for `<=` changed the reported coverage unseen). Both ends count: an HDI can end
exactly at a domain bound that is the truth (parts at GD 200 or 600)."""

import numpy as np
import pytest

import control
import roadgen
from control.errors import ControlError
from control.metrics import interval_coverage

NAN = np.nan


def test_both_ends_of_an_interval_hold_the_truth():
    lo = np.array([200.0, 250.0, 290.0, 300.0, 300.0 + 1e-9])
    hi = np.array([600.0, 300.0, 310.0, 300.0, 400.0])
    truth = np.array([200.0, 300.0, 300.0, 300.0, 300.0])
    mean = np.array([250.0, 280.0, 300.0, 300.0, 350.0])
    assert interval_coverage(mean, lo, hi, truth) == 4 / 5


def test_only_estimates_with_a_finite_mean_count_and_a_nan_end_holds_nothing():
    mean = np.array([300.0, NAN, 300.0, 300.0])
    lo = np.array([250.0, 250.0, NAN, 250.0])
    hi = np.array([350.0, 350.0, NAN, 280.0])
    truth = np.full(4, 300.0)
    assert interval_coverage(mean, lo, hi, truth) == 1 / 3
    assert np.isnan(interval_coverage(np.full(2, NAN), lo[:2], hi[:2], truth[:2]))
    assert np.isnan(interval_coverage(*(np.zeros(0),) * 4))


def test_shapes_are_checked():
    with pytest.raises(ControlError, match=r"1-D of one length, got shapes \(3,\), \(3,\), "):
        interval_coverage(np.zeros(3), np.zeros(3), np.zeros(2), np.zeros(3))
    with pytest.raises(ControlError, match="gd_true"):
        interval_coverage(np.zeros(3), np.zeros(3), np.zeros(3), ["a", "b", "c"])


def test_it_is_public_and_the_loop_reports_it(emulator_a, likelihood_a):
    assert control.interval_coverage is interval_coverage
    track = roadgen.track([(12, 300), (12, 500)], seed=2)
    r = control.run_closed_loop(track, emulator_a, likelihood=likelihood_a, seed=2)
    want = interval_coverage(r.gd_mean, r.gd_lo, r.gd_hi, r.gd_true)
    assert r.metrics.coverage == want and 0 < want <= 1
