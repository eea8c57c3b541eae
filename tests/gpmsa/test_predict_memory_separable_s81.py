"""A separable (Kronecker) emulator's prediction never forms a (points, m) array: its memory
check counts the factors' correlations and the contraction, not points x m (a 40 x 50 design
at 100,000 points was refused at 5.97 GiB and needs about 0.2 GB; the review of the blocked
predictions, session 81)."""

from __future__ import annotations

import tracemalloc
from functools import cache

import numpy as np

import gpmsa
import gpmsa.fitting.emulator as emulator_mod
from gpmsa.fitting.emulator import Emulator


@cache
def _separable() -> Emulator:
    """A 40 x 50 separable design (m = 2,000 runs) at fixed parameters."""
    x, t = (g.ravel() for g in np.meshgrid(np.linspace(0, 1, 40), np.linspace(0, 1, 50),
                                           indexing="ij"))  # fmt: skip
    sim = gpmsa.SimData(x=x[:, None], t=t[:, None], y=(np.sin(3 * x) + t)[:, None],
                        separable=[[0], [1]])  # fmt: skip
    params = {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [1e3], "lamWOs": [1e3]}
    return Emulator.from_params(sim, params)


def _estimate(monkeypatch, emu: Emulator, n: int) -> float:
    """The bytes the memory check estimates for a prediction at n points."""
    seen = []
    monkeypatch.setattr(emulator_mod, "check_memory", lambda nbytes, what: seen.append(nbytes))
    emu._check_predict_memory(np.zeros((n, 1)), np.zeros((n, 1)))
    monkeypatch.undo()
    return seen[0]


def test_a_separable_prediction_at_many_points_is_not_refused():
    emu = _separable()
    assert emu.separable is not None and emu.m == 2000
    n = 100_000
    emu._check_predict_memory(np.zeros((n, 1)), np.zeros((n, 1)))  # under the default 4 GiB


def test_the_separable_estimate_covers_the_prediction(monkeypatch):
    emu = _separable()
    n = 20_000
    estimate = _estimate(monkeypatch, emu, n)
    rng = np.random.default_rng(0)
    x, t = rng.random((n, 1)), rng.random((n, 1))
    emu.predict(x[:2], t[:2])  # the factors' cache, outside the measured call
    tracemalloc.start()
    try:
        emu.predict(x, t)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak <= estimate <= 4 * peak, (peak, estimate)
    assert estimate < 8.0 * 4 * n * emu.m / 10  # far below points x m
