"""Milliseconds per GPM/SA sweep on the road case (198 runs, scalar output), numpy backend.

Prints the median over repeats for the sim-only and the sim+obs model and the extrapolated time
of a 30,000-sweep fit (plus 1,000 tuning sweeps), each with its ratio to this run's baseline: the
CPU time of one 198 x 198 Cholesky factorisation (LAPACK's dpotrf, as the sampler calls it, one
thread; a sweep's floor is about five of them, docs/internals.md), and the load average before
and after.

    PYTHONPATH=. python benchmarks/fit_speed.py [REPEATS]    # default 15 repeats of 200 sweeps

About 9 s at the default (README.md's figures), 3 s with ``1``.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np
from _host import load_average
from scipy.linalg import lapack
from threadpoolctl import threadpool_limits

import gpmsa
from gpmsa.mcmc.sampler import ChainState, elements, sample
from gpmsa.model.problem import prepare

CASE = Path(__file__).parents[1] / "tests" / "data" / "case.npz"


def sweep_ms(problem, repeats: int, n_sweeps: int = 200) -> tuple[float, float, float]:
    """ms per sweep: median wall clock, median and best process CPU time over ``repeats``.

    Step widths come from a short tuning run. On a shared machine the CPU time is the steadier
    figure (it excludes time spent waiting for a core); the best repeat is the least disturbed.
    """
    tuned = sample(problem, n_iter=10, seed=0, tune_rounds=10)
    widths = {k: v[0] for k, v in tuned.step_widths.items()}
    start = problem.with_init({k: v[0, -1] for k, v in tuned.draws.items()})
    state = ChainState(start, start.init, np.random.default_rng(1))
    w = np.array([widths[n][i] for n, i in elements(start)])
    acc = np.zeros(len(w))
    wall, cpu = [], []
    with threadpool_limits(1):
        for _ in range(repeats):
            t0, c0 = time.perf_counter(), time.process_time()
            for _ in range(n_sweeps):
                state.sweep(w, False, acc)
            wall.append((time.perf_counter() - t0) / n_sweeps * 1e3)
            cpu.append((time.process_time() - c0) / n_sweeps * 1e3)
    return float(np.median(wall)), float(np.median(cpu)), float(np.min(cpu))


def cholesky_ms(m: int, repeats: int, n_calls: int = 200) -> float:
    """The baseline: median CPU ms of one m x m Cholesky (LAPACK's dpotrf, the sampler's, one
    BLAS thread) over ``repeats`` batches of ``n_calls``, on a fixed SPD matrix (seed 0)."""
    a = np.random.default_rng(0).standard_normal((m, m))
    spd = a @ a.T + m * np.eye(m)
    times = []
    with threadpool_limits(1):
        lapack.dpotrf(spd, lower=1, clean=0)
        for _ in range(repeats):
            c0 = time.process_time()
            for _ in range(n_calls):
                lapack.dpotrf(spd, lower=1, clean=0)
            times.append((time.process_time() - c0) / n_calls * 1e3)
    return float(np.median(times))


def main(repeats: int = 15) -> None:
    d = np.load(CASE)
    sim = gpmsa.SimData(x=d["v"], t=d["GD"], y=d["f"])
    obs = gpmsa.ObsData(x=d["v_obs"][:, None], y=d["f_obs"][:, None])
    print(f"road case: m={sim.m}, scalar output; load average {load_average()[0]:.2f} "
          f"on {os.cpu_count()} cores; 1 BLAS thread")  # fmt: skip
    chol = cholesky_ms(sim.m, repeats)
    print(f"baseline: one {sim.m} x {sim.m} Cholesky {chol:.4f} ms CPU (median of {repeats})")
    for label, prob in (("sim-only", prepare(sim).problem), ("sim+obs", prepare(sim, obs).problem)):
        wall, cpu, best = sweep_ms(prob, repeats)
        print(
            f"{label:9s} {wall:6.3f} ms/sweep wall, {cpu:6.3f} ms CPU (medians of {repeats}), "
            f"best {best:.3f} ms CPU; CPU / baseline {cpu / chol:5.2f}; 30,000 sweeps + 1,000 "
            f"tuning ~ {31 * wall:5.1f} s wall, {31 * cpu:5.1f} s CPU"
        )
    print(f"load average after: {load_average()[0]:.2f}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("repeats", nargs="?", type=int, default=15, help="repeats of 200 sweeps")
    args = parser.parse_args()
    if args.repeats < 1:
        parser.error(f"repeats must be >= 1, got {args.repeats}")
    main(args.repeats)
