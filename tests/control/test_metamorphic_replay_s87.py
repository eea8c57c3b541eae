"""Metamorphic checks of the replay (session 87): a recording's stamps moved to the epoch (integer
nanoseconds), its topics written in the other order, the same bag replayed twice give the same
estimates bit for bit; its odometry moved 1e6 m from the frame's origin gives the same statuses
and reasons, and GD within the float64 resolution of the positions."""

import numpy as np
import pytest

import control
import roadgen

#: the per-estimate fields of a `ReplayResult`, and the samples fed to the BCR
FIELDS = ("time", "speed", "status", "reason", "domain_edge", "gd_mean", "gd_sd", "gd_lo",
          "gd_hi", "prob_above", "prob_change", "command", "mode", "sample_time",
          "sample_speed", "sample_accel")  # fmt: skip


@pytest.fixture(scope="module")
def drive(emulator_a, likelihood_a):
    """A short closed-loop run (12 m of GD 300, 12 m of GD 500) and its bag's replay."""
    pytest.importorskip("rosbags")
    pytest.importorskip("mcap")
    track = roadgen.track([(12, 300), (12, 500)], seed=3)
    return control.run_closed_loop(track, emulator_a, seed=3, likelihood=likelihood_a)


def _replay(path, emulator, likelihood):
    return control.replay_bag(path, emulator, likelihood=likelihood)


def _assert_same(got, want, fields=FIELDS):
    for name in fields:
        a, b = getattr(got, name), getattr(want, name)
        if np.asarray(b).dtype.kind == "f":
            assert np.array_equal(a, b, equal_nan=True), name
        else:
            assert np.asarray(a).tolist() == np.asarray(b).tolist(), name


def test_stamps_since_the_epoch_replay_as_stamps_from_zero(drive, emulator_a, likelihood_a,
                                                           tmp_path):  # fmt: skip
    start = 1_700_000_000_123_456_789
    early = control.record_run(drive, tmp_path / "early.mcap")
    late = control.record_run(drive, tmp_path / "late.mcap", start_ns=start)
    ref, got = (_replay(p, emulator_a, likelihood_a) for p in (early, late))
    assert ref.status_counts()["ok"] > 40
    _assert_same(got, ref, (*FIELDS, "position", "sample_position"))
    assert np.array_equal(got.stamp_ns - ref.stamp_ns, np.full(ref.stamp_ns.size, start))


def test_topics_in_the_other_order_and_a_second_replay_change_nothing(
    drive, emulator_a, likelihood_a, tmp_path
):
    from control.robot import messages as msgs
    from control.robot.bags import merge_in_time, open_bag_writer, sensor_messages

    t, p, a, v = (drive.sample_time, drive.sample_position, drive.sample_accel,
                  drive.sample_speed)  # fmt: skip
    bag = control.robot.write_sensor_bag(tmp_path / "imu_first", t, a, t, p, v)
    t_imu, imu, t_odom, odom = sensor_messages(t, a, t, p, v)
    store = msgs.typestore()
    with open_bag_writer(tmp_path / "odom_first", "mcap", {}) as writer:
        c_odom = writer.add_connection("/odometry/filtered", msgs.ODOMETRY_TYPE, typestore=store)
        c_imu = writer.add_connection("/imu/data", msgs.IMU_TYPE, typestore=store)
        for conn, stamp, data in merge_in_time([(c_odom, t_odom, odom), (c_imu, t_imu, imu)]):
            writer.write(conn, stamp, data)
    ref = _replay(bag, emulator_a, likelihood_a)
    _assert_same(_replay(tmp_path / "odom_first", emulator_a, likelihood_a), ref)
    _assert_same(_replay(bag, emulator_a, likelihood_a), ref, (*FIELDS, "position"))


def test_an_odometry_far_from_its_frames_origin_moves_gd_within_its_resolution(
    drive, emulator_a, likelihood_a, tmp_path
):
    """1e6 m off (positions spaced 1.2e-10 m there): GD moved by at most 4.4e-10 on this drive."""
    t, p, a, v = (drive.sample_time, drive.sample_position, drive.sample_accel,
                  drive.sample_speed)  # fmt: skip
    write = control.robot.write_sensor_bag
    ref = _replay(write(tmp_path / "near", t, a, t, p, v), emulator_a, likelihood_a)
    far = np.stack([p + 1e6, np.zeros_like(p), np.zeros_like(p)], axis=1)
    got = _replay(write(tmp_path / "far", t, a, t, far, v), emulator_a, likelihood_a)
    _assert_same(got, ref, ("status", "reason", "command", "mode", "sample_accel"))
    for name in ("gd_mean", "gd_sd", "prob_change"):
        np.testing.assert_allclose(getattr(got, name), getattr(ref, name), rtol=1e-9, atol=0,
                                   err_msg=name)  # fmt: skip
    np.testing.assert_allclose(got.position - 1e6, ref.position, rtol=0, atol=1e-9)
