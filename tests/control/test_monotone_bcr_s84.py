"""The change-point BCR's monotone relations where they hold (session 84): near the Simplex's band
a uniformly louder acceleration stream never reads as smoother ground, the same stream at a
higher reported speed never as rougher, and in the closed loop the same road scaled to a higher
GD is never driven faster.

Measured, not pinned (docs/closed-loop.md, "Monotone relations"): far off the emulator's GD
manifold, a stream 1.3-2 times louder on ground near the top of the GD domain can read lower, as
the Student-t block law's likelihood flattens and the posterior falls back towards the prior."""

from __future__ import annotations

import numpy as np
import pytest

import control
import roadgen
import vehicle
from vehicle.simulate import simulate


def drive(gd: float, speed: float, seed: int, noise_std: float = 1.0):
    """A constant-speed drive over one-GD ground: (t, position, accel, speed), 14 s at 120 Hz."""
    profile = roadgen.iso8608_profile(speed * 14.0 + 2.0, gd, seed=seed)
    trace = simulate(vehicle.Jackal(), profile, speed, noise_std=noise_std, seed=seed + 1)
    return trace.t, trace.position, trace.accel_front_measured, trace.speed


def estimates(bcr: control.BCR, t, position, accel, speed) -> list[control.Estimate]:
    out = []
    for k in range(0, t.size, 42):
        sl = slice(k, k + 42)
        out.append(bcr.update(t[sl], position[sl], accel[sl], speed[sl]))
    return out


def numbers(e: control.Estimate) -> np.ndarray:
    return np.array([e.gd_mean, e.quantile(0.9), e.quantile(0.95), e.prob_above(350.0)])


def ordered_pairs(base, other):
    """The pairs of estimates at each update, both ok; the twins' statuses must agree (the same
    blocks pooled), and most must be ok."""
    assert [e.status for e in base] == [e.status for e in other]
    pairs = [(numbers(a), numbers(b)) for a, b in zip(base, other, strict=True) if a.ok]
    assert len(pairs) > len(base) // 2
    return pairs


@pytest.mark.parametrize(("gd", "speed", "seed"), [(300, 1.0, 3), (350, 1.5, 4)])
def test_a_louder_stream_never_reads_as_smoother_ground_near_the_band(new_bcr, gd, speed, seed):
    t, p, a, v = drive(gd, speed, seed)
    base = estimates(new_bcr("B"), t, p, a, v)
    for gain in (1.05, 1.1):
        louder = estimates(new_bcr("B"), t, p, a * gain, v)
        for quiet, loud in ordered_pairs(base, louder):
            assert np.all(loud >= quiet - 1e-9 * np.abs(quiet)), (gain, quiet, loud)


@pytest.mark.parametrize(("gd", "speed", "seed"), [(300, 1.0, 3), (350, 1.2, 5)])
def test_a_higher_reported_speed_never_reads_as_rougher_ground(new_bcr, gd, speed, seed):
    t, p, a, v = drive(gd, speed, seed)
    base = estimates(new_bcr("B"), t, p, a, v)
    faster = estimates(new_bcr("B"), t, p, a, v * 1.2)
    for slow, fast in ordered_pairs(base, faster):
        assert np.all(fast <= slow + 1e-9 * np.abs(slow)), (slow, fast)


def test_the_same_road_scaled_to_a_higher_gd_is_never_driven_faster(likelihood_b, emulator_b):
    segments = [(8.0, 250.0), (8.0, 300.0)]
    runs = [
        control.run_closed_loop(
            roadgen.track([(length, gd * k) for length, gd in segments], seed=12), emulator_b,
            noise_std=1.0, seed=12, likelihood=likelihood_b,
        )
        for k in (1.0, 1.5)
    ]  # fmt: skip
    for start, end in ((0.5, 8.0), (8.0, 15.5)):
        x = np.linspace(start, end, 200)
        smooth, rough = (np.interp(x, r.sample_position, r.sample_speed).mean() for r in runs)
        assert rough <= smooth, (start, smooth, rough)
