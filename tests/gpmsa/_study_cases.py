"""Shared cases for the study tests: a small scalar emulator of y = x exp(k t) and synthetic
observations from a known truth."""

from __future__ import annotations

from functools import cache

import numpy as np

import gpmsa

K = 1.5
"""The simulator's curvature in t: y = x exp(K t)."""


def simulator(x, t):
    return np.asarray(x) * np.exp(K * np.asarray(t))


def sim_data(t_lo: float = 0.0, t_hi: float = 1.0, t_name: str = "t") -> gpmsa.SimData:
    xg, tg = np.meshgrid(np.linspace(0.0, 1.0, 5), np.linspace(t_lo, t_hi, 7), indexing="ij")
    x, t = xg.reshape(-1, 1), tg.reshape(-1, 1)
    return gpmsa.SimData(x=x, t=t, y=simulator(x, t), x_names=["x"], t_names=[t_name])


PARAMS = {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [1000.0], "lamWOs": [1000.0]}


@cache
def emulator(priors: gpmsa.Priors | None = None, t_lo: float = 0.0, t_hi: float = 1.0,
             t_name: str = "t", lam_w: float = 1000.0) -> gpmsa.Emulator:  # fmt: skip
    """The emulator at fixed parameters; ``lam_w``: its lamWs and lamWOs (1e5 - 1: a nugget so
    small that the emulator is in effect the simulator, for checks of interval coverage)."""
    params = {**PARAMS, "lamWs": [lam_w], "lamWOs": [lam_w]}
    return gpmsa.Emulator.from_params(sim_data(t_lo, t_hi, t_name), params, priors)


EXACT = 1e5 - 1.0
"""``lam_w`` of an emulator whose nugget is negligible."""


def observations(theta: float, n: int, sd: float, rng: np.random.Generator):
    x = np.linspace(0.1, 0.9, n)[:, None]
    return x, simulator(x, theta) + sd * rng.standard_normal((n, 1))


def two_model_study(n_samples: int, n_burn: int, tune_rounds: int) -> gpmsa.Study:
    """Models "a" and "b" (theta 0.35 and 0.5, three observations each, sd 0.03) sharing a
    hierarchical t: a small study to save and read back."""
    rng = np.random.default_rng(4)
    data = [observations(th, 3, 0.03, rng) for th in (0.35, 0.5)]
    return gpmsa.calibrate_study(
        [emulator(None)] * 2, [d[0] for d in data], [d[1] for d in data], labels=["a", "b"],
        hierarchical=["t"], n_samples=n_samples, n_burn=n_burn, seed=5, tune_rounds=tune_rounds,
    )  # fmt: skip
