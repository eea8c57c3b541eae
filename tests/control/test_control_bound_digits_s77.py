"""control's messages tell a value just past its bound, or a value that differs from its
counterpart by more than the check allows, from that bound (gpmsa.errors.numbers_text):
they read "[200, 600] but the domain is [200, 600]" or "0.1 m against 0.1 m" before."""

import re
from types import SimpleNamespace

import numpy as np
import pytest

from control import compat, sensor_checks
from control.errors import ControlError, EmulatorMismatchError
from control.simplex import Simplex
from control.tracker import GDTracker


def test_a_grid_just_inside_the_trackers_domain_reads_apart_from_it() -> None:
    grid = np.geomspace(200.0 * (1 + 1e-8), 600.0, 50)
    with pytest.raises(ControlError) as info:
        GDTracker((200.0, 600.0)).update(grid, np.zeros(grid.size))
    first, low = re.search(r"spans GD \[([^,]+), .*domain is \[([^,]+),", str(info.value)).groups()
    assert first != low and float(first) > float(low)


def test_a_speed_step_just_past_v_max_reads_apart_from_it() -> None:
    with pytest.raises(ControlError) as info:
        Simplex(v_max=np.nextafter(2.0, 0.0), speed_step_mps=2.0)
    assert "[0, v_max] = [0, 1.9999999999999998], got 2.0" in str(info.value)


def test_a_simplex_speed_just_past_the_emulators_domain_reads_apart_from_it() -> None:
    emulator = SimpleNamespace(domain={"v": (0.5, 2.0)}, x_names=["v"])
    with pytest.raises(EmulatorMismatchError) as info:
        compat._check_speeds(emulator, Simplex(v_max=2.00000001))
    assert "v_max = 2.00000001 m/s lies outside the emulator's speed domain [0.5, 2] m/s" in str(
        info.value
    )


def test_a_road_grid_that_differs_reads_apart_from_the_trained_one() -> None:
    track = SimpleNamespace(dx_m=0.1004, settings=None)
    text = compat._track_road_mismatch({"road": {"dx_m": 0.1, "band": None}}, track)
    assert text == "dx_m = 0.1004 m against 0.1 m"


def test_timing_faults_tell_the_span_and_distance_from_the_expected() -> None:
    t = np.arange(121) / 120.0
    speed = np.ones(t.size)
    limits = sensor_checks.SensorLimits(rate_tolerance=1e-6, odometry_tolerance=1e-6)
    text = sensor_checks.timing_fault(t * (1 + 1e-5), t, speed, 120.0, limits)
    span, expected = re.search(r"span (\S+) s .* not the (\S+) s", text).groups()
    assert span != expected and float(span) > float(expected)
    limits = sensor_checks.SensorLimits(odometry_tolerance=1e-6, odometry_slack_m=0.0)
    text = sensor_checks.timing_fault(t, t * (1 + 1e-5), speed, 120.0, limits)
    moved, by_speed = re.search(r"moved (\S+) m .* give (\S+) m", text).groups()
    assert moved != by_speed and float(moved) > float(by_speed)
