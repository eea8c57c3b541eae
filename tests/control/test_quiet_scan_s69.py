"""The quiet-signal check's scan (`BCRSettings.quiet_scan`): a sensor gain that drops mid-run
reads quiet in its own blocks only, and the sum over the check's whole memory (16 blocks a
phase) let the blocks from before the drop dilute them: a gain of 0.7 was flagged 1.7-12.3 m
into the fault (session 68's table), driving on GD 500 as on smooth ground meanwhile. The check
now also sums each phase's newest k blocks, for every k, at the same ``plausibility_p``."""

import numpy as np
import pytest

import control
import roadgen
import vehicle
from control import ControlError


def drive(segments, speed, seed):
    """A constant-speed drive over ``segments`` ((length m, GD), ...), noise N(0, 1) (case B)."""
    track = roadgen.track(list(segments), seed=seed)
    return vehicle.simulate(vehicle.Jackal(), track, speed, noise_std=1.0, seed=seed)


def estimates(bcr, trace, accel):
    """Every estimate of ``bcr`` over ``trace`` with the accelerations ``accel``, in 42-sample
    chunks (the BCR's updates)."""
    return [
        bcr.update(trace.t[a : a + 42], trace.position[a : a + 42], accel[a : a + 42],
                   trace.speed[a : a + 42])
        for a in range(0, trace.t.size, 42)
    ]  # fmt: skip


def first_flag_m(steps):
    return next(e.position for e in steps if e.status == "implausible")


def test_a_gain_drop_after_the_memory_filled_is_flagged_before_the_rough_part(new_bcr):
    """A gain of 0.7 from 5 s (7.8 m) on GD 300, GD 500 from 10 m, at 1.5 m/s: flagged at
    9.7 m, on GD 300; the whole memory's sum alone flagged it at 13.4 m, on GD 500."""
    trace = drive([(10.0, 300.0), (14.0, 500.0)], 1.5, seed=5)
    accel = np.where(trace.t >= 5.0, 0.7, 1.0) * trace.accel_front_measured
    steps = estimates(new_bcr("B"), trace, accel)
    assert first_flag_m(steps) < 10.0
    assert not any(e.status == "implausible" for e in steps if e.time < 5.0)
    assert first_flag_m(estimates(new_bcr("B", quiet_scan=False), trace, accel)) > 12.0


def test_a_healthy_sensor_reads_as_without_the_scan(new_bcr):
    trace = drive([(10.0, 250.0), (10.0, 450.0)], 1.5, seed=2)
    accel = trace.accel_front_measured
    plain = estimates(new_bcr("B", quiet_scan=False), trace, accel)
    scanned = estimates(new_bcr("B"), trace, accel)
    assert [e.status for e in scanned] == [e.status for e in plain]
    assert all(e.ok for e in scanned[6:])
    np.testing.assert_array_equal([e.gd_mean for e in scanned], [e.gd_mean for e in plain])


@pytest.mark.parametrize("value", [1, 0.0, None, "True", np.float64(1.0)])
def test_quiet_scan_is_checked(value):
    with pytest.raises(ControlError, match="quiet_scan must be True or False"):
        control.BCRSettings(quiet_scan=value)
    assert control.BCRSettings(quiet_scan=np.bool_(False)).quiet_scan is False
