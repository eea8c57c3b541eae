"""control's GD filters used directly under a caller's ``np.seterr(all="raise")`` (session 86):
ChangePointFilter (a steep prior, sharp blocks, a move while down, the mixture of filters) and
GDTracker (sharp windows, the walk's far tails) give what numpy's default state gives (their
far masses underflow to 0 as intended) and leave the caller's state as it was; the stream
check takes an infinite time stamp after an infinite previous one without numpy's complaint."""

import numpy as np
import pytest

import control
from control.changepoint import mixture_posterior
from control.sensor_checks import stream_breaks


def _sharp(grid: np.ndarray, k: int) -> np.ndarray:
    return -0.5 * ((np.log(grid) - np.log(300.0 + 5.0 * k)) / 0.01) ** 2


def _changepoint(jump_sd: float | None) -> list:
    gd = np.geomspace(50.0, 800.0, 120)
    prior = lambda g: -(((g - 300.0) / 8.0) ** 2)  # noqa: E731 (exp underflows far from 300)
    f = control.ChangePointFilter(gd, control.ChangePointSettings(prior=prior, jump_sd=jump_sd))
    out = [f.prior.copy()]
    for k in range(12):
        f.update(_sharp(gd, k), 2.0)
        f.predict(0.5)
        out += [f.gd_mass, f.prob_change_within(5.0), f.expected_run_m()]
    f.relocate(50.0)
    out += [f.gd_mass, f.mass_by_run([1.0, 10.0]), f.expected_run_m()]
    grid = mixture_posterior([f, f], [1e-300, 1.0]).grids["GD"]
    return [*out, grid.mean(), grid.sd()]


def _tracker(prior: str) -> list:
    t = control.GDTracker((50.0, 800.0), control.TrackerSettings(prior=prior))
    out = []
    for k in range(12):
        t.update(t.grid, _sharp(t.grid, k), power=0.7)
        t.predict(2.0)
        out.append(t.log_mass.copy())
    return [*out, t.posterior().grids["GD"].mean()]


@pytest.mark.parametrize(
    "run",
    [
        lambda: _changepoint(None),
        lambda: _changepoint(0.3),
        lambda: _tracker("uniform"),
        lambda: _tracker("log_uniform"),
    ],
    ids=["changepoint", "changepoint-jump-sd", "tracker", "tracker-log-uniform"],
)
def test_a_filter_used_directly_gives_the_same_numbers_under_raise(run):
    default = run()
    with np.errstate(all="raise"):
        raised = run()
        assert np.geterr() == {"divide": "raise", "over": "raise", "under": "raise",
                               "invalid": "raise"}  # fmt: skip
    assert len(raised) == len(default)
    for a, b in zip(raised, default, strict=True):
        np.testing.assert_array_equal(a, b)


def test_an_infinite_stamp_after_an_infinite_previous_one_is_a_bad_value_quietly():
    t, z = np.array([np.inf, 0.01, 0.02]), np.zeros(3)
    with np.errstate(all="raise"):
        drop, restart, _ = stream_breaks(t, z, z, z, np.inf, 100.0)
    assert drop.tolist() == [True, False, False] and not restart.any()
