"""The three-parameter functional problem of the outside-the-emulator tests (session 69): 40
output values a run, one x, an emulator at fixed parameters (no fit)."""

import numpy as np

import gpmsa

GRID = np.linspace(0.0, 1.0, 40)
X_OBS = np.array([[0.2], [0.5], [0.8]])
PARAMS = {"betaU": np.full((4, 3), 0.15), "lamUz": np.full(3, 0.33),
          "lamWs": np.full(3, 5e3), "lamWOs": np.array([1e5])}  # fmt: skip


def simulator(x: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Outputs (n, 40) at inputs x (n,) and parameters t (n, 3), linear in t."""
    return (1 + x)[:, None] * (t[:, [0]] * np.sin(3 * GRID) + t[:, [1]] * GRID**2) + t[
        :, [2]
    ] * np.cos(2 * GRID)


def three_parameter_emulator(corners: bool = False) -> gpmsa.Emulator:
    """60 runs (seed 7); ``corners``: the first two at the design's corners."""
    rng = np.random.default_rng(7)
    x = rng.uniform(size=60)
    t = rng.uniform(size=(60, 3))
    if corners:
        x[:2], t[:2] = [0.0, 1.0], [[0.0] * 3, [1.0] * 3]
    sim = gpmsa.SimData(x=x, t=t, y=simulator(x, t), index=GRID)
    return gpmsa.Emulator.from_params(sim, PARAMS)
