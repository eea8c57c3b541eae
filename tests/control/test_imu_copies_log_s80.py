"""On receive times (``time_base="log"``) an IMU message is an exact copy only where its receive
time repeats too: messages of one header stamp received apart are samples (a driver stamping
several at once; a stuck sensor's reading repeated), never left out as copies."""

import numpy as np
import pytest

pytest.importorskip("rosbags")
pytest.importorskip("mcap")

from control.robot import messages as msgs  # noqa: E402
from control.robot import replay_bag  # noqa: E402
from control.robot.bags import open_bag_writer, sensor_messages  # noqa: E402


def _bag(path, imu, odom):
    """A ROS 2 bag of these (receive time ns, CDR message) pairs."""
    store = msgs.typestore()
    with open_bag_writer(path) as writer:
        c_imu = writer.add_connection("/imu/data", msgs.IMU_TYPE, typestore=store)
        c_odom = writer.add_connection("/odometry/filtered", msgs.ODOMETRY_TYPE, typestore=store)
        for conn, items in ((c_imu, imu), (c_odom, odom)):
            for log, data in items:
                writer.write(conn, log, data)
    return path


def test_one_stamp_received_apart_is_no_copy_on_receive_times(emulator_b, likelihood_b, tmp_path):
    n = 600
    t = 2.0 + np.arange(n) / 120.0
    accel = np.random.default_rng(4).normal(0.0, 2.0, n)
    accel[200:300] = 0.3  # a stuck sensor: one reading, bit for bit, for 100 samples
    batch = t[(np.arange(n) // 4) * 4]  # a driver stamping 4 messages at a time
    _, imu, t_odom, odom = sensor_messages(batch, accel, t, t - 2.0, np.ones(n))
    log = np.round(t * 1e9).astype(np.int64).tolist()  # received 1/120 s apart
    bag = _bag(tmp_path / "b", list(zip(log, imu, strict=True)),
               list(zip(t_odom.tolist(), odom, strict=True)))  # fmt: skip
    r = replay_bag(bag, emulator_b, likelihood=likelihood_b, time_base="log")
    assert not any("exact copies" in note for note in r.notes)  # 75 were left out
    assert np.array_equal(r.sample_accel, accel[: r.sample_accel.size])
    assert np.count_nonzero(r.sample_accel == 0.3) == 100
    # the same message received twice at once (a merged bag) still is a copy
    twice = [(lg, d) for lg, d in zip(log, imu, strict=True) for _ in range(1 + (lg == log[50]))]
    bag = _bag(tmp_path / "twice", twice, list(zip(t_odom.tolist(), odom, strict=True)))
    r2 = replay_bag(bag, emulator_b, likelihood=likelihood_b, time_base="log")
    assert any("1 IMU message(s) left out as exact copies of an earlier one (the same header "
               "stamp, receive time and acceleration" in note for note in r2.notes)  # fmt: skip
    assert np.array_equal(r2.sample_accel, r.sample_accel)
