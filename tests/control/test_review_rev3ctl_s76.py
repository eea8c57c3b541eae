"""Review (session 76, rev3): the replay's static-level marks leave out every sample the BCR
drops for its other values, not only those in an odometry gap: a finite speed beyond
``MAX_SPEED_MPS`` (a wild odometry velocity) is dropped by the BCR (`stream_breaks`) and
restarts its long span too, so the replay's span must restart there as well."""

import numpy as np
import pytest

import control
from control.robot.condition import static_level_marks
from control.sensor_checks import MAX_SPEED_MPS, SensorLimits
from tests.control.test_msgdigits_control_s76 import _span_faults

G = 9.80665
ON = SensorLimits(static_mps2=G)


def test_samples_the_bcr_drops_for_a_speed_beyond_the_limit_restart_the_replays_span(new_bcr):
    n = 120 * 30
    a = 0.9 * (np.random.default_rng(5).normal(0.0, 2.0, n) + G)
    t = np.arange(n) / 120.0
    pos, spd = 1.5 * t, np.full(n, 1.5)
    spd[1500:1560] = 1.2 * MAX_SPEED_MPS  # a wild odometry velocity, interpolated: finite
    faults = _span_faults(new_bcr("B", sensor=ON), t, a, pos, spd)
    assert faults and not any(1500 <= i < 1560 + 999 for i in faults)  # its span restarted
    from control.robot.replay import _bcr_kept

    marks = static_level_marks(a, ON, 42, 125, t, 120.0, _bcr_kept(pos, spd))
    assert {i for i, why in marks.items() if "last 1000 samples" in why} == faults


def test_the_replay_restarts_its_span_after_a_wild_odometry_speed(tmp_path, likelihood_a):
    pytest.importorskip("rosbags")
    pytest.importorskip("mcap")
    from control.robot import read_recording, write_sensor_bag
    from control.robot.replay import replay_recording

    n = 120 * 25
    t = 1.0 + np.arange(n) / 120.0
    speed = np.where((t > 13.5) & (t < 14.5), 1.2 * MAX_SPEED_MPS, 1.5)  # a wild velocity
    accel = 0.9 * (np.random.default_rng(1).normal(0.0, 2.0, n) + G)
    write_sensor_bag(tmp_path / "b", t, accel, t, 1.5 * (t - 1.0), speed)
    settings = control.ReplaySettings(gravity="highpass", static_mps2=G)
    out = replay_recording(
        read_recording(tmp_path / "b"), likelihood_a.emulator, settings, likelihood=likelihood_a
    )
    span = out.time[[i for i, why in enumerate(out.reason) if "last 1000 samples" in why]]
    # the BCR drops the samples beyond MAX_SPEED_MPS: its span fills again after them
    assert not np.any((span > 12.5) & (span < 13.5 + 999 / 120.0)), span
    assert np.any(span >= 13.5 + 999 / 120.0)
