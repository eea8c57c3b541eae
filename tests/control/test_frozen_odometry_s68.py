"""Odometry that freezes while the robot drives (a dead wheel-odometry node: the pose held, the
twist 0): the BCR read the robot as standing and carried its last estimate, so the Simplex kept
the performance speed from the GD-300 ground onto the next ground for ``max_age_s`` (5 s), up to
10 m unseen. The accelerometer still reads a moving vehicle; a robot standing reads its noise."""

import numpy as np
import pytest

import roadgen
import vehicle
from control import Simplex
from control.bcr import STANDING_SETTLE_S


def drive(noise: float, seed: int = 2, legs=((8.0, 1.5),), gd: float = 300.0):
    """A drive over GD ``gd`` (t, position, accel, speed): ``legs`` ((seconds, m/s set-point),
    ...), 8 s at 1.5 m/s by default."""
    track = roadgen.track([(20.0, gd)], seed=seed)
    sim = vehicle.Simulation(vehicle.Jackal(), track, noise_std=noise, seed=seed)
    parts = [sim.advance(dt, v) for dt, v in legs]
    return (
        np.concatenate([np.asarray(getattr(p, k), dtype=float) for p in parts])
        for k in ("t", "position", "accel_front", "speed")
    )


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
    # no estimate while it may be a stop's ringing (STANDING_SETTLE_S), then the fault
    assert after and after[0][0].status == "out_of_domain"
    assert "standing" in after[0][0].reason
    faults = [e.time for e, _ in after if e.status == "sensor_fault"]
    assert faults and faults[0] < 4.0 + 125 / 120 + STANDING_SETTLE_S + 0.4
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


@pytest.mark.parametrize("case", ["A", "B"])
def test_a_robot_that_stops_on_rough_ground_is_no_fault(new_bcr, case):
    """A hard stop (20 m/s^2) from 2 m/s on GD 500: the suspension rings for a second, and its
    first standing blocks read as driving at 0.5 m/s (level score +5.5 sd (A), +2.6 (B)); they
    were a "sensor_fault" that latched the Simplex for the rest of the run."""
    t, pos, acc, spd = drive(0.0 if case == "A" else 1.0, 0, ((6.0, 2.0), (5.0, 0.0)), 500.0)
    out = feed(new_bcr(case), t, pos, acc, spd)
    assert not any(e.status == "sensor_fault" for e, _ in out)
    assert not any("latched" in c.reason for _, c in out)
    standing = [e for e, _ in out if e.time > 6.2 and e.status == "ok"]
    assert standing and "no new information" in standing[-1].reason  # carried while standing
