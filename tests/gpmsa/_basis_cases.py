"""The functional problem of the basis-continuation tests (a fit's and a study's): 20 runs on a
12-point grid, a discrepancy basis of three kernels in two groups."""

import functools

import numpy as np

import gpmsa

GRID = np.linspace(0.0, 1.0, 12)
D = np.exp(-((GRID[:, None] - np.array([0.1, 0.5, 0.9])) ** 2) / 0.05)
GROUPS = [0, 0, 1]


@functools.cache
def basis_sim() -> gpmsa.SimData:
    """20 runs of y(x, t) on ``GRID``."""
    rng = np.random.default_rng(1)
    x, t = rng.random((20, 1)), rng.random((20, 1))
    y = np.sin(3 * x + GRID) + t**2 * np.cos(2 * GRID) + 0.1 * t * GRID
    return gpmsa.SimData(x=x, t=t, y=y, x_names=["x"], t_names=["t"], index=GRID)


def basis_obs(shift: float = 0.0) -> gpmsa.ObsData:
    """Two observations at x = 0.2 and 0.7 (plus ``shift``) on ``GRID``."""
    xo = np.array([[0.2], [0.7]]) + shift
    return gpmsa.ObsData(x=xo, y=np.sin(3 * xo + GRID) + 0.16 * np.cos(2 * GRID), index=GRID)
