"""A stand-in block-feature emulator for the Simplex reach checks (`control.compat`)."""

from types import SimpleNamespace

import numpy as np

from control.observation_model import BlockScatter


def block_emulator(feature_sd: float = 0.5, calls: list | None = None):
    """A stand-in block-feature emulator on GD [200, 600], speeds [0.5, 2] m/s: its feature is
    GD / 100 with sd ``feature_sd`` (the likelihood's sd in GD: 100 ``feature_sd``)."""

    def predict_mean(v, gd):
        if calls is not None:
            calls.append(len(gd))
        return np.asarray(gd, dtype=float)[:, None] / 100.0

    scatter = BlockScatter(np.array([0.5, 2.0]), np.full((2, 1, 1), feature_sd**2))
    return SimpleNamespace(
        domain={"v": (0.5, 2.0), "GD": (200.0, 600.0)},
        x_names=["v"],
        t_names=["GD"],
        metadata={"block_scatter": scatter.to_dict()},
        predict_mean=predict_mean,
    )
