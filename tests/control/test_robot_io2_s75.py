"""Robot I/O (session 75): simulated bags whose IMU reports gravity (the static-level check's
recipe), and odometry received later than ``reorder_periods`` put into the gap it left."""

import warnings

import numpy as np
import pytest

import control
import roadgen
from control.robot import (
    clock,
    read_recording,
    record_run,
    replay_bag,
    write_run_bag,
    write_sensor_bag,
)

pytest.importorskip("rosbags")
pytest.importorskip("mcap")

from _robot_cases import small_result  # noqa: E402

G = 9.80665


@pytest.fixture(scope="module")
def runs(likelihood_a, likelihood_b):
    """Closed-loop drives over 15 m of GD 300 then 15 m of GD 500 (seed 3): {case: result}."""
    track = roadgen.track([(15, 300), (15, 500)], seed=3)
    return {
        case: control.run_closed_loop(track, lik.emulator, noise_std=noise, seed=3, likelihood=lik)
        for case, lik, noise in (("A", likelihood_a, 0.0), ("B", likelihood_b, 1.0))
    }


def _replay(bag, lik, **kw):
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always", control.ControlWarning)
        r = replay_bag(bag, lik.emulator, likelihood=lik, **kw)
    return r, [str(w.message) for w in seen if issubclass(w.category, control.ControlWarning)]


def test_the_writers_add_gravity_to_the_up_axis_only_when_asked(tmp_path):
    result = small_result()
    plain = read_recording(write_run_bag(result, tmp_path / "plain")).imu.accel
    np.testing.assert_array_equal(plain[:, 2], result.sample_accel)  # default: as before
    up = read_recording(write_run_bag(result, tmp_path / "up", gravity=True)).imu.accel
    np.testing.assert_array_equal(up[:, 2], result.sample_accel + G)
    np.testing.assert_array_equal(up[:, :2], 0.0)
    rec = read_recording(record_run(result, tmp_path / "run.mcap", gravity=True)).imu.accel
    np.testing.assert_array_equal(rec[:, 2], result.sample_accel + G)
    t = result.sample_time
    x = read_recording(write_sensor_bag(tmp_path / "x", t, result.sample_accel, t, t, t,
                                        axis="x", gravity=True)).imu.accel  # fmt: skip
    np.testing.assert_array_equal(x[:, 0], result.sample_accel + G)


@pytest.mark.parametrize(
    ("kw", "says"),
    [
        ({"gravity": "yes"}, "gravity must be True or False"),
        ({"gravity": 1}, "gravity must be True or False"),
        ({"faults": [control.SensorFault(0.5, 1.0, "time_nan")]}, "time_nan"),
        ({"faults": control.SensorFault(0.5, 1.0, "scale", 0.8)}, r"pass \[fault\]"),
        ({"faults": [control.SensorFault(0.5, 1.0)], "fault_seed": -1}, "fault_seed"),
    ],
)
def test_bad_gravity_and_fault_options_are_refused(kw, says, tmp_path):
    with pytest.raises(control.ControlError, match=says):
        write_run_bag(small_result(), tmp_path / "b", **kw)
    assert not (tmp_path / "b").exists()


def test_a_gain_written_after_gravity_scales_it_as_a_real_imu_s_gain(tmp_path):
    result = small_result()
    fault = control.SensorFault(1.0, 10.0, "scale", 0.8)
    got = read_recording(write_run_bag(result, tmp_path / "g", gravity=True, faults=[fault]))
    late = result.sample_time >= 1.0
    np.testing.assert_allclose(got.imu.accel[late, 2], 0.8 * (result.sample_accel[late] + G))
    np.testing.assert_array_equal(got.imu.accel[~late, 2], result.sample_accel[~late] + G)


def test_the_recipe_a_gain_fault_latches_the_static_check_a_clean_drive_does_not(
    runs, likelihood_b, tmp_path
):
    r = runs["B"]
    # before: the simulator's IMU reads no gravity, every block a scale fault
    free, said = _replay(write_run_bag(r, tmp_path / "free"), likelihood_b, static_mps2=G)
    assert any("reads no gravity" in w for w in said)
    clean, said = _replay(write_run_bag(r, tmp_path / "clean", gravity=True), likelihood_b,
                          static_mps2=G)  # fmt: skip
    assert not said and "sensor_fault" not in clean.status.tolist()
    np.testing.assert_array_equal(clean.status, replay_bag(tmp_path / "free", "B").status)
    fault = control.SensorFault(10.0, 1e3, "scale", 0.8)
    bag = write_run_bag(r, tmp_path / "gain", gravity=True, faults=[fault])
    faulty, _ = _replay(bag, likelihood_b, static_mps2=G)
    scale = np.flatnonzero(["scale or tilt" in why for why in faulty.reason])
    assert scale.size and faulty.time[scale[0]] >= 10.0
    assert faulty.time[scale[0]] < 14.0  # within 4 s of the fault
    assert np.all(faulty.mode[scale[0] :] == "safety")  # latched
    assert not np.any(np.isin(faulty.status[faulty.time < 10.0], ["sensor_fault", "implausible"]))


def test_emulator_a_names_gravity_kept_and_the_high_pass_reads_as_gravity_free(
    runs, likelihood_a, tmp_path
):
    r = runs["A"]
    free, _ = _replay(write_run_bag(r, tmp_path / "free"), likelihood_a)
    bag = write_run_bag(r, tmp_path / "up", gravity=True)
    kept, said = _replay(bag, likelihood_a, static_mps2=G)
    assert any("gravity='highpass'" in w for w in said)  # flights flagged with gravity kept
    passed, said = _replay(bag, likelihood_a, gravity="highpass", static_mps2=G)
    assert not said
    np.testing.assert_array_equal(passed.status, free.status)
    assert np.count_nonzero(kept.status == "sensor_fault") > np.count_nonzero(
        free.status == "sensor_fault"
    )


def _stamps(n=400, period=0.025):
    return 1.0 + period * np.arange(n), period


def test_into_gaps_moves_late_messages_only_into_the_slots_they_left():
    t, p = _stamps()
    recv = t.copy()
    recv[[50, 51, 200]] += 10 * p  # received 10 periods late (two of them together)
    arrived = np.argsort(recv, kind="stable")
    got = t[arrived]
    order, moved = clock.into_gaps(got, clock.stamp_order(got, 3 * p), p)
    assert moved == 3
    np.testing.assert_array_equal(got[order], t)
    # in order, or late within the window: the order as given, the same object
    within = clock.stamp_order(t, 3 * p)
    assert clock.into_gaps(t, within, p) == (within, 0)


@pytest.mark.parametrize("what", ["clock step back", "stale stamp", "zero stamp", "duplicate"])
def test_into_gaps_leaves_clock_steps_and_wrong_stamps_behind(what):
    t, p = _stamps()
    if what == "clock step back":  # 0.51 s back at message 200: its slots are taken
        got = np.where(np.arange(t.size) >= 200, t - 20.5 * p, t)
    elif what == "stale stamp":  # one message stamped 5 s early
        got = t.copy()
        got[200] -= 200.5 * p
    elif what == "zero stamp":
        got = t.copy()
        got[200] = 0.0
    else:  # message 100 received a second time, 10 periods later
        got = np.insert(t, 110, t[100])
    order = clock.stamp_order(got, 3 * p)
    assert clock.into_gaps(got, order, p) == (order, 0)


def test_odometry_received_ten_periods_late_replays_as_received_in_order(
    runs, likelihood_b, tmp_path
):
    r = runs["B"]
    t, a, x, v = r.sample_time, r.sample_accel, r.sample_position, r.sample_speed
    o = slice(None, None, 3)  # odometry at 40 Hz
    late = np.zeros(t[o].size)
    late[5::20] = 0.25  # every 20th message received 10 periods late (left out before)
    log = np.concatenate([t + 0.002, t[o] + 0.004 + late])
    bag = write_sensor_bag(tmp_path / "late", t, a, t[o], x[o], v[o], log_time=log)
    got, _ = _replay(bag, likelihood_b)
    ref, _ = _replay(write_sensor_bag(tmp_path / "ok", t, a, t[o], x[o], v[o]), likelihood_b)
    assert not any("odometry messages left out" in n for n in got.notes), got.notes
    n = np.count_nonzero(late)
    assert f"{n} message(s) received out of stamp order put in stamp order ({n} of them" in (
        got.odometry.note
    )
    np.testing.assert_array_equal(got.sample_speed, ref.sample_speed)
    np.testing.assert_array_equal(got.gd_mean, ref.gd_mean)
