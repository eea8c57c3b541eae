"""Mutation testing of control/robot/record.py and control/robot/messages.py (session 92, the
sites session 91 left): exact expectations for `record_run`'s default start (the epoch), a start
on the last ROS 2 stamp itself, a folder several levels deep, and an encoded Odometry whose
frame_id needs no padding."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from control.closed_loop import ClosedLoopResult
from control.robot import messages as msgs
from control.robot import record


def _result(time) -> ClosedLoopResult:
    """One BCR update per entry of ``time`` (s), each over one odometry/IMU sample at it."""
    t = np.asarray(time, dtype=float)
    k = t.size
    return ClosedLoopResult(
        time=t, position=np.full(k, 0.5), gd_mean=np.full(k, 300.0), gd_lo=np.full(k, 250.0),
        gd_hi=np.full(k, 350.0), gd_true=np.full(k, 301.0), status=np.array(["ok"] * k),
        reason=np.array([""] * k), domain_edge=np.array([""] * k), prob_change=np.zeros(k),
        command=np.ones(k), mode=np.array(["performance"] * k), latency_s=np.zeros(k),
        sample_time=t.copy(), sample_position=np.zeros(k), sample_speed=np.ones(k),
        sample_accel=np.zeros(k), metrics={}, settings={},
    )  # fmt: skip


def _log_times(path) -> dict[str, list[int]]:
    """{topic: [log_time ns, ...]} of an MCAP file, in file order."""
    reader_mod = pytest.importorskip("mcap.reader")
    out: dict[str, list[int]] = {}
    with open(path, "rb") as f:
        for _, channel, message in reader_mod.make_reader(f).iter_messages(log_time_order=False):
            out.setdefault(channel.topic, []).append(message.log_time)
    return out


def test_record_run_starts_at_the_epoch_by_default(tmp_path):
    pytest.importorskip("rosbags")
    pytest.importorskip("mcap")
    times = _log_times(record.record_run(_result([0.0, 0.25, 1.5]), tmp_path / "run.mcap"))
    expect = [0, 250_000_000, 1_500_000_000]
    assert times == {topic: expect for topic in record.TOPICS.values()}


def test_record_run_takes_the_last_ros_stamp_itself_as_start(tmp_path):
    pytest.importorskip("rosbags")
    pytest.importorskip("mcap")
    top = msgs.MAX_STAMP_NS
    path = record.record_run(_result([0.0]), tmp_path / "run.mcap", start_ns=top)
    assert _log_times(path) == {topic: [top] for topic in record.TOPICS.values()}


def test_record_run_makes_every_missing_folder_of_the_path(tmp_path):
    pytest.importorskip("rosbags")
    pytest.importorskip("mcap")
    target = tmp_path / "a" / "b" / "c" / "run.mcap"
    assert record.record_run(_result([0.0]), target) == target
    assert _log_times(target)["/sim/gd_true"] == [0]


@pytest.mark.parametrize(("child", "pad"), [(b"base", 7), (b"bas", 0)])
def test_odometry_frame_ids_that_need_no_padding(child, pad):
    # "map" and its NUL: 4 + 12 + 4 = 20 bytes, 16 past the encapsulation: no padding before the
    # child's length; "base" and its NUL end at 29 (25 past it), padded by 7 to 36; "bas" at 28
    # (24 past it, a multiple of 8): no padding
    data = msgs.encode_odometry(3, [1.0, 2.0, 3.0], [4.0, 5.0, 6.0], "map", child.decode())
    head = b"\x00\x01\x00\x00" + struct.pack("<iII", 0, 3, 4) + b"map\x00"
    head += struct.pack("<I", len(child) + 1) + child + b"\x00" + b"\x00" * pad
    body = (1.0, 2.0, 3.0, 0.0, 0.0, 0.0, 1.0, *(0.0,) * 36, 4.0, 5.0, 6.0, *(0.0,) * 39)
    assert data == head + struct.pack("<85d", *body)
    stamp, position, velocity = msgs.decode_odometry([data])
    assert stamp.tolist() == [3] and position.tolist() == [[1.0, 2.0, 3.0]]
    assert velocity.tolist() == [[4.0, 5.0, 6.0]]
