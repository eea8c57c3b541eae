"""Shared case for the sensitivity tests: an emulator with a categorical input at fixed
parameters."""

from __future__ import annotations

import numpy as np

import gpmsa


def categorical_emulator(mean_basis):
    """3 inputs (x continuous, kind categorical with levels 0, 1, 3, a continuous), a
    functional output of 4 elements and 3 components, at fixed parameters."""
    rng = np.random.default_rng(5)
    m, s = 45, np.linspace(0, 1, 4)
    x = np.column_stack([rng.uniform(0, 2, m), rng.choice([0, 1, 3], m)])
    t = rng.uniform(-1, 1, (m, 1))
    y = (np.sin(2 * x[:, :1]) * (1 + s) + 0.5 * np.outer(x[:, 1], s)
         + np.outer(t[:, 0] ** 2 + 0.3 * t[:, 0] * x[:, 1], 1 - s))  # fmt: skip
    data = gpmsa.SimData(x=x, t=t, y=y, index=s, x_names=["x", "kind"], t_names=["a"],
                         x_categorical=["kind"])  # fmt: skip
    params = {"betaU": np.array([[2.0, 3, 1], [1.0, 0.5, 2], [1.5, 2, 3]]), "lamUz": [1, 2, 3],
              "lamWs": [1e4] * 3, "lamWOs": [1e4]}  # fmt: skip
    return gpmsa.Emulator.from_params(data, params, n_pc=3, mean_basis=mean_basis)
