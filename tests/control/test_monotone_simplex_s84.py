"""The Simplex's monotone relations (session 84): a rougher reading, or a more cautious setting,
never commands a higher speed. Pinned over seeded random posteriors and settings, for the laws
whose performance speed is never below v_safe ("linear", "switch"; "paper" is exempt by design:
its law commands less than v_safe mid-band, docs/closed-loop.md "After a fault"), and over
sequences: `SimplexRun` twins fed pointwise ordered estimates, with the latch and the release
dwell.

Not pinned (measured, by design): with ``release_m > 0`` the start's safety mode has no dwell, so
a twin that read rougher from the start and first reads performance mode later leaves safety mode
at once, where its smoother twin, which had driven in performance mode, dwells (docs/closed-loop.md
"Release dwell"); the speed grid is anchored at v_safe, so a lower v_safe can round the same
law a grid step higher."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy import stats

from control import Estimate, Simplex
from gpmsa import Posterior
from gpmsa.calibration.posterior import GridMarginal

GRID = np.geomspace(200.0, 600.0, 121)
LAWS = ("linear", "switch")


def estimate(log_density: np.ndarray, position: float = 1.0, edge: str = "") -> Estimate:
    """An ok estimate whose posterior is ``log_density`` on GRID."""
    marginal = GridMarginal.from_log_density(GRID, log_density)
    post = Posterior(grids={"GD": marginal}, draw=lambda: {}, info={"names": ("GD",)})
    return Estimate(
        time=position, position=position, status="ok", gd_mean=post.mean("GD"),
        gd_sd=post.sd("GD"), interval=post.interval("GD", 0.9), posterior=post, domain_edge=edge,
    )  # fmt: skip


def random_log_density(rng: np.random.Generator) -> np.ndarray:
    """A mixture of 1-3 normals, centred anywhere in and beyond the grid."""
    parts = [
        np.log(rng.uniform(0.05, 1.0)) + stats.norm.logpdf(GRID, rng.uniform(180, 650),
                                                           rng.uniform(3, 120))
        for _ in range(rng.integers(1, 4))
    ]  # fmt: skip
    return np.logaddexp.reduce(parts, axis=0)


def rougher(rng: np.random.Generator, log_density: np.ndarray) -> np.ndarray:
    """The posterior times an increasing likelihood ratio: first-order stochastically higher
    (every quantile, the mean and P(GD > x) not lower)."""
    return log_density + rng.uniform(0.0, 0.05) * (GRID - GRID[0])


def random_simplex(rng: np.random.Generator, law: str) -> Simplex:
    gd_min = rng.uniform(150, 450)
    v_max = rng.uniform(0.6, 2.0)
    kw = dict(
        gd_min=gd_min, gd_max=gd_min + rng.uniform(1, 200), v_max=v_max,
        v_safe=rng.uniform(0.2, v_max), law=law,
        risk=None if rng.random() < 0.3 else float(10 ** rng.uniform(-4, np.log10(0.9))),
        speed_step_mps=float(rng.choice([0.0, 0.1, rng.uniform(0, v_max)])),
    )  # fmt: skip
    if law == "linear" and rng.random() < 0.3:
        kw["kp"] = float(10 ** rng.uniform(-3.5, -1))
    return Simplex(**kw)


def cases(seed: int, n: int):
    rng = np.random.default_rng(seed)
    for i in range(n):
        s = random_simplex(rng, LAWS[i % 2])
        yield rng, s, random_log_density(rng)


def test_a_rougher_posterior_never_commands_a_higher_speed():
    for rng, s, ld in cases(1, 300):
        smooth, rough = s.command(estimate(ld)), s.command(estimate(rougher(rng, ld)))
        assert rough.speed <= smooth.speed, (s, smooth, rough)


def test_the_upper_domain_edge_never_commands_a_higher_speed():
    for _, s, ld in cases(2, 200):
        assert s.command(estimate(ld, edge="upper")).speed <= s.command(estimate(ld)).speed


def test_a_smaller_risk_never_commands_a_higher_speed():
    for rng, s, ld in cases(3, 300):
        if s.risk is None:
            continue
        e = estimate(ld)
        cautious = replace(s, risk=s.risk * rng.uniform(0.01, 1.0))
        assert cautious.command(e).speed <= s.command(e).speed, (s, cautious.risk)


def test_a_lower_gd_max_or_gd_min_never_commands_a_higher_speed():
    for rng, s, ld in cases(4, 300):
        e = estimate(ld)
        lower_max = replace(s, gd_max=rng.uniform(s.gd_min + 1e-3, s.gd_max))
        lower_min = replace(s, gd_min=rng.uniform(s.gd_min / 2, s.gd_min))
        assert lower_max.command(e).speed <= s.command(e).speed, (s, lower_max.gd_max)
        assert lower_min.command(e).speed <= s.command(e).speed, (s, lower_min.gd_min)


def test_a_lower_v_max_never_commands_a_higher_speed():
    for rng, s, ld in cases(5, 300):
        e = estimate(ld)
        v_max = rng.uniform(s.v_safe, s.v_max)
        slower = replace(s, v_max=v_max, speed_step_mps=min(s.speed_step_mps, v_max))
        assert slower.command(e).speed <= s.command(e).speed, (s, v_max)


def test_a_lower_v_safe_never_commands_a_higher_speed_on_the_continuous_law():
    for rng, s, ld in cases(6, 300):
        s = replace(s, speed_step_mps=0.0)
        e = estimate(ld)
        slower = replace(s, v_safe=rng.uniform(0.05, s.v_safe))
        assert slower.command(e).speed <= s.command(e).speed, (s, slower.v_safe)


def ordered_sequences(rng: np.random.Generator, n: int = 40):
    """Twin estimate sequences at the same positions, the second pointwise rougher (or not ok
    where the first is): random walks of a normal posterior about the band, a few updates
    filling, stale, out of domain or faulted (the same in both)."""
    positions = np.cumsum(rng.uniform(0.2, 0.8, n))
    mu = rng.uniform(200, 500)
    smooth, rough = [], []
    for k, pos in enumerate(positions):
        mu = float(np.clip(mu + rng.normal(0, 30), 150, 650))
        ld = stats.norm.logpdf(GRID, mu, rng.uniform(10, 60))
        status = "filling" if k < 2 else "ok"
        if rng.random() < 0.04:
            status = str(rng.choice(["stale", "out_of_domain", "sensor_fault"]))
        if status != "ok":
            e = Estimate(time=pos, position=pos, status=status, reason="x")
            smooth.append(e)
            rough.append(e)
            continue
        smooth.append(estimate(ld, pos))
        if rng.random() < 0.05:
            rough.append(Estimate(time=pos, position=pos, status="stale", reason="x"))
        else:
            rough.append(estimate(rougher(rng, ld) if rng.random() < 0.5 else ld, pos))
    return smooth, rough


def speeds(s: Simplex, estimates) -> np.ndarray:
    run = s.start()
    return np.array([run.command(e).speed for e in estimates])


def test_simplex_run_twins_fed_ordered_estimates_never_differ_the_wrong_way():
    rng = np.random.default_rng(7)
    for i in range(80):
        s = replace(
            random_simplex(rng, LAWS[i % 2]),
            after_fault=str(rng.choice(["latch", "resume"])),
        )
        smooth, rough = ordered_sequences(rng)
        assert np.all(speeds(s, rough) <= speeds(s, smooth)), s


def test_with_the_dwell_ordered_twins_that_left_the_start_together_never_differ_wrongly():
    # Both twins' first ok estimate reads performance mode, so both leave the start's
    # dwell-free safety mode at the same update (the one documented exception lies before it).
    rng = np.random.default_rng(8)
    start = estimate(stats.norm.logpdf(GRID, 150.0, 5.0), 0.1)
    checked = 0
    for i in range(110):
        s = replace(random_simplex(rng, LAWS[i % 2]),
                    release_m=float(rng.choice([0.5, 2.0, 5.0])))  # fmt: skip
        if s.command(start).mode != "performance":
            continue
        smooth, rough = ordered_sequences(rng)
        assert np.all(speeds(s, [start, *rough]) <= speeds(s, [start, *smooth])), s
        checked += 1
    assert checked > 50


def test_a_longer_dwell_a_smaller_risk_or_a_lower_gd_max_never_drives_faster_over_a_run():
    rng = np.random.default_rng(9)
    for i in range(80):
        s = replace(random_simplex(rng, LAWS[i % 2]), release_m=float(rng.choice([0.0, 2.0])))
        smooth, _ = ordered_sequences(rng)
        base = speeds(s, smooth)
        longer = replace(s, release_m=s.release_m + rng.uniform(0.1, 10))
        assert np.all(speeds(longer, smooth) <= base), s
        if s.release_m == 0:  # (with the dwell, the start's exception applies to these too)
            lower = replace(s, gd_max=rng.uniform(s.gd_min + 1, s.gd_max))
            assert np.all(speeds(lower, smooth) <= base), (s, lower.gd_max)
            if s.risk is not None:
                cautious = replace(s, risk=s.risk * rng.uniform(0.05, 1.0))
                assert np.all(speeds(cautious, smooth) <= base), (s, cautious.risk)
