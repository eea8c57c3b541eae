"""Metamorphic checks of the replay (session 88): a recording's header stamps moved to 0 s, to
the epoch, to before 0 (a simulator's clock started at -10 s; -1e3 s) or across 0, its receive
times apart from them (negative too, in a sqlite3 bag), in each storage the replay reads (ROS 2
MCAP and sqlite3 folders, a bare ``*.mcap`` file, a ROS 1 ``*.bag``), replay to the same
estimates bit for bit (statuses, reasons, numbers, reports, notes; jitter, a gap and a repeated
stamp in them), their stamps shifted exactly. By design (docs/robot.md): the estimates' ROS 2
bag holds no stamp before 1970, as none after January 2038, and this package's writers take
stamps from 0 s on."""

import dataclasses
import struct

import numpy as np
import pytest
from _robot_cases import ros1_bag

import control
import roadgen

pytest.importorskip("rosbags")
pytest.importorskip("mcap")

from control.errors import ControlError  # noqa: E402
from control.robot import messages as msgs  # noqa: E402
from control.robot.bags import merge_in_time, open_bag_writer, sensor_messages  # noqa: E402

EPOCH_NS = 1_700_000_000_123_456_789
FIELDS = ("time", "position", "speed", "status", "reason", "domain_edge", "gd_mean", "gd_sd",
          "gd_lo", "gd_hi", "prob_above", "prob_change", "command", "mode", "sample_time",
          "sample_position", "sample_speed", "sample_accel", "notes")  # fmt: skip
REPORTS = ("imu", "odometry", "restamping", "resampling")


@pytest.fixture(scope="module")
def signals(emulator_a, likelihood_a):
    """(IMU stamps s, accel, odometry stamps s, position, speed) of a 12 m closed-loop drive
    (1,098 IMU messages, odometry at 40 Hz), its IMU stamps jittered by sd 0.3 ms (re-stamped),
    two messages dropped (a gap) and one stamp repeated."""
    track = roadgen.track([(6, 300), (6, 500)], seed=3)
    run = control.run_closed_loop(track, emulator_a, seed=3, likelihood=likelihood_a)
    t = run.sample_time + np.random.default_rng(1).normal(0.0, 3e-4, run.sample_time.size)
    t[700] = t[699]
    keep = np.ones(t.size, dtype=bool)
    keep[500:502] = False
    return (t[keep], run.sample_accel[keep], run.sample_time[::3], run.sample_position[::3],
            run.sample_speed[::3])  # fmt: skip


def _moved(data: bytes, by_ns: int) -> bytes:
    """A CDR message whose header stamp (int32 s, uint32 ns at bytes 4-12) is ``by_ns`` later:
    before 1970 for a negative one, as a ROS 2 header holds it (this package's writers refuse
    such stamps)."""
    sec, nsec = struct.unpack_from("<iI", data, 4)
    out = bytearray(data)
    struct.pack_into("<iI", out, 4, *divmod(sec * 10**9 + nsec + by_ns, 10**9))
    return bytes(out)


def _ros2_bag(path, signals, header_ns: int, log_ns: int, storage: str = "mcap", checked=True):
    """A ROS 2 bag of ``signals``, header stamps ``header_ns`` and receive times ``log_ns``
    later; ``checked=False``: rosbags' own writer (no checksums), which takes receive times
    before 1970 into a sqlite3 bag."""
    t_imu, imu, t_odom, odom = sensor_messages(*signals)
    imu, odom = ([_moved(m, header_ns) for m in ms] for ms in (imu, odom))
    store = msgs.typestore()
    if checked:
        opened = open_bag_writer(path, storage)
    else:
        from rosbags.rosbag2 import StoragePlugin, Writer

        opened = Writer(path, version=9, storage_plugin=StoragePlugin.SQLITE3)
    with opened as writer:
        c_imu = writer.add_connection("/imu/data", msgs.IMU_TYPE, typestore=store)
        c_odom = writer.add_connection("/odometry/filtered", msgs.ODOMETRY_TYPE, typestore=store)
        streams = [(c_imu, t_imu + log_ns, imu), (c_odom, t_odom + log_ns, odom)]
        for conn, stamp, data in merge_in_time(streams):
            writer.write(conn, stamp, data)
    return path


def _replay(path, emulator, likelihood, **kw):
    return control.replay_bag(path, emulator, likelihood=likelihood, **kw)


def _assert_same(got, ref, shift_ns: int) -> None:
    for name in FIELDS:
        a, b = getattr(got, name), getattr(ref, name)
        if isinstance(b, np.ndarray) and b.dtype.kind == "f":
            assert np.array_equal(a, b, equal_nan=True), name
        else:
            assert np.asarray(a).tolist() == np.asarray(b).tolist(), name
    for name in REPORTS:
        assert dataclasses.asdict(getattr(got, name)) == dataclasses.asdict(getattr(ref, name))
    assert np.array_equal(got.stamp_ns - ref.stamp_ns, np.full(ref.stamp_ns.size, shift_ns))
    assert got.t0_ns - ref.t0_ns == shift_ns


@pytest.fixture(scope="module")
def reference(signals, emulator_a, likelihood_a, tmp_path_factory):
    """The replay of the recording as written (header stamps and receive times from 8 ms)."""
    path = _ros2_bag(tmp_path_factory.mktemp("ref") / "ref", signals, 0, 0)
    ref = _replay(path, emulator_a, likelihood_a)
    counts = ref.status_counts()
    assert counts["ok"] >= 10 and counts["sensor_fault"] >= 1, counts
    assert "re-stamped" in ref.imu.note and ref.imu.gaps and ref.imu.repeated
    return ref


#: (the first header stamp, the receive times' shift), ns: from 0 s; at the epoch; a
#: simulator's clock from -10 s beside receive times as written; from -1e3 s beside receive
#: times at the epoch; across 0 s
ORIGINS = {
    "from 0 s": (0, 0),
    "epoch": (EPOCH_NS, EPOCH_NS),
    "sim clock from -10 s": (-10 * 10**9, 0),
    "-1e3 s, epoch receive times": (-1000 * 10**9, EPOCH_NS),
    "across 0 s": (-4_500_000_001, 0),
}


def _shift(signals, first_ns: int) -> int:
    """The header stamps' shift, ns, that puts the first IMU stamp at ``first_ns``."""
    return first_ns - int(np.rint(signals[0][0] * 1e9))


@pytest.mark.parametrize("storage", ["mcap", "sqlite3", "bare mcap"])
@pytest.mark.parametrize("origin", list(ORIGINS))
def test_header_stamps_from_any_origin_replay_bit_for_bit(
    signals, reference, emulator_a, likelihood_a, tmp_path, origin, storage
):
    first_ns, log_ns = ORIGINS[origin]
    header_ns = _shift(signals, first_ns)
    path = _ros2_bag(tmp_path / "bag", signals, header_ns, log_ns, storage.split()[-1])
    if storage == "bare mcap":  # the folder's file alone
        path = next(path.glob("*.mcap")).rename(tmp_path / "alone.mcap")
    got = _replay(path, emulator_a, likelihood_a)
    _assert_same(got, reference, header_ns)
    assert got.t0_ns == first_ns
    csv = got.to_csv(tmp_path / "estimates.csv").read_text().splitlines()  # stamps as they are
    assert csv[1].startswith(f"{got.stamp_ns[0]},{float(reference.time[0])!r},")


@pytest.mark.parametrize("header_ns", [0, -1000 * 10**9])
def test_receive_times_before_1970_in_a_sqlite3_bag_replay_bit_for_bit(
    signals, reference, emulator_a, likelihood_a, tmp_path, header_ns
):
    """rosbag2's sqlite3 storage holds int64 receive times (MCAP: uint64): -1e3 s."""
    log_ns = -1000 * 10**9
    path = _ros2_bag(tmp_path / "bag", signals, header_ns, log_ns, "sqlite3", checked=False)
    _assert_same(_replay(path, emulator_a, likelihood_a), reference, header_ns)
    on_log = _replay(path, emulator_a, likelihood_a, time_base="log")
    ref_log = _replay(_ros2_bag(tmp_path / "ref", signals, 0, 0), emulator_a, likelihood_a,
                      time_base="log")  # fmt: skip
    _assert_same(on_log, ref_log, log_ns)


def test_a_ros1_bag_from_0_s_replays_as_one_from_the_epoch(
    signals, emulator_a, likelihood_a, tmp_path
):
    t, accel, t_odom, position, speed = signals
    t_ns = np.rint(t * 1e9).astype(np.int64) - np.rint(t[0] * 1e9).astype(np.int64)
    on_imu = (np.interp(t, t_odom, position), np.interp(t, t_odom, speed))
    early = ros1_bag(tmp_path / "early.bag", t_ns, accel, *on_imu)
    late = ros1_bag(tmp_path / "late.bag", t_ns + EPOCH_NS, accel, *on_imu)
    ref = _replay(early, emulator_a, likelihood_a)
    assert ref.stamp_ns[0] > 0 and ref.status_counts()["ok"] >= 10
    _assert_same(_replay(late, emulator_a, likelihood_a), ref, EPOCH_NS)


def test_estimates_stamped_before_1970_stay_out_of_the_estimates_bag(
    signals, emulator_a, likelihood_a, tmp_path
):
    """By design: a ROS 2 bag's receive times (MCAP's uint64) and this package's header stamps
    start at 1970; the message names the stamp and the remedies."""
    path = _ros2_bag(tmp_path / "bag", signals, _shift(signals, -10 * 10**9), 0)
    with pytest.raises(ControlError, match=r"-9\.\d+ s since 1970.*time_base, --time-base"):
        _replay(path, emulator_a, likelihood_a, out_bag=tmp_path / "estimates")
    assert not (tmp_path / "estimates").exists()
    on_log = _replay(path, emulator_a, likelihood_a, time_base="log")
    assert on_log.write_bag(tmp_path / "estimates").is_dir()  # the receive times fit
    with pytest.raises(ControlError, match=r"imu_time holds -10\.0 s.*lie in \[0, "):
        control.robot.write_sensor_bag(tmp_path / "w", [-10.0], [0.0], [0.0], [0.0], [1.0])
