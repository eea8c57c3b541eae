"""Odometry that freezes while the robot drives (a dead wheel-odometry node: the pose held, the
twist 0): the BCR read the robot as standing and carried its last estimate, so the Simplex kept
the performance speed from the GD-300 ground onto the next ground for ``max_age_s`` (5 s), up to
10 m unseen. The accelerometer still reads a moving vehicle; a robot standing reads its noise."""

import numpy as np
import pytest

import roadgen
import vehicle
from control import Simplex


def drive(noise: float, seed: int = 2):
    """6 s of GD 300 at 1.5 m/s (t, position, accel, speed), and the sample where it reaches
    speed plus 2 s."""
    track = roadgen.track([(12.0, 300.0)], seed=seed)
    sim = vehicle.Simulation(vehicle.Jackal(), track, noise_std=noise, seed=seed)
    s = sim.advance(6.0, 1.5)
    return (np.asarray(x, dtype=float) for x in (s.t, s.position, s.accel_front, s.speed))


def feed(bcr, t, pos, acc, spd):
    """(estimate, command) of each update, fed in 42-sample chunks with now= the newest stamp."""
    run, out = Simplex().start(), []
    for k in range(0, t.size - 41, 42):
        part = slice(k, k + 42)
        est = bcr.update(t[part], pos[part], acc[part], spd[part], now=float(t[part][-1]))
        out.append((est, run.command(est)))
    return out


@pytest.mark.parametrize("case", ["A", "B"])
def test_odometry_that_freezes_while_driving_is_a_sensor_fault(new_bcr, case):
    t, pos, acc, spd = drive(noise=0.0 if case == "A" else 1.0)
    frozen = t >= 4.0
    pos, spd = pos.copy(), spd.copy()
    pos[frozen], spd[frozen] = pos[frozen][0], 0.0
    out = feed(new_bcr(case), t, pos, acc, spd)
    before = [e.status for e, _ in out if e.time < 4.0]
    after = [(e, c) for e, c in out if e.time >= 4.0 + 125 / 120]  # a whole frozen block
    assert before[-1] == "ok"
    assert after and after[0][0].status == "sensor_fault"
    assert "standing" in after[0][0].reason
    assert all(c.mode == "safety" for _, c in after)


@pytest.mark.parametrize("case", ["A", "B"])
def test_a_robot_standing_still_is_no_fault(new_bcr, case):
    """Standing after a drive: the accelerometer reads its own noise (B: N(0, 1); A: a real
    IMU's 0.05 m/s^2), the estimate is carried until it turns stale, never a fault."""
    t, pos, acc, spd = drive(noise=0.0 if case == "A" else 1.0)
    stand = t >= 4.0
    pos, spd, acc = pos.copy(), spd.copy(), acc.copy()
    pos[stand], spd[stand] = pos[stand][0], 0.0
    rng = np.random.default_rng(3)
    acc[stand] = rng.normal(0.0, 1.0 if case == "B" else 0.05, int(stand.sum()))
    statuses = {e.status for e, _ in feed(new_bcr(case), t, pos, acc, spd)}
    assert "sensor_fault" not in statuses and "ok" in statuses
