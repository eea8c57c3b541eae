"""IMU stamps with jitter, and messages received out of order (session 70).

Before: header stamps with 1 ms of Gaussian jitter (every message delivered) gave the BCR steps
outside 0.5-1.5 periods, read as dropped or repeated samples (`sensor_fault`, which latches the
Simplex), and adjacent messages received out of order with right header stamps were fed in
receive order (sensor faults). Now the replay puts such messages in stamp order and re-stamps
the IMU on its own fitted clock (`clock.restamp`): jitter goes, while a dropped message, a
duplicate and a clock step still reach the BCR as sensor faults (docs/robot.md, "Time stamps")."""

import re

import numpy as np
import pytest

pytest.importorskip("rosbags")
pytest.importorskip("mcap")

import roadgen  # noqa: E402
import vehicle  # noqa: E402
from control.errors import ControlError  # noqa: E402
from control.robot import ReplaySettings, clock, replay_bag, write_sensor_bag  # noqa: E402

P = 1 / 120


def _clock(n=4800, sd_s=0.0, seed=0, drop=()):
    """(true times, stamps) of n samples at 120 Hz (slightly slow clock) with Gaussian jitter."""
    true = 50.0 + np.arange(n) * P * (1 + 40e-6)
    stamps = true + np.random.default_rng(seed).normal(0.0, sd_s, n)
    keep = np.ones(n, bool)
    keep[list(drop)] = False
    return true[keep], stamps[keep]


def _faults(t):
    step = np.diff(t) / P
    return int(np.count_nonzero((step < 0.5) | (step > 1.5)))


@pytest.mark.parametrize("sd_ms", [0.2, 1.0])
def test_jitter_is_removed_and_a_dropped_message_stays_a_gap(sd_ms):
    true, t = _clock(sd_s=sd_ms * 1e-3, drop=(1000, 3000))
    assert _faults(t) > (2 if sd_ms == 1.0 else 1)  # before: jitter read as gaps
    new, info = clock.restamp(t, "the stamps")
    assert info.restamped and info.jitter_sd_s == pytest.approx(sd_ms * 1e-3, rel=0.1)
    assert _faults(new) == 2  # the two dropped messages, nothing else
    assert np.max(np.abs(new - true)) < 1e-4  # every message on its own slot (P = 8.3 ms)
    assert "Hz clock: jitter sd" in info.note


def test_exact_stamps_are_kept_bit_for_bit_and_too_much_jitter_is_refused_and_said():
    _, t = _clock()
    new, info = clock.restamp(np.round(t, 9))
    assert not info.restamped and np.array_equal(new, np.round(t, 9)) and info.note == ""
    _, t = _clock(sd_s=3e-3)
    new, info = clock.restamp(np.sort(t), "its header stamps")
    assert not info.restamped and np.array_equal(new, np.sort(t))
    # the clock fitted on the stamps' mean step (session 70; the median step read 121.4 Hz)
    assert re.search(
        r"were not re-stamped: they jitter by sd (2\.\d|3) ms about a 120\.00 Hz", info.note
    )
    assert "cannot be told from a dropped one" in info.note


def test_a_duplicate_and_clock_steps_stay_faults():
    _, t = _clock(sd_s=0.5e-3)
    dup = np.insert(t, 2000, t[2000])
    assert _faults(clock.restamp(dup)[0]) == 1  # a repeated stamp
    back = t.copy()
    back[2500:] -= 30.0  # the clock steps back 30 s
    new, info = clock.restamp(back)
    assert info.runs == 2 and _faults(new) == 1 and np.diff(new)[2499] < -29
    for step_s, faults in ((5e-3, 1), (4.2e-3, 1), (2.5e-3, 0)):  # 0.6, 0.5 and 0.3 period back
        stepped = t.copy()
        stepped[2500:] -= step_s
        new, info = clock.restamp(stepped)
        # kept as the step it is (a sensor fault where the BCR would take it for one)
        assert info.runs == 2 and _faults(new) == faults
        assert abs(np.diff(new)[2499] - (P - step_s)) < 1e-3
    fwd = t.copy()
    fwd[2500:] += 0.5 + 0.003  # a pause of half a second, then another phase
    new, info = clock.restamp(fwd)
    assert info.runs == 2 and _faults(new) == 1 and np.diff(new)[2499] > 0.5


def test_receive_latency_is_taken_as_late_only():
    rng = np.random.default_rng(3)
    t = np.sort(np.arange(20_000) * P + rng.exponential(1e-3, 20_000))  # receive times
    assert _faults(t) > 5
    new, info = clock.restamp(t)
    assert info.restamped and _faults(new) <= 2


def test_stamp_order_sorts_late_messages_but_keeps_clock_steps():
    t = np.arange(10) * P
    t[[3, 4]] = t[[4, 3]]
    assert np.array_equal(clock.stamp_order(t, 3 * P), [0, 1, 2, 4, 3, 5, 6, 7, 8, 9])
    stepped = np.r_[t[:5], t[5:] - 1.0]  # a clock step back of 1 s is kept
    order = clock.stamp_order(stepped, 3 * P)
    assert np.array_equal(order[5:], np.arange(5, 10))


@pytest.fixture(scope="module")
def drive():
    trace = vehicle.simulate(
        vehicle.Jackal(), roadgen.track([(12, 400)], seed=2), 1.5, noise_std=1.0, seed=2
    )
    return trace.t + 1.0, trace.accel_front_measured, trace.position, trace.speed


def _replay(tmp_path, drive, emulator_b, likelihood_b, stamps, keep=None, log=None, **kw):
    t, a, p, s = drive
    if keep is not None:
        stamps, a = stamps[keep], a[keep]
    lt = None if log is None else np.concatenate([log, t])
    bag = write_sensor_bag(tmp_path / f"bag{len(list(tmp_path.iterdir()))}", stamps, a, t, p, s,
                           log_time=lt)  # fmt: skip
    return replay_bag(bag, emulator_b, likelihood=likelihood_b, **kw)


def test_replay_of_jittered_and_misordered_stamps(tmp_path, drive, emulator_b, likelihood_b):
    t = drive[0]
    run = lambda *a, **kw: _replay(tmp_path, drive, emulator_b, likelihood_b, *a, **kw)  # noqa: E731
    clean = run(t)
    assert clean.restamping.restamped is False and "re-stamped" not in clean.imu.describe()
    jitter = t + np.random.default_rng(1).normal(0.0, 1e-3, t.size)
    before = run(jitter, restamp=False)
    assert "sensor_fault" in before.status
    after = run(jitter)
    assert np.array_equal(after.status, clean.status)
    assert "re-stamped on a 120.00 Hz clock: jitter sd 0.97 ms" in after.imu.describe()
    assert after.imu.describe().endswith("on that clock: no stamp faults")
    ok = after.status == "ok"  # the odometry is read at the clock's times: nearly the same
    assert np.max(np.abs(after.gd_mean - clean.gd_mean)[ok] / clean.gd_sd[ok]) < 0.2
    keep = np.ones(t.size, bool)
    keep[400] = False  # a dropped message still is a sensor fault
    dropped = run(jitter, keep)
    assert "sensor_fault" in dropped.status and "gap" in " ".join(dropped.reason)
    late = t + np.random.default_rng(2).exponential(2e-3, t.size)  # received out of order
    assert np.any(np.diff(late) < 0)
    swapped = run(t, log=late)
    assert np.array_equal(swapped.status, clean.status)
    assert "put in stamp order" in swapped.imu.describe()
    assert "sensor_fault" in run(t, log=late, reorder_periods=0.0).status


def test_settings_are_checked():
    with pytest.raises(ControlError, match="reorder_periods must be >= 0"):
        ReplaySettings(reorder_periods=-1.0)
    with pytest.raises(ControlError, match="restamp must be True or False"):
        ReplaySettings(restamp=1)
