"""A categorical theta's level reaches a user's constraint and callable prior exactly (session 73:
with 24 levels the unit scale's round trip gave 12.999999999999998 for 13, so
``lambda th: th[0] != 13`` and a prior of -inf at 13 were silently ignored: the Calibrator's
grid put 0.9997 of the mass at 13, ``calibrate`` every draw; ``calibrate(fast=False)``'s draws
were not the level codes)."""

from __future__ import annotations

import warnings
from functools import cache

import numpy as np

import gpmsa


@cache
def _case():
    rng = np.random.default_rng(0)
    m = 48
    x = rng.random((m, 1))
    kind = np.arange(m) % 24
    y = np.sin(3 * x[:, 0]) + 0.05 * kind
    sim = gpmsa.SimData(x, kind[:, None], y, x_names=["s"], t_names=["kind"],
                        t_categorical=["kind"])  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = gpmsa.fit(sim, n_iter=80, seed=0)
    xo = np.linspace(0.1, 0.9, 5)[:, None]
    return emu, xo, np.sin(3 * xo[:, 0]) + 0.05 * 13


def _not_13(th) -> bool:
    return bool(th[0] != 13)


def test_the_constraint_and_the_prior_see_the_exact_level_on_the_grid():
    emu, xo, yo = _case()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        post = gpmsa.Calibrator(emu, constraint=_not_13).update(xo, yo)
        assert post.grids["kind"].probabilities()[13.0] == 0.0
        seen = []

        def prior(th):
            seen.extend(np.ravel(th))
            return np.where(np.asarray(th) == 13, -np.inf, 0.0)

        post = gpmsa.Calibrator(emu).update(xo, yo, prior=prior)
    assert post.grids["kind"].probabilities()[13.0] == 0.0
    assert set(seen) == set(map(float, range(24)))  # exactly the codes


def test_calibrate_honours_the_constraint_and_draws_the_codes():
    emu, xo, yo = _case()
    for fast in (True, False):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            post = gpmsa.calibrate(emu, xo, yo, constraint=_not_13, n_samples=300, n_burn=50,
                                   n_chains=1, seed=1, fast=fast)  # fmt: skip
        kind = post.samples["kind"]
        assert not np.any(kind == 13), fast
        assert set(np.unique(kind)) <= set(map(float, range(24))), fast
