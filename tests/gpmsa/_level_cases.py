"""Shared case for a categorical theta that trades off with a continuous one: y = sin(3x) + k +
0.5 kind, observed at k = 0.4, kind = 1 (kind 0 at k = 0.9 fits alike; a brute-force grid gives
P(kind) = 0.717 / 0.283 / 0)."""

from __future__ import annotations

from functools import cache

import numpy as np

import gpmsa


def level_function(x: np.ndarray, t: np.ndarray) -> np.ndarray:
    """y (n,) at x (n, 1) and t (n, 2) = (k, kind)."""
    return np.sin(3 * x[:, 0]) + t[:, 0] + 0.5 * t[:, 1]


def level_sim(rng: np.random.Generator, m: int) -> gpmsa.SimData:
    """The case's design of ``m`` runs (x, k from ``rng``; kind cycling over 0, 1, 2)."""
    x = rng.random((m, 1))
    t = np.column_stack([rng.random(m), np.arange(m) % 3])
    return gpmsa.SimData(x, t, level_function(x, t), x_names=["s"], t_names=["k", "kind"],
                         t_categorical=["kind"])  # fmt: skip


def three_theta_case(rng: np.random.Generator) -> tuple:
    """(sim, obs): theta (a, b, kind), kind in {0, 1}, 30 runs; 5 observations at a + b = 0.9
    (a constraint a + b < 1.2 leaves the truth inside), from ``rng``."""
    m = 30
    x = rng.random((m, 1))
    t = np.column_stack([rng.random(m), rng.random(m), np.arange(m) % 2])
    y = np.sin(3 * x[:, :1]) + t[:, :1] + 0.3 * t[:, 1:2] + 0.5 * t[:, 2:]
    sim = gpmsa.SimData(x, t, y, t_names=["a", "b", "kind"], t_categorical=["kind"])
    xo = np.linspace(0.1, 0.9, 5)[:, None]
    obs = gpmsa.ObsData(x=xo, y=np.sin(3 * xo) + 0.4 + 0.5 + 0.02 * rng.standard_normal((5, 1)))
    return sim, obs


@cache
def level_case() -> tuple:
    """(sim, emulator, x_obs (6, 1), y_obs (6,)): 60 runs, kind in {0, 1, 2}, a 600-sweep fit."""
    rng = np.random.default_rng(2)
    sim = level_sim(rng, 60)
    emu = gpmsa.fit(sim, n_iter=600, seed=0)
    xo = np.linspace(0.1, 0.9, 6)[:, None]
    truth = np.column_stack([np.full(6, 0.4), np.full(6, 1)])
    yo = level_function(xo, truth) + rng.normal(0, 0.05, 6)
    return sim, emu, xo, yo
