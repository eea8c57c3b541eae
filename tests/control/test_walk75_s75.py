"""A robotics engineer's walkthrough of session 75's replay features (walk75): the replay's
report says where late odometry was put back in stamp order, as it says for the IMU; a static
level given for a recording whose IMU reads no gravity is named (every block a scale fault)."""

import warnings

import numpy as np
import pytest

from control.errors import ControlWarning
from control.robot import replay_bag, write_sensor_bag

pytest.importorskip("rosbags")
pytest.importorskip("mcap")


def test_the_odometry_report_says_late_messages_were_put_in_stamp_order(
    emulator_a, likelihood_a, tmp_path
):
    # 12 s of a still IMU at 120 Hz, odometry at 40 Hz, every 20th odometry message received
    # 2.4 of its periods late: its report counted them as backwards stamps and said nothing of
    # their being put in order (the IMU's report says so), so they read as faults
    t = np.arange(1440) / 120.0
    a = np.random.default_rng(0).normal(0.0, 1.0, t.size)
    o = slice(None, None, 3)
    late = np.zeros(t[o].size)
    late[5::20] = 0.06
    log = np.concatenate([t + 0.002, t[o] + 0.004 + late])
    x = 1.5 * t
    bag = write_sensor_bag(tmp_path / "late", t, a, t[o], x[o], np.full(t.size, 1.5)[o],
                           log_time=log)  # fmt: skip
    r = replay_bag(bag, emulator_a, likelihood=likelihood_a)
    assert r.odometry.backwards > 0  # counted as recorded
    assert "put in stamp order" in r.odometry.note, r.odometry.note
    assert "put in stamp order" not in r.imu.note  # the IMU's came in order
    in_order = replay_bag(
        write_sensor_bag(tmp_path / "ordered", t, a, t[o], x[o], np.full(t.size, 1.5)[o]),
        emulator_a, likelihood=likelihood_a,
    )  # fmt: skip
    assert "stamp order" not in in_order.odometry.note


@pytest.mark.parametrize("gravity", ["keep", "highpass"])
def test_a_static_level_for_an_imu_that_reads_no_gravity_is_named(
    emulator_a, likelihood_a, tmp_path, gravity
):
    # a simulated drive written without gravity, replayed with --static-mps2: every block read
    # as a scale fault, and nothing said why
    t = np.arange(1440) / 120.0
    a = np.random.default_rng(0).normal(0.0, 1.0, t.size)
    o = slice(None, None, 3)
    bag = write_sensor_bag(tmp_path / "flat", t, a, t[o], 1.5 * t[o], np.full(t.size, 1.5)[o])
    with pytest.warns(ControlWarning, match="reads no gravity"):
        r = replay_bag(bag, emulator_a, likelihood=likelihood_a, static_mps2=9.80665,
                       gravity=gravity)  # fmt: skip
    assert any("reads no gravity" in n for n in r.notes)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ControlWarning)  # the check off: nothing to say
        replay_bag(bag, emulator_a, likelihood=likelihood_a, gravity=gravity)
