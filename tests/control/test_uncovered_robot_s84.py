"""Paths of the robot replay that no test reached before session 84's coverage review:
positions from the integrated speed, no clock-skew check, the checks of an odometry without a
usable message and of topics that do not overlap, a CSV that fails after the output bag (the
bag goes too), and the MCAP reader's walk over records shorter than a message at a chunk's end."""

import math
import struct

import numpy as np
import pytest

pytest.importorskip("rosbags")
pytest.importorskip("mcap")

import control  # noqa: E402
from control import BagError, ControlError, SensorLimits  # noqa: E402
from control.robot import (  # noqa: E402
    ReplaySettings,
    replay_bag,
    storage,
    write_sensor_bag,
)
from control.robot import replay as replay_mod  # noqa: E402

N = 1200  # 10 s at 120 Hz, odometry at 40 Hz


def _drive(tmp_path, name, odom_shift=0.0, odom_nan=False):
    t = 1.0 + np.arange(N) / 120.0
    pos, spd = 0.8 * (t - 1.0), np.full(N, 0.8)
    acc = np.random.default_rng(0).normal(0.0, 2.0, N)
    o = slice(None, None, 3)
    p_odom = np.full(t[o].size, np.nan) if odom_nan else pos[o]
    return write_sensor_bag(tmp_path / name, t, acc, t[o] + odom_shift, p_odom, spd[o])


def test_positions_from_the_integrated_speed_match_the_path_on_a_straight_drive(
    emulator_a, likelihood_a, tmp_path
):
    bag = _drive(tmp_path, "straight")
    by_path = replay_bag(bag, emulator_a, likelihood=likelihood_a)
    by_speed = replay_bag(bag, emulator_a, likelihood=likelihood_a, position="speed")
    assert by_speed.sample_position.size == by_path.sample_position.size > 1000
    assert np.allclose(by_speed.sample_position, by_path.sample_position, rtol=0, atol=1e-9)
    assert by_speed.status.tolist() == by_path.status.tolist()


def test_an_infinite_clock_skew_limit_checks_nothing(emulator_a, likelihood_a, tmp_path):
    bag = _drive(tmp_path, "skew")
    base = replay_bag(bag, emulator_a, likelihood=likelihood_a)
    free = replay_bag(bag, emulator_a, likelihood=likelihood_a, max_clock_skew_s=math.inf)
    assert np.array_equal(free.gd_mean, base.gd_mean, equal_nan=True)
    assert free.status.tolist() == base.status.tolist()


def test_an_odometry_without_a_usable_message_and_topics_apart_in_time_are_named(
    emulator_a, likelihood_a, tmp_path
):
    with pytest.raises(BagError, match=r"odometry topic '/odometry/filtered' has no usable"):
        replay_bag(_drive(tmp_path, "nan", odom_nan=True), emulator_a, likelihood=likelihood_a)
    with pytest.raises(BagError, match=r"'/imu/data' and the odometry topic .* do not overlap"):
        replay_bag(_drive(tmp_path, "apart", odom_shift=100.0), emulator_a, likelihood=likelihood_a)


def test_two_static_levels_that_differ_are_refused_before_reading(emulator_a, tmp_path):
    bcr = control.bcr_settings_for(emulator_a, sensor=SensorLimits(static_mps2=9.80665))
    want = r"static_mps2 = 9.81 and bcr.sensor.static_mps2 = 9.80665 differ: give the static level"
    with pytest.raises(ControlError, match=want):
        replay_bag(tmp_path / "not-read", emulator_a, bcr=bcr, static_mps2=9.81)


@pytest.mark.parametrize(
    ("field", "value", "match"),
    [
        ("rate_tolerance", 0.5, r"rate_tolerance must lie in \[0, 0.5\), got 0.5"),
        ("reorder_periods", math.inf, r"reorder_periods must be >= 0 and finite"),
        ("max_odometry_gap_s", math.inf, r"max_odometry_gap_s must be > 0 and finite"),
    ],
)
def test_replay_settings_name_the_rule_an_odd_value_breaks(field, value, match):
    with pytest.raises(ControlError, match=match):
        ReplaySettings(**{field: value})


def test_a_csv_that_cannot_be_written_takes_the_new_output_bag_with_it(
    emulator_a, likelihood_a, tmp_path, monkeypatch
):
    bag = _drive(tmp_path, "in")

    def full_disk(self, path):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(replay_mod.ReplayResult, "to_csv", full_disk)
    out = tmp_path / "out"
    with pytest.raises(OSError, match="No space left"):
        replay_bag(bag, emulator_a, likelihood=likelihood_a, out_bag=out, csv=tmp_path / "e.csv")
    assert not out.exists()  # written whole or not at all


def _message(channel: int, log_ns: int, data: bytes) -> bytes:
    body = struct.pack("<HIQQ", channel, 0, log_ns, log_ns) + data
    return struct.pack("<BQ", storage.OP_MESSAGE, len(body)) + body


def _walk(records: bytes) -> storage.RawTopics:
    out = storage.RawTopics(log_ns={"/a": []}, data={"/a": []}, schema_index={"/a": []})
    storage._walk(records, {1: ("/a", 0)}, out)
    return out


def test_the_mcap_walk_reads_a_chunk_that_ends_in_records_shorter_than_a_message():
    tail = struct.pack("<BQ", 0x80, 2) + b"xy"  # a user record (opcode >= 0x80), 11 bytes
    records = _message(1, 5, b"abc") + _message(2, 6, b"z") + tail
    out = _walk(records)
    assert out.log_ns["/a"] == [5] and out.data["/a"] == [b"abc"]
    # a short message last (its length below a message's fields) and a record running past the end
    short = struct.pack("<BQ", storage.OP_MESSAGE, 10) + bytes(10)
    with pytest.raises(storage._Damaged, match=r"message record at byte \d+ .* is too short"):
        _walk(_message(1, 5, b"abc") + short)
    with pytest.raises(storage._Damaged, match="its last record runs past its end"):
        _walk(_message(1, 5, b"abc") + struct.pack("<BQ", 0x80, 50) + b"xy")
    # a message that starts within a message's fields of the end cannot be whole: it runs past
    cut = _message(1, 7, b"abcdef")[:20]
    with pytest.raises(storage._Damaged, match="its last record runs past its end"):
        _walk(_message(1, 5, b"abc") + cut)
