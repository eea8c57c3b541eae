"""A speed schedule given as a callable that edits the array it is given (``s /= 10`` to change
units, ``t *= 2``): the schedule's own time or position grid was passed, so the edit rewrote the
grid the drive was integrated on: ``simulate`` on a 6 m road with ``speed_of="position"`` drove
to 24 m, and ``schedule_grid`` returned an empty drive (an IndexError) or one of 1973 instead
of 4204 steps. The callable now gets a copy."""

import numpy as np
import pytest

import roadgen
import vehicle
from vehicle.kinematics import schedule_grid


def _speed(x):
    return 1.0 + 0.2 * np.sin(np.asarray(x, dtype=float))


def _doubling(x):
    out = _speed(x)
    x *= 2.0
    return out


def _zeroing(x):
    out = _speed(x)
    x[...] = 0.0
    return out


def _returning_its_input(x):
    x[...] = _speed(x)
    return x


@pytest.mark.parametrize("speed_of", ["time", "position"])
@pytest.mark.parametrize("speed", [_doubling, _zeroing, _returning_its_input])
def test_a_speed_callable_that_edits_its_input_leaves_the_drive_as_given(speed, speed_of):
    s0, v0 = schedule_grid(_speed, speed_of, 0.5, 5.0, 1e-3, 2.0)
    s, v = schedule_grid(speed, speed_of, 0.5, 5.0, 1e-3, 2.0)
    np.testing.assert_array_equal(s, s0)
    np.testing.assert_array_equal(v, v0)


def test_simulate_with_a_speed_callable_that_edits_its_input_stays_on_the_road():
    road = roadgen.iso8608_profile(6.0, 100.0, dx_m=0.01, seed=0)
    model = vehicle.Jackal()
    given = vehicle.simulate(model, road, _speed, rate_hz=120, seed=0, speed_of="position")
    edited = vehicle.simulate(model, road, _doubling, rate_hz=120, seed=0, speed_of="position")
    assert edited.position[-1] <= 6.0
    np.testing.assert_array_equal(edited.position, given.position)
    np.testing.assert_array_equal(edited.t, given.t)
