"""Review of the torch hot-copies commit (session 76): a float32 torch fit's categorical theta.

A torch ``dtype="float32"`` fit samples a categorical theta at its levels rounded to float32
(unit level 1/3 is 0.3333333432674408 there); its draws and its hot copies' record hold those
values in float64, off the level, where the theta prior has no mass. Its continuation (default:
every hot copy resumed, on either backend) refused the record ("lies outside the support of
the theta prior") whenever a hot copy sat at such a level, where before the record existed it
re-tuned and ran; a chain whose last kept draw sat there was refused the same way, tempered or
not. The continuation now puts a value that equals a level in float32 back on that level.
"""

import warnings

import numpy as np
import pytest

import gpmsa

pytest.importorskip("gpmsa.backends.torch_backend")

SMALL = {"tune_rounds": 1, "tune_levels": 2, "warmup": 2, "tune_stages": 1}


def _case() -> tuple[gpmsa.SimData, gpmsa.ObsData]:
    """t = (k, level in 0..3): unit levels 0, 1/3, 2/3, 1 (1/3 and 2/3 inexact in float32)."""
    rng = np.random.default_rng(0)
    x = rng.random((24, 1))
    t = np.column_stack([rng.random(24), np.arange(24) % 4])
    y = np.column_stack([np.sin(3 * x[:, 0] + t[:, 0]) + 0.5 * t[:, 1] + 0.1 * k * x[:, 0]
                         for k in range(5)])  # fmt: skip
    sim = gpmsa.SimData(x, t, y, t_categorical=[1], index=np.linspace(0, 1, 5))
    return sim, gpmsa.ObsData(x=np.array([[0.3], [0.7]]), y=y[:2] + 0.01)


def _fit(backend="torch", **kw):
    sim, obs = _case()
    where = {"n_jobs": 1} if backend == "numpy" else {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gpmsa.fit(sim, obs, backend=backend, n_pc=2, n_chains=2, **where, **kw)


def _levels(values) -> set:
    return {float(v) for v in np.ravel(values)}


def test_a_float32_fits_hot_copies_off_a_level_in_float64_are_resumed_at_it():
    src = _fit(n_iter=20, seed=3, temperatures=3, dtype="float32", **SMALL)
    hot = np.array(src.settings["hot_states"]["theta"])[..., 1]
    assert float(np.float32(1 / 3)) in _levels(hot)  # a hot copy at level 1/3, rounded
    for backend, kw in (("numpy", {}), ("torch", {}), ("torch", {"dtype": "float32"})):
        more = _fit(backend, n_iter=10, seed=4, init=src, **kw)  # refused before
        assert more.settings["tune"] is False, (backend, kw)  # every copy resumed
        resumed = np.array(more.settings["hot_states"]["theta"])[..., 1]
        assert _levels(resumed) <= {0.0, 1 / 3, 2 / 3, 1.0} | _levels(np.float32([1 / 3, 2 / 3]))


def test_a_float32_fits_last_draw_off_a_level_in_float64_is_continued_from_it():
    src = _fit(n_iter=20, seed=3, dtype="float32", **SMALL)  # untempered
    last = src.calibration["theta"][[9, 19], 1]  # each chain's last kept draw (10 a chain)
    assert float(np.float32(1 / 3)) in _levels(last)
    more = _fit("numpy", n_iter=10, seed=4, init=src)  # refused before
    assert _levels(more.calibration["theta"][:, 1]) <= {0.0, 1 / 3, 2 / 3, 1.0}
