"""Shared cases for the prediction, sensitivity and cross-validation tests."""

from __future__ import annotations

import warnings
from functools import cache

import numpy as np
from scipy.stats import qmc

import gpmsa

GRID = np.linspace(0.0, 1.0, 12)
T_TRUE = 1.2
NOISE_SD = 0.02


@cache
def vector_fit() -> gpmsa.Emulator:
    """A functional-output emulator (l_sim = 10, p_u = 2) fitted by MCMC: it has draws."""
    rng = np.random.default_rng(11)
    m = 36
    x = rng.uniform(0.0, 2.0, (m, 1))
    t = rng.uniform(-1.0, 1.0, (m, 1))
    s = np.linspace(0.0, 1.0, 10)
    y = np.sin(2.0 * x) * (1.0 + s) + np.outer(t[:, 0] ** 2 + 0.3 * t[:, 0], s**2)
    data = gpmsa.SimData(x=x, t=t, y=y, index=s, x_names=["x"], t_names=["t"])
    return gpmsa.fit(data, n_iter=300, seed=3, n_pc=2, tune_rounds=10)


def known_truth_sim(x: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The simulator of the known-truth case: exp(-t (1 + x / 2) s) on GRID, rows per (x, t)."""
    return np.exp(-np.outer(t * (1.0 + 0.5 * x), GRID))


def known_truth_discrepancy(x: np.ndarray) -> np.ndarray:
    """The real world's extra term: linear in the output index s, so "linear" spans it."""
    return 0.1 * (1.0 + x)[:, None] - 0.15 * np.outer(x, GRID)


def known_truth_world(x: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Noisy observations of the real world at x (one row per x)."""
    x = np.asarray(x, dtype=float)
    truth = known_truth_sim(x, np.full(x.size, T_TRUE)) + known_truth_discrepancy(x)
    return truth + NOISE_SD * rng.standard_normal(truth.shape)


def known_truth_case(seed: int = 0):
    """A joint fit of a simulator with a known discrepancy and noise, and 60 held-out points.

    Returns (emulator, obs, x_new (60, 1), y_new (60, 12) noisy held-out observations).
    """
    return _known_truth_case(seed)  # one cache entry for ``()`` and ``(0)``


@cache
def _known_truth_case(seed: int):
    """`known_truth_case`, computed once a seed."""
    rng = np.random.default_rng(seed)
    d = qmc.LatinHypercube(2, seed=seed).random(40)
    x, t = d[:, 0], 0.5 + 1.5 * d[:, 1]
    data = gpmsa.SimData(x=x[:, None], t=t[:, None], y=known_truth_sim(x, t), index=GRID,
                         x_names=["x"], t_names=["t"])  # fmt: skip
    xo = np.linspace(0.05, 0.95, 12)
    obs = gpmsa.ObsData(x=xo[:, None], y=known_truth_world(xo, rng), index=GRID)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a few observations near the design's edge
        emu = gpmsa.fit(data, obs, n_iter=1500, seed=seed, discrepancy="linear")
    x_new = np.linspace(0.05, 0.95, 60)
    return emu, obs, x_new[:, None], known_truth_world(x_new, rng)


def mc_z(samples: np.ndarray, mean: np.ndarray, var: np.ndarray) -> tuple[float, float]:
    """Largest |z| of the sample mean and the sample variance (axis 0) against exact moments.

    The standard errors are the Monte-Carlo ones estimated from the samples themselves:
    sd / sqrt(n) for the mean, sqrt(m4 - s^4) / sqrt(n) for the variance (m4: fourth central
    moment), valid for any distribution with finite fourth moment, mixtures included. Elements
    whose exact variance is 0 (e.g. an output fixed by construction) must be constant in the
    samples and equal to the mean; they are left out of the z-scores.
    """
    n = samples.shape[0]
    live = var > 1e-12 * var.max()
    dead_err = np.abs(samples - mean)[:, ~live]
    assert dead_err.size == 0 or dead_err.max() < 1e-9 * max(1.0, np.abs(mean).max())
    samples, mean, var = samples[:, live], mean[live], var[live]
    centred = samples - samples.mean(axis=0)
    s2 = np.mean(centred**2, axis=0)
    m4 = np.mean(centred**4, axis=0)
    z_mean = (samples.mean(axis=0) - mean) / np.sqrt(var / n)
    z_var = (s2 * n / (n - 1) - var) / np.sqrt((m4 - s2**2) / n)
    return float(np.max(np.abs(z_mean))), float(np.max(np.abs(z_var)))


def three_input_emulator() -> gpmsa.Emulator:
    """An emulator of 150 runs over one x and two thetas at fixed parameters (no fit): the
    sensitivity memory tests' case."""
    rng = np.random.default_rng(3)
    xt = rng.uniform(size=(150, 3))
    data = gpmsa.SimData(x=xt[:, :1], t=xt[:, 1:], y=np.sin(3 * xt[:, :1]) + xt[:, 1:2] ** 2,
                         x_names=["x"], t_names=["a", "b"])  # fmt: skip
    prm = {"betaU": [[1.0], [2.0], [0.5]], "lamUz": [1.0], "lamWs": [1e3], "lamWOs": [1e3]}
    return gpmsa.Emulator.from_params(data, prm)


def four_run_data() -> gpmsa.SimData:
    """Four runs of one output, one x and one t: the exact prediction tests' tiny design."""
    x = np.array([[0.0], [0.5], [1.0], [0.25]])
    t = np.array([[0.0], [1.0], [0.5], [0.75]])
    y = np.array([[1.0], [3.0], [2.0], [2.5]])
    return gpmsa.SimData(x=x, t=t, y=y, x_names=["x"], t_names=["t"])


def four_run_emulator() -> gpmsa.Emulator:
    """`four_run_data`'s emulator (K = [[1]], lam_sim = 1) at fixed parameters."""
    prm = {"betaU": [[1.0], [2.0]], "lamUz": [2.0], "lamWs": [10.0], "lamWOs": [50.0]}
    return gpmsa.Emulator.from_params(four_run_data(), prm)
