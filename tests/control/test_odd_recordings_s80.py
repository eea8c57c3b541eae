"""Odd but valid robot recordings: what real robots' bags hold that a simulated one does not.

An IMU message marking its acceleration unknown (covariance element 0 = -1), exact copies of
IMU messages (merged or overlapping bags), a ROS 1 bag stamped after January 2038 (its seconds
are a uint32), estimates whose stamps a ROS 2 header cannot hold.
"""

import struct

import numpy as np
import pytest
from _robot_cases import ros1_bag

pytest.importorskip("rosbags")
pytest.importorskip("mcap")

from control.errors import BagError, ControlError  # noqa: E402
from control.robot import messages as msgs  # noqa: E402
from control.robot import read_recording, replay_bag, write_sensor_bag  # noqa: E402
from control.robot.bags import open_bag_writer, sensor_messages  # noqa: E402


def _drive(n: int = 600):
    """(t s, accel m/s^2, position m, speed m/s): n samples at 120 Hz driving at 1 m/s."""
    t = 2.0 + np.arange(n) / 120.0
    accel = np.random.default_rng(4).normal(0.0, 2.0, n)
    return t, accel, t - 2.0, np.ones(n)


def _bag(path, imu: list[tuple[int, bytes]], odom: list[tuple[int, bytes]], extra_imu=()):
    """A ROS 2 bag of these (receive time ns, CDR message) pairs, written in the order given."""
    store = msgs.typestore()
    with open_bag_writer(path) as writer:
        c_imu = writer.add_connection("/imu/data", msgs.IMU_TYPE, typestore=store)
        for topic in extra_imu:
            writer.add_connection(topic, msgs.IMU_TYPE, typestore=store)
        c_odom = writer.add_connection("/odometry/filtered", msgs.ODOMETRY_TYPE, typestore=store)
        for conn, items in ((c_imu, imu), (c_odom, odom)):
            for log, data in items:
                writer.write(conn, log, data)
    return path


def _unknown_accel(data: bytes) -> bytes:
    """An Imu message with linear_acceleration_covariance[0] = -1 and the acceleration zero
    (what a driver without an accelerometer reading sends)."""
    b = bytearray(data)
    n = len(b)
    b[n - 96 : n - 72] = bytes(24)  # linear_acceleration
    b[n - 72 : n - 64] = struct.pack("<d", -1.0)  # linear_acceleration_covariance[0]
    return bytes(b)


def _messages(t, accel, position, speed):
    t_imu, imu, t_odom, odom = sensor_messages(t, accel, t, position, speed)
    streams = ((t_imu, imu), (t_odom, odom))
    pairs = [list(zip(ts.tolist(), data, strict=True)) for ts, data in streams]
    return pairs[0], pairs[1]


def test_imu_messages_marking_their_acceleration_unknown_are_sensor_faults_not_zeros(
    emulator_b, likelihood_b, tmp_path
):
    # sensor_msgs/Imu: covariance element 0 = -1 means "no estimate, disregard": read as a
    # reading of 0 m/s^2, 1% of such messages moved GD means by up to 50, every update `ok`
    t, accel, position, speed = _drive()
    imu, odom = _messages(t, accel, position, speed)
    marked = [100, 101, 350]
    imu_marked = [(log, _unknown_accel(d)) if k in marked else (log, d)
                  for k, (log, d) in enumerate(imu)]  # fmt: skip
    bag = _bag(tmp_path / "some", imu_marked, odom)
    assert read_recording(bag).imu.accel_unknown.nonzero()[0].tolist() == marked
    r = replay_bag(bag, emulator_b, likelihood=likelihood_b)
    assert np.flatnonzero(np.isnan(r.sample_accel)).tolist() == marked
    assert any("3 of the IMU's 600 messages mark their linear acceleration unknown" in n
               for n in r.notes)  # fmt: skip
    assert "non-finite accel" in " ".join(r.reason[r.status == "sensor_fault"])
    # where every message does, the topic holds no acceleration: refused, naming the others
    every = [(log, _unknown_accel(d)) for log, d in imu]
    bag = _bag(tmp_path / "all", every, odom, extra_imu=("/imu/data_raw",))
    with pytest.raises(BagError, match=r"'/imu/data' marks its linear acceleration unknown in "
                                       r"each of its 600 messages .*covariance\[0\] = -1.*"
                                       r"other IMU topics: /imu/data_raw"):  # fmt: skip
        replay_bag(bag, emulator_b, likelihood=likelihood_b)


def test_orientation_marked_unknown_changes_nothing(emulator_b, likelihood_b, tmp_path):
    # the bags this package writes mark orientation and angular velocity unknown (-1)
    t, accel, position, speed = _drive()
    bag = write_sensor_bag(tmp_path / "bag", t, accel, t, position, speed)
    rec = read_recording(bag)
    assert rec.imu.accel_unknown is None
    r = replay_bag(bag, emulator_b, likelihood=likelihood_b)
    assert np.array_equal(r.sample_accel, accel[: r.sample_accel.size])


def test_exact_copies_of_imu_messages_are_left_out_not_faults(emulator_b, likelihood_b, tmp_path):
    # a merged or overlapping bag holds some messages twice, bytes and stamps alike: each copy
    # read as a repeated stamp made every update a sensor_fault (all doubled) or 14 of 166
    t, accel, position, speed = _drive()
    imu, odom = _messages(t, accel, position, speed)
    clean = replay_bag(_bag(tmp_path / "clean", imu, odom), emulator_b, likelihood=likelihood_b)
    doubled = [m for m in imu for _ in range(2)]
    late = imu + imu[200:260]  # a stretch written again at the end (overlapping files)
    for name, msgs_ in (("doubled", doubled), ("late", late)):
        r = replay_bag(_bag(tmp_path / name, msgs_, odom), emulator_b, likelihood=likelihood_b)
        copies = len(msgs_) - len(imu)
        assert r.status.tolist() == clean.status.tolist(), name
        assert np.array_equal(r.gd_mean, clean.gd_mean, equal_nan=True), name
        assert np.array_equal(r.sample_accel, clean.sample_accel), name
        assert f"{copies} IMU message(s) left out as exact copies" in " ".join(r.notes)
        assert r.imu.repeated == copies  # the report counts the stamps as recorded
    # the same stamp with another reading is no copy: which is right? a fault, as before
    another = sensor_messages([t[300]], [accel[300] + 0.5], [t[0]], [0.0], [1.0])[1][0]
    other = imu[:301] + [(imu[300][0], another)] + imu[301:]
    r = replay_bag(_bag(tmp_path / "other", other, odom), emulator_b, likelihood=likelihood_b)
    assert "repeated or backwards time stamp" in " ".join(r.reason[r.status == "sensor_fault"])
    assert not any("exact copies" in n for n in r.notes)


def test_a_ros1_bag_stamped_after_2038_reads_its_stamps_and_estimates(
    emulator_b, likelihood_b, tmp_path
):
    # a ROS 1 time's seconds run to 2106 (uint32); read as int32 they came out in 1902
    t, accel, position, speed = _drive()
    t_ns = np.rint(t * 1e9).astype(np.int64)
    bag = ros1_bag(
        tmp_path / "run.bag", t_ns + 2_200_000_000 * 10**9, accel, position, speed
    )  # 2039
    rec = read_recording(bag)
    assert np.array_equal(rec.imu.stamp_ns, rec.imu.log_ns)
    assert rec.imu.stamp_ns[0] == 2_200_000_002_000_000_000
    early = ros1_bag(tmp_path / "early.bag", t_ns, accel, position, speed)
    r, base = (replay_bag(b, emulator_b, likelihood=likelihood_b) for b in (bag, early))
    assert np.array_equal(r.gd_mean, base.gd_mean, equal_nan=True)
    assert np.array_equal(r.stamp_ns - 2_200_000_000_000_000_000, base.stamp_ns)
    # the estimates' bag is ROS 2, whose header stamps end in January 2038: refused, naming it
    with pytest.raises(ControlError, match=r"outside a ROS 2 header stamp's .* keep the CSV"):
        r.write_bag(tmp_path / "estimates")
    assert not (tmp_path / "estimates").exists()


def test_estimates_stamped_after_2038_are_refused_as_a_bag_by_name(
    emulator_b, likelihood_b, tmp_path
):
    # receive times (int64 ns) may lie after 2038 where the header stamps cannot
    t, accel, position, speed = _drive()
    bag = write_sensor_bag(tmp_path / "bag", t, accel, t, position, speed,
                           log_time=np.r_[t, t] + 2.3e9)  # fmt: skip
    with pytest.raises(ControlError, match=r"2\.3e\+09 s since 1970\), outside a ROS 2 header"):
        replay_bag(bag, emulator_b, likelihood=likelihood_b, time_base="log",
                   out_bag=tmp_path / "est", csv=tmp_path / "est.csv")  # fmt: skip
    assert not (tmp_path / "est").exists() and not (tmp_path / "est.csv").exists()
    r = replay_bag(bag, emulator_b, likelihood=likelihood_b)  # header stamps fit
    assert r.write_bag(tmp_path / "est").is_dir()
