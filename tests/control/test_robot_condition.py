"""From recorded messages to the BCR's samples: stamps, resampling, odometry, the CDR codec.

None of these needs the robot extra (numpy and scipy only), except where a test says so.
"""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from control.errors import BagError, ControlError
from control.robot import condition
from control.robot import messages as msgs

RATE = 120.0


def test_stream_check_counts_each_kind_of_stamp_fault():
    t = np.arange(100) / RATE
    t = np.insert(t, 40, t[40])  # a repeated stamp
    t[[60, 61]] = t[[61, 60]]  # two messages swapped: one stamp before an earlier one
    t = np.delete(t, range(80, 85))  # a gap of 5 lost samples
    report = condition.check_stream("/imu", t, np.isfinite(t), "header")
    assert report.rate_hz == pytest.approx(RATE)
    assert (report.repeated, report.backwards, report.gaps) == (1, 1, 1)
    assert report.largest_gap_s == pytest.approx(6 / RATE)
    assert not report.clean
    assert "1 repeated" in report.describe() and "1 gap" in report.describe()
    clean = condition.check_stream("/imu", np.arange(50) / RATE, np.ones(50, bool), "log")
    assert clean.clean and "no stamp faults" in clean.describe()


def test_an_imu_at_the_emulators_rate_passes_unchanged():
    rng = np.random.default_rng(0)
    t = np.arange(600) / RATE + rng.uniform(-1e-4, 1e-4, 600)  # jitter stays with the BCR
    a = rng.normal(size=600)
    t2, a2, info = condition.to_rate(t, a, RATE)
    assert not info.resampled and "none" in info.filter
    assert np.array_equal(t2, t) and np.array_equal(a2, a)


def test_an_imu_slower_than_the_emulator_is_refused_with_both_rates():
    t = np.arange(200) / 50.0
    with pytest.raises(BagError, match=r"50 Hz, slower than the emulator's 120 Hz"):
        condition.to_rate(t, np.zeros(200), RATE)


def test_an_imu_a_hair_slower_names_a_rate_below_the_emulators():
    # 119.98 Hz refused (rate_tolerance 0) must not read "120 Hz, slower than ... 120 Hz"
    t = np.arange(600) / 119.98
    with pytest.raises(BagError, match=r"runs at 119\.98 Hz, slower than the emulator's 120 Hz"):
        condition.to_rate(t, np.zeros(600), RATE, tolerance=0.0)


def _tone(rate_in: float, freq: float, seconds: float = 6.0):
    t = np.arange(int(seconds * rate_in)) / rate_in
    return t, np.sin(2 * np.pi * freq * t)


@pytest.mark.parametrize("rate_in", [200.0, 400.0, 1000.0])
@pytest.mark.parametrize("method", ["sample", "lowpass"])
def test_resampling_keeps_a_low_tone_and_lands_on_a_uniform_grid(rate_in, method):
    t, a = _tone(rate_in, 7.0)
    t2, a2, info = condition.to_rate(t, a + 9.81, RATE, method=method)
    assert info.resampled and info.method == method and info.runs == 1
    assert np.allclose(np.diff(t2), 1 / RATE, rtol=0, atol=1e-12)
    assert t2[0] >= t[0] and t2[-1] <= t[-1]
    assert np.max(np.abs(a2 - 9.81 - np.sin(2 * np.pi * 7.0 * t2))) < 2e-3
    assert f"resample_poly(up={info.up}, down={info.down})" in info.filter


def test_the_two_filters_differ_where_they_should_above_the_output_nyquist():
    # 'sample' gives what a 120 Hz sampler of the signal gives: a 100 Hz tone aliases to 20 Hz
    # at full amplitude (as in the simulator); 'lowpass' removes it.
    t, a = _tone(400.0, 100.0)
    t_s, a_s, _ = condition.to_rate(t, a, RATE, method="sample")
    assert np.max(np.abs(a_s - np.sin(2 * np.pi * 100.0 * t_s))) < 0.02
    _, a_l, _ = condition.to_rate(t, a, RATE, method="lowpass")
    assert np.std(a_l) < 0.01
    # ... and near the top of the band 'sample' keeps the amplitude, 'lowpass' loses some
    t, a = _tone(400.0, 56.0)
    _, a_s, _ = condition.to_rate(t, a, RATE, method="sample")
    _, a_l, _ = condition.to_rate(t, a, RATE, method="lowpass")
    assert np.std(a_s) * np.sqrt(2) == pytest.approx(1.0, abs=0.02)
    assert np.std(a_l) * np.sqrt(2) < 0.9


@pytest.mark.parametrize("rate_in", [24_000.0, 30_000.0, 100_000.0])
def test_an_imu_hundreds_of_times_faster_than_the_emulator_is_resampled(rate_in):
    # the resampling ratio 120 / rate_in was once rounded to 0 / 1 (ZeroDivisionError)
    t, a = _tone(rate_in, 7.0, 2.0)
    for method in condition.METHODS:
        t2, a2, info = condition.to_rate(t, a, RATE, method=method)
        assert info.up >= 1 and info.up / info.down == pytest.approx(RATE / rate_in, rel=1e-3)
        assert t2.size > 150 and np.allclose(np.diff(t2), 1 / RATE, rtol=0, atol=1e-9)
        assert np.max(np.abs(a2 - np.sin(2 * np.pi * 7.0 * t2))) < 2e-3


def test_resampling_turns_stamp_faults_into_faults_the_bcr_reports():
    from control.sensor_checks import stream_breaks

    t, a = _tone(400.0, 7.0, 20.0)
    bad = a.copy()
    t = np.insert(t, 2000, t[2000])  # a duplicate message
    bad = np.insert(bad, 2000, bad[2000])
    bad[4000] = np.nan  # a non-finite value
    keep = np.ones(t.size, bool)
    keep[6000:6040] = False  # 0.1 s lost
    t2, a2, info = condition.to_rate(t[keep], bad[keep], RATE)
    assert info.runs == 4 and info.dropped == 2
    _, _, breaks = stream_breaks(t2, np.zeros(t2.size), a2, np.ones(t2.size), np.nan, RATE)
    reason = breaks.reason(RATE)
    assert "repeated or backwards" in reason and "non-finite accel" in reason and "gap" in reason


def test_highpass_removes_gravity_and_keeps_the_band():
    t, a = _tone(RATE, 5.0, 20.0)
    out = condition.highpass(t, a + 9.81 + 0.05 * t, RATE, 0.5)
    core = slice(240, -240)
    assert np.max(np.abs(out[core] - a[core])) < 0.02
    gap = np.concatenate([t[:1000], t[1010:] + 0.5])  # a gap: filtered run by run
    assert np.all(np.isfinite(condition.highpass(gap, np.ones(gap.size), RATE, 0.5)))


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(0.0, 0.05), min_size=1, max_size=300))
def test_a_straight_drive_from_the_origin_gives_its_distance_exactly(steps):
    x = np.cumsum(steps)
    p = np.zeros((x.size, 3))
    p[:, 0] = x
    assert np.array_equal(condition.path_length(p), x)  # bit for bit, standing included


def test_path_length_follows_turns_and_reversals():
    theta = np.linspace(0, np.pi, 2001)[1:]
    circle = np.stack([np.sin(theta), 1 - np.cos(theta), 0 * theta], axis=1)
    assert condition.path_length(circle)[-1] == pytest.approx(np.pi, rel=1e-6)
    back = np.array([[1.0, 0, 0], [2.0, 0, 0], [1.5, 0, 0], [1.5, 0, 0], [1.0, 0, 0]])
    assert np.allclose(condition.path_length(back), [1.0, 2.0, 2.5, 2.5, 3.0])
    assert np.array_equal(condition.path_length(np.zeros((4, 3))), np.zeros(4))


def test_odometry_interpolates_and_leaves_gaps_empty():
    t_odom = np.array([0.0, 0.1, 0.2, 1.0, 1.1])
    s = np.array([0.0, 0.1, 0.2, 1.0, 1.1])
    pos, spd = condition.odometry_at(np.array([0.05, 0.1, 0.5, 1.05, 2.0]), t_odom, s, s, 0.25)
    assert pos[:2] == pytest.approx([0.05, 0.1]) and pos[3] == pytest.approx(1.05)
    assert np.isnan(pos[2]) and np.isnan(spd[2]) and np.isnan(pos[4])
    assert condition.integrated_speed(np.arange(5.0), np.full(5, 2.0))[-1] == 8.0


# --- the CDR codec ------------------------------------------------------------------------------

frames = st.text(st.characters(codec="ascii", exclude_characters="\x00"), max_size=24)
finite = st.floats(-1e6, 1e6)
stamps = st.integers(0, msgs.MAX_STAMP_NS)


@settings(max_examples=80, deadline=None)
@given(frames, stamps, st.lists(finite, min_size=3, max_size=3))
def test_imu_codec_round_trips(frame, stamp, accel):
    raw = msgs.encode_imu(stamp, accel, frame)
    got_stamp, got_accel, _ = msgs.decode_imu([raw, msgs.encode_imu(1, [0, 0, 1], "imu")])
    assert got_stamp[0] == stamp and got_accel[0].tolist() == accel
    assert got_accel[1].tolist() == [0.0, 0.0, 1.0]


@settings(max_examples=80, deadline=None)
@given(frames, frames, stamps, st.lists(finite, min_size=6, max_size=6))
def test_odometry_codec_round_trips(frame, child, stamp, values):
    raw = msgs.encode_odometry(stamp, values[:3], values[3:], frame, child)
    got = msgs.decode_odometry([raw, msgs.encode_odometry(5, [1, 2, 3], [4, 5, 6], "o", "")])
    assert got[0][0] == stamp and got[1][0].tolist() == values[:3]
    assert got[2][0].tolist() == values[3:] and got[2][1].tolist() == [4.0, 5.0, 6.0]


def test_codec_refuses_what_it_does_not_know():
    with pytest.raises(ControlError, match="ROS 2 time stamp"):
        msgs.encode_imu(msgs.MAX_STAMP_NS + 1, [0, 0, 1])
    with pytest.raises(msgs.CdrLayoutError):
        msgs.decode_imu([b"\x00\x00\x00\x00" + bytes(400)])  # big-endian: the generic path
    with pytest.raises(msgs.CdrLayoutError):
        msgs.decode_odometry([msgs.encode_imu(1, [0, 0, 1])])


@settings(max_examples=40, deadline=None)
@given(frames, frames, st.integers(0, 2**31 - 1), st.lists(finite, min_size=6, max_size=6))
def test_codec_agrees_with_rosbags(frame, child, sec, values):
    pytest.importorskip("rosbags")
    store = msgs.typestore()
    imu = store.deserialize_cdr(msgs.encode_imu(sec * 10**9 + 7, values[:3], frame), msgs.IMU_TYPE)
    assert (imu.header.frame_id, imu.header.stamp.sec, imu.header.stamp.nanosec) == (frame, sec, 7)
    assert [imu.linear_acceleration.x, imu.linear_acceleration.y, imu.linear_acceleration.z] == (
        values[:3]
    )
    odom = store.deserialize_cdr(
        msgs.encode_odometry(sec * 10**9, values[:3], values[3:], frame, child), msgs.ODOMETRY_TYPE
    )
    assert odom.child_frame_id == child
    assert [odom.twist.twist.linear.x, odom.twist.twist.linear.y] == values[3:5]
    raw = bytes(store.serialize_cdr(odom, msgs.ODOMETRY_TYPE))
    assert msgs.decode_odometry([raw])[1][0].tolist() == values[:3]


# --- settings and the optional packages -----------------------------------------------------------


def test_replay_settings_name_the_bad_field():
    from control.robot import ReplaySettings

    for kw, word in (
        ({"imu_axis": "w"}, "imu_axis"),
        ({"imu_sign": 2}, "imu_sign"),
        ({"time_base": "gps"}, "time_base"),
        ({"resample": "cubic"}, "resample"),
        ({"imu_topic": "imu"}, "imu_topic"),
        ({"max_odometry_gap_s": 0}, "max_odometry_gap_s"),
    ):
        with pytest.raises(ControlError, match=word):
            ReplaySettings(**kw)


def test_import_control_needs_no_robot_package():
    code = (
        "import sys\n"
        "for m in ('rosbags', 'mcap'): sys.modules[m] = None\n"
        "import control\n"
        "assert callable(control.replay_bag) and callable(control.record_run)\n"
        "try:\n"
        "    control.robot.bags.read_recording('.')\n"
        "except control.MissingExtraError as exc:\n"
        "    print(exc)\n"
    )
    root = Path(__file__).resolve().parents[2]
    env = {**os.environ, "PYTHONPATH": str(root)}
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=root, env=env
    )
    assert "'rosbags'" in out.stdout and 'pip install -e ".[robot]"' in out.stdout
