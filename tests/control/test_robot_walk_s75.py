"""A robotics engineer's walkthrough of the replay (session 75): IMU and odometry stamped on
different clocks, odometry received out of order, a bag folder without its metadata."""

import warnings

import numpy as np
import pytest

import control
import roadgen
import vehicle
from control.robot import replay_bag, write_sensor_bag

pytest.importorskip("rosbags")
pytest.importorskip("mcap")


@pytest.fixture(scope="module")
def drive():
    """(t s, accel m/s^2, position m, speed m/s) at 120 Hz: 26 s at 1.5 m/s on GD 300."""
    sim = vehicle.Simulation(vehicle.Jackal(), roadgen.track([(40, 300)], seed=1), seed=1)
    parts = []
    while not sim.finished:
        s = sim.advance(1.0, 1.5)
        if len(s) == 0:
            break
        parts.append((s.t, s.accel_front, s.position, s.speed))
    t, a, x, v = (np.concatenate(p) for p in zip(*parts, strict=True))
    cruise = t >= 2.0
    return t[cruise], a[cruise], x[cruise], v[cruise]


def _bag(path, drive, imu_stamp_shift, odom_log_delay=None):
    """A bag of the drive, odometry at 40 Hz; the IMU's header stamps shifted by
    ``imu_stamp_shift`` (s, per message) while receive times stay the true times (+2 ms)."""
    t, a, x, v = drive
    o = slice(None, None, 3)
    log_odom = t[o] + (0.004 if odom_log_delay is None else odom_log_delay)
    log = np.concatenate([t + 0.002, log_odom])
    return write_sensor_bag(
        path, t + imu_stamp_shift, a, t[o], x[o], v[o], log_time=log
    )  # fmt: skip


def test_an_imu_stamped_on_another_clock_than_the_odometry_is_refused_with_the_remedy(
    drive, emulator_a, likelihood_a, tmp_path
):
    # an IMU driver stamping in GPS time (18 s ahead of UTC) beside odometry in system time:
    # paired on header stamps, every IMU sample met the odometry of 18 s before (96 `ok`
    # estimates of a drive that stood, then drove, GD 500 read as 373)
    bag = _bag(tmp_path / "gps", drive, 18.0)
    with pytest.raises(control.BagError, match=r"different clocks.*18(\.0)? s.*time-base log"):
        replay_bag(bag, emulator_a, likelihood=likelihood_a)
    r = replay_bag(bag, emulator_a, likelihood=likelihood_a, time_base="log")
    assert np.count_nonzero(r.status == "ok") > 0.8 * r.status.size


def test_an_imu_clock_step_that_the_odometry_does_not_share_turns_its_samples_into_faults(
    drive, emulator_a, likelihood_a, tmp_path
):
    t = drive[0]
    step = np.where(t > t[0] + 12.0, -10.0, 0.0)  # the IMU's clock steps back 10 s at 12 s
    bag = _bag(tmp_path / "step", drive, step)
    with pytest.warns(control.ControlWarning, match="another clock than the odometry"):
        r = replay_bag(bag, emulator_a, likelihood=likelihood_a)
    assert any("another clock than the odometry" in n for n in r.notes)
    before = r.status[: r.status.size // 3]
    assert np.count_nonzero(before == "ok") > 0.5 * before.size  # the part before is read
    # before: the samples after the step met the odometry of 10 s before and read as `ok`
    assert not np.isfinite(r.sample_accel[-1500:]).any()
    assert not np.any(r.status[-(r.status.size // 3) :] == "ok")


def test_receive_latency_and_a_small_offset_between_the_clocks_pass_unflagged(
    drive, emulator_a, likelihood_a, tmp_path
):
    # 0.4 s between the clocks, and odometry received 0.3 s late: below max_clock_skew_s (1 s)
    bag = _bag(tmp_path / "near", drive, 0.4, odom_log_delay=0.3)
    with warnings.catch_warnings():
        warnings.simplefilter("error", control.ControlWarning)
        r = replay_bag(bag, emulator_a, likelihood=likelihood_a)
    assert not any("clock" in n for n in r.notes)
    assert np.count_nonzero(r.status == "ok") > 0.8 * r.status.size
    with pytest.raises(control.ControlError, match="max_clock_skew_s"):
        control.ReplaySettings(max_clock_skew_s=0.0)


def test_odometry_received_out_of_order_is_put_in_stamp_order_not_dropped(
    drive, emulator_a, likelihood_a, tmp_path
):
    t, a, x, v = drive
    o = slice(None, None, 3)
    late = np.zeros(t[o].size)
    late[5::20] = 0.06  # every 20th odometry message received 2.4 periods late
    log = np.concatenate([t + 0.002, t[o] + 0.004 + late])
    bag = write_sensor_bag(tmp_path / "late", t, a, t[o], x[o], v[o], log_time=log)
    r = replay_bag(bag, emulator_a, likelihood=likelihood_a)
    assert not any("odometry messages left out" in n for n in r.notes), r.notes
    assert r.odometry.backwards > 0  # the report still counts them as recorded
    in_order = write_sensor_bag(tmp_path / "ordered", t, a, t[o], x[o], v[o])
    ref = replay_bag(in_order, emulator_a, likelihood=likelihood_a)
    np.testing.assert_array_equal(r.sample_position, ref.sample_position)


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_a_bag_folder_without_its_metadata_names_ros2_bag_reindex(drive, storage, tmp_path):
    t, a, x, v = drive
    bag = write_sensor_bag(tmp_path / "b", t[:200], a[:200], t[:200], x[:200], v[:200],
                           storage=storage)  # fmt: skip
    (bag / "metadata.yaml").unlink()  # a recorder killed before it wrote it
    data = next(p for p in bag.iterdir())
    with pytest.raises(control.BagError, match=f"{data.name}.*ros2 bag reindex .* -s {storage}"):
        replay_bag(bag, "A")
    if storage == "sqlite3":
        with pytest.raises(control.BagError, match="ros2 bag reindex .* -s sqlite3"):
            replay_bag(data, "A")
    else:  # an MCAP file reads alone
        assert replay_bag(data, "A").sample_time.size == 200
