"""Mutation testing of control/robot/record.py and control/robot/messages.py (session 91): exact
expectations for a run recorded from a hand-built `ClosedLoopResult` (every estimate field, the
speed interpolated from odometry, stamps, sequence numbers, metadata), `check_can_record` without
each package, and the CDR codecs against hand-built byte layouts (every field of an encoded Imu
and Odometry, the decoders' length and range checks at their edges)."""

from __future__ import annotations

import math
import struct
import sys
from types import SimpleNamespace

import numpy as np
import pytest

from control.closed_loop import ClosedLoopResult
from control.errors import ControlError, MissingExtraError
from control.robot import messages as msgs
from control.robot import record


def _result(sample_time, sample_speed, settings=None) -> ClosedLoopResult:
    """Three BCR updates at 0.25, 0.75 and 1 s over the given odometry samples."""
    k = 3
    n = len(sample_time)
    return ClosedLoopResult(
        time=np.array([0.25, 0.75, 1.0]), position=np.array([0.1, 0.6, 0.9]),
        gd_mean=np.array([np.nan, 310.0, 320.0]), gd_lo=np.array([np.nan, 250.0, 260.0]),
        gd_hi=np.array([np.nan, 350.0, 360.0]), gd_true=np.array([300.0, 301.5, 302.25]),
        status=np.array(["filling", "ok", "ok"]), reason=np.array(["few samples", "", "a"]),
        domain_edge=np.array(["", "upper", "lower"]), prob_change=np.array([np.nan, 0.25, 0.5]),
        command=np.array([0.5, 1.0, 1.5]), mode=np.array(["safety", "performance", "safety"]),
        latency_s=np.zeros(k), sample_time=np.asarray(sample_time, dtype=float),
        sample_position=np.linspace(0.0, 1.0, n), sample_speed=np.asarray(sample_speed, float),
        sample_accel=np.arange(n, dtype=float), metrics={}, settings=settings or {},
    )  # fmt: skip


def _read(path):
    """(metadata {name: dict}, [(topic, log_time, publish_time, sequence, decoded message)])."""
    reader_mod = pytest.importorskip("mcap.reader")
    store = msgs.typestore()
    with open(path, "rb") as f:
        reader = reader_mod.make_reader(f)
        meta = {m.name: dict(m.metadata) for m in reader.iter_metadata()}
    with open(path, "rb") as f:
        reader = reader_mod.make_reader(f)
        out = [
            (ch.topic, m.log_time, m.publish_time, m.sequence,
             store.deserialize_cdr(m.data, sc.name))
            for sc, ch, m in reader.iter_messages(log_time_order=False)
        ]  # fmt: skip
    return meta, out


def _same(a: float, b: float) -> bool:
    return (math.isnan(a) and math.isnan(b)) or a == b


def test_every_field_of_a_recorded_run(tmp_path):
    pytest.importorskip("rosbags")
    pytest.importorskip("mcap")
    settings = {
        "bcr": SimpleNamespace(interval_level=0.8),
        "simplex": SimpleNamespace(gd_max=400.0),
    }
    # odometry speed 0, 1, 3 m/s at 0, 0.5, 1 s: 0.5 at 0.25 s, 2.0 at 0.75 s, 3.0 at 1 s
    res = _result([0.0, 0.5, 1.0], [0.0, 1.0, 3.0], settings)
    start = 7_000_000_001
    path = record.record_run(res, tmp_path / "a" / "run.mcap", start_ns=start)
    assert path == tmp_path / "a" / "run.mcap"
    meta, out = _read(path)
    assert meta == {}  # no model nor noise sd in the settings: no simulation record
    # sequence numbers count the messages in time order; log time == publish time
    assert [m[3] for m in out] == list(range(len(out)))
    assert all(m[1] == m[2] for m in out)
    assert [m[1] for m in out] == sorted(m[1] for m in out)
    est = [(t, m) for topic, t, _, _, m in out if topic == "/bcr/estimate"]
    truth = [(t, m) for topic, t, _, _, m in out if topic == "/sim/gd_true"]
    imu = [(t, m) for topic, t, _, _, m in out if topic == "/imu/data"]
    odom = [(t, m) for topic, t, _, _, m in out if topic == "/odometry/filtered"]
    stamps = [start + 250_000_000, start + 750_000_000, start + 1_000_000_000]
    assert [t for t, _ in est] == stamps and [t for t, _ in truth] == stamps
    assert [m.data for _, m in truth] == [300.0, 301.5, 302.25]
    assert [t for t, _ in imu] == [start, start + 500_000_000, start + 1_000_000_000]
    assert [t for t, _ in odom] == [t for t, _ in imu]
    assert [m.linear_acceleration.z for _, m in imu] == [0.0, 1.0, 2.0]
    assert [m.twist.twist.linear.x for _, m in odom] == [0.0, 1.0, 3.0]
    expect = [
        ("filling", "few samples", "", 0.1, 0.5, np.nan, np.nan, np.nan, np.nan, 0.5, "safety"),
        ("ok", "", "upper", 0.6, 2.0, 310.0, 250.0, 350.0, 0.25, 1.0, "performance"),
        ("ok", "a", "lower", 0.9, 3.0, 320.0, 260.0, 360.0, 0.5, 1.5, "safety"),
    ]
    for (t, m), e in zip(est, expect, strict=True):
        assert m.header.stamp.sec * 1_000_000_000 + m.header.stamp.nanosec == t
        assert (m.status, m.reason, m.domain_edge) == e[:3]
        got = (m.position, m.speed, m.gd_mean, m.gd_lo, m.gd_hi, m.prob_change, m.command_speed)
        assert all(_same(a, b) for a, b in zip(got, e[3:10], strict=True)), got
        assert (m.mode, m.safety) == (e[10], e[10] == "safety")
        assert math.isnan(m.gd_sd) and math.isnan(m.prob_above_gd_max)
        assert (m.interval_level, m.gd_max) == (0.8, 400.0)


def test_a_run_without_odometry_samples_records_no_speed(tmp_path):
    pytest.importorskip("rosbags")
    pytest.importorskip("mcap")
    _, out = _read(record.record_run(_result([], []), tmp_path / "run.mcap"))
    est = [m for topic, _, _, _, m in out if topic == "/bcr/estimate"]
    assert len(est) == 3 and all(math.isnan(m.speed) for m in est)
    assert all(math.isnan(m.interval_level) and math.isnan(m.gd_max) for m in est)
    assert [m.position for m in est] == [0.1, 0.6, 0.9]


@pytest.mark.parametrize(
    ("module", "dist"), [("mcap.writer", "mcap"), ("rosbags.typesys", "rosbags")]
)
def test_check_can_record_names_each_missing_package(monkeypatch, module, dist):
    monkeypatch.setitem(sys.modules, module, None)  # import raises ImportError
    with pytest.raises(MissingExtraError, match=f"optional package '{dist}'"):
        record.check_can_record()


@pytest.mark.parametrize("start_ns", [True, False, -1, msgs.MAX_STAMP_NS + 1, 1.0, "5", None])
def test_record_run_refuses_a_start_that_is_no_ros_stamp(tmp_path, start_ns):
    pytest.importorskip("rosbags")
    pytest.importorskip("mcap")
    with pytest.raises(ControlError, match=r"start_ns must be an integer in \[0, 2\*\*31 s\)"):
        record.record_run(_result([0.0], [1.0]), tmp_path / "run.mcap", start_ns=start_ns)
    assert not (tmp_path / "run.mcap").exists()


@pytest.mark.parametrize("start_ns", [0, np.int64(3), msgs.MAX_STAMP_NS - 1_999_999_999])
def test_record_run_takes_a_start_up_to_the_last_ros_stamp(tmp_path, start_ns):
    pytest.importorskip("rosbags")
    pytest.importorskip("mcap")
    res = _result([0.0], [1.0])
    _, out = _read(record.record_run(res, tmp_path / "run.mcap", start_ns=start_ns))
    assert [t for topic, t, _, _, _ in out if topic == "/imu/data"] == [int(start_ns)]
    assert [t for topic, t, _, _, _ in out if topic == "/bcr/estimate"] == [
        int(start_ns) + 250_000_000,
        int(start_ns) + 750_000_000,
        int(start_ns) + 1_000_000_000,
    ]


# --- messages: the CDR codecs against hand-built byte layouts -----------------------------------

_LE = b"\x00\x01\x00\x00"  # CDR encapsulation: little-endian, no options


def _imu_bytes(sec, nsec, frame: bytes, accel, acc_cov0=0.0) -> bytes:
    """An Imu by hand: header (frame_id with its NUL), padding to 8 (from after the 4-byte
    encapsulation), then 37 float64s."""
    head = _LE + struct.pack("<iII", sec, nsec, len(frame) + 1) + frame + b"\x00"
    head += b"\x00" * (-(len(head) - 4) % 8)
    unknown = (-1.0,) + (0.0,) * 8
    body = (0.0, 0.0, 0.0, 1.0, *unknown, 0.0, 0.0, 0.0, *unknown, *accel, acc_cov0)
    return head + struct.pack("<37d", *body, *(0.0,) * 8)


def _odom_bytes(sec, nsec, frame: bytes, child: bytes, position, velocity) -> bytes:
    head = _LE + struct.pack("<iII", sec, nsec, len(frame) + 1) + frame + b"\x00"
    head += b"\x00" * (-(len(head) - 4) % 4)
    head += struct.pack("<I", len(child) + 1) + child + b"\x00"
    head += b"\x00" * (-(len(head) - 4) % 8)
    body = (*position, 0.0, 0.0, 0.0, 1.0, *(0.0,) * 36, *velocity, 0.0, 0.0, 0.0, *(0.0,) * 36)
    return head + struct.pack("<85d", *body)


def test_encode_imu_is_the_hand_built_layout():
    data = msgs.encode_imu(1_500_000_002, [0.25, -1.5, 9.75], "imu_link")
    # 4 + 12 + 9 ("imu_link" and its NUL) = 25 bytes, padded by 3 to 28; 37 doubles: 324
    assert len(data) == 324
    assert data[:28] == _LE + struct.pack("<iII", 1, 500_000_002, 9) + b"imu_link\x00" + b"\0" * 3
    assert data == _imu_bytes(1, 500_000_002, b"imu_link", (0.25, -1.5, 9.75))
    assert msgs.encode_imu(7, (1, 2, 3)) == _imu_bytes(0, 7, b"imu_link", (1.0, 2.0, 3.0))


def test_encode_odometry_is_the_hand_built_layout():
    data = msgs.encode_odometry(2_000_000_001, [1.5, -2.0, 0.125], [0.5, 0.0, -0.25])
    # "odom": 4 + 12 + 5 = 21, padded by 3 to 24; child length 4 + "base_link" 10: 38, padded
    # by 6 to 44; 85 doubles: 724
    assert len(data) == 724
    head = _LE + struct.pack("<iII", 2, 1, 5) + b"odom\x00" + b"\0" * 3
    assert data[:44] == head + struct.pack("<I", 10) + b"base_link\x00" + b"\0" * 6
    assert data == _odom_bytes(2, 1, b"odom", b"base_link", (1.5, -2.0, 0.125), (0.5, 0.0, -0.25))


def test_stamps_at_the_ends_of_a_ros_time():
    top = msgs.MAX_STAMP_NS
    assert top == 2**31 * 1_000_000_000 - 1
    assert msgs.encode_imu(top, (0, 0, 0))[4:12] == struct.pack("<iI", 2**31 - 1, 999_999_999)
    assert msgs.encode_imu(0, (0, 0, 0))[4:12] == b"\0" * 8
    for bad in (top + 1, -1):
        with pytest.raises(ControlError, match=r"outside a ROS 2 time stamp's range \[0, "):
            msgs.encode_imu(bad, (0, 0, 0))
        with pytest.raises(ControlError, match="outside a ROS 2 time stamp"):
            msgs.encode_odometry(bad, (0, 0, 0), (0, 0, 0))


@pytest.mark.parametrize("n", range(10))
def test_decoders_read_every_frame_id_length(n):
    frame, child = b"f" * n, b"c" * (9 - n)
    raw_imu = _imu_bytes(3, 999_999_999, frame, (0.5, 1.5, -2.5))
    stamp, accel, unknown = msgs.decode_imu([raw_imu])
    assert stamp.tolist() == [3_999_999_999] and accel.tolist() == [[0.5, 1.5, -2.5]]
    assert unknown.tolist() == [False]
    raw_odom = _odom_bytes(3, 5, frame, child, (1.0, 2.0, 3.0), (4.0, 5.0, 6.0))
    stamp, pos, vel = msgs.decode_odometry([raw_odom])
    assert stamp.tolist() == [3_000_000_005]
    assert pos.tolist() == [[1.0, 2.0, 3.0]] and vel.tolist() == [[4.0, 5.0, 6.0]]


def test_decoders_keep_the_order_of_messages_of_several_lengths():
    raws = [_imu_bytes(k, 0, b"i" * k, (k, -k, 0.5 * k), -1.0 if k % 2 else 0.0) for k in range(6)]
    stamp, accel, unknown = msgs.decode_imu(raws)
    assert stamp.tolist() == [k * 1_000_000_000 for k in range(6)]
    assert accel.tolist() == [[k, -k, 0.5 * k] for k in range(6)]
    assert unknown.tolist() == [False, True, False, True, False, True]
    raws = [_odom_bytes(-k, k, b"o" * k, b"b", (k, 0, 0), (0, k, 0)) for k in range(6)]
    stamp, pos, vel = msgs.decode_odometry(raws)
    assert stamp.tolist() == [-k * 1_000_000_000 + k for k in range(6)]  # int32 seconds
    assert pos[:, 0].tolist() == list(range(6)) and vel[:, 1].tolist() == list(range(6))
    empty = msgs.decode_imu([])
    assert [a.shape for a in empty] == [(0,), (0, 3), (0,)]


def test_decoders_refuse_a_nanosecond_field_of_a_whole_second():
    with pytest.raises(msgs.CdrLayoutError, match="nanosec out of range"):
        msgs.decode_imu([_imu_bytes(0, 1_000_000_000, b"imu", (0, 0, 0))])
    with pytest.raises(msgs.CdrLayoutError, match="nanosec out of range"):
        msgs.decode_odometry([_odom_bytes(0, 1_000_000_000, b"o", b"b", (0, 0, 0), (0, 0, 0))])


@pytest.mark.parametrize(
    "change",
    [
        lambda b: b"\x01" + b[1:],  # big-endian CDR
        lambda b: b[:1] + b"\x00" + b[2:],  # big-endian representation id
        lambda b: b[:1] + b"\x03" + b[2:],  # another representation (XCDR2)
        lambda b: b[:15],  # shorter than a header
        lambda b: b + b"\0" * 8,  # a double too many
        lambda b: b[:-8],  # a double too few
    ],
)
def test_decoders_refuse_a_layout_that_is_not_theirs(change):
    with pytest.raises(msgs.CdrLayoutError):
        msgs.decode_imu([change(_imu_bytes(1, 2, b"imu_link", (0, 0, 0)))])
    with pytest.raises(msgs.CdrLayoutError):
        msgs.decode_odometry([change(_odom_bytes(1, 2, b"odom", b"b", (0, 0, 0), (0, 0, 0)))])


@pytest.mark.parametrize("size", [16, 17, 20, 21, 24, 25, 28, 29, 32])
def test_odometry_cut_short_is_a_layout_error(size):
    """A frame_id length that leaves the child_frame_id's length field past the end (or just at
    it) is a layout error, never an IndexError."""
    data = _odom_bytes(1, 2, b"odom", b"base_link", (0, 0, 0), (0, 0, 0))[:size]
    with pytest.raises(msgs.CdrLayoutError, match="length does not match an Odometry"):
        msgs.decode_odometry([data])


def test_stamps_are_checked_against_their_limit_in_integers():
    # session 91: the check summed in float64 (256 ns apart near 2**31 s), so a stamp landing
    # exactly on the largest ROS 2 stamp was refused; the one after it still is
    from control.robot import bags

    top = msgs.MAX_STAMP_NS
    assert bags.stamps_ns("t", [0.0, 1.0], offset_ns=top - 10**9).tolist() == [top - 10**9, top]
    with pytest.raises(ControlError, match=r"^t holds 1\.000000001 s: allowed finite"):
        bags.stamps_ns("t", [1.000000001], offset_ns=top - 10**9)
    # receive times: int64 ns, any below 2**63 (the largest float64 below it too)
    below = float(np.nextafter(2.0**63, 0.0))
    assert bags.stamps_ns("log", [below / 1e9], limit=bags.MAX_LOG_NS).tolist() == [int(below)]
    for t in (9.3e9, -1e-9, float("nan"), -1e300):
        with pytest.raises(ControlError, match=r"^log holds "):
            bags.stamps_ns("log", [t], limit=bags.MAX_LOG_NS)
