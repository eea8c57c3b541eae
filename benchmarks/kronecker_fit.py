"""Seconds per GPM/SA sweep, dense vs Kronecker likelihood, on separable designs (numpy backend).

A design of nx points in x times nt in t (m = nx * nt runs, scalar output) declared separable
(``SimData(separable=True)``) samples through the factors' eigendecompositions
(``gpmsa.model.kronecker``); the same problem without the declaration factors the dense m x m
Sigma_W at every betaU, lamUz and lamWs proposal. Prints the CPU time per sweep of each (the
same proposals: the same seed draws the same chain), their ratio, and the load average.

    PYTHONPATH=. python benchmarks/kronecker_fit.py [N_SWEEPS]    # default 3 sweeps per size
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import time

import numpy as np
from _host import load_average
from threadpoolctl import threadpool_limits

import gpmsa
from gpmsa.mcmc.sampler import ChainState, default_widths, elements
from gpmsa.model.problem import prepare

SIZES = ((20, 25), (25, 40), (40, 50))
"""(nx, nt): m = 500, 1,000 and 2,000 runs."""


def separable_problem(nx: int, nt: int):
    rng = np.random.default_rng(0)
    xs, ts = np.linspace(0.0, 1.0, nx), np.sort(rng.random(nt))
    x, t = np.repeat(xs, nt)[:, None], np.tile(ts, nx)[:, None]
    y = np.sin(3 * x) + t**2 + 0.01 * rng.standard_normal(x.shape)
    return prepare(gpmsa.SimData(x=x, t=t, y=y, separable=True)).problem


def sweep_cpu(problem, n_sweeps: int) -> float:
    """CPU seconds per sweep (one BLAS thread), GPM/SA's default widths, seed 1."""
    state = ChainState(problem, problem.init, np.random.default_rng(1))
    widths = default_widths(problem)
    w = np.array([widths[n][i] for n, i in elements(problem)])
    acc = np.zeros(len(w))
    with threadpool_limits(1):
        c0 = time.process_time()
        for _ in range(n_sweeps):
            state.sweep(w, True, acc)
        return (time.process_time() - c0) / n_sweeps


def main(n_sweeps: int = 3) -> None:
    print(f"load average {load_average()[0]:.2f} on {os.cpu_count()} cores; 1 BLAS thread; "
          f"{n_sweeps} sweeps each; CPU seconds per sweep")  # fmt: skip
    for nx, nt in SIZES:
        kron = separable_problem(nx, nt)
        dense = dataclasses.replace(kron, separable=None)
        t_kron = sweep_cpu(kron, max(n_sweeps, 20))
        t_dense = sweep_cpu(dense, n_sweeps)
        print(f"m = {nx * nt:5d} ({nx} x {nt}): dense {t_dense:8.4f} s, Kronecker "
              f"{t_kron:8.5f} s, ratio {t_dense / t_kron:7.0f}; load average "
              f"{load_average()[0]:.2f}")  # fmt: skip


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("n_sweeps", nargs="?", type=int, default=3,
                        help="timed sweeps per size and likelihood (default 3)")  # fmt: skip
    main(parser.parse_args().n_sweeps)
