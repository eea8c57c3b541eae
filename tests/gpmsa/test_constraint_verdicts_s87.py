"""A constraint (or a callable prior's zeros) that answers both ways at one theta: the grid
Calibrator's bisection meets it and names it, instead of failing later on a grid of repeated
nodes ("a grid marginal's nodes must be finite and strictly increasing")."""

from functools import cache

import numpy as np
import pytest

import gpmsa
from gpmsa.errors import GPMSAError


@cache
def _emulator() -> gpmsa.Emulator:
    rng = np.random.default_rng(0)
    x, t = rng.uniform(0, 1, 30), rng.uniform(0, 1, 30)
    sim = gpmsa.SimData(x=x[:, None], t=t[:, None], y=(np.sin(3 * t) + x)[:, None])
    params = {"betaU": [[1.0, 1.0]], "lamUz": [1.0], "lamWs": [5e3], "lamWOs": [5e3]}
    return gpmsa.Emulator.from_params(sim, params, n_pc=1)


OBS = gpmsa.ObsData(x=np.array([[0.5]]), y=np.array([[np.sin(1.5) + 0.5]]), precision=400.0)


def test_a_constraint_with_random_answers_is_named():
    rng = np.random.default_rng(1)

    def flaky(th):
        return bool(rng.uniform() < 0.5) or th[0] < 0.3

    with pytest.raises(GPMSAError, match=r"the constraint .* gave both answers at t0 = "):
        cal = gpmsa.Calibrator(_emulator(), seed=0, constraint=flaky)
        cal.update(OBS)  # (found by the first bisection: the Calibrator's fixed grid's)


def test_a_prior_with_random_zeros_is_named():
    rng = np.random.default_rng(1)

    def prior(th):
        return np.where((rng.uniform(size=th.shape[0]) < 0.5) | (th < 0.3), 0.0, -np.inf)

    with pytest.raises(GPMSAError, match=r"the prior \(zero and not\) gave both answers at t0"):
        gpmsa.Calibrator(_emulator(), seed=0).update(OBS, prior=prior)


@pytest.mark.parametrize("edge", [0.3, 0.323, 0.5, 0.91])
def test_a_deterministic_constraint_still_cuts_at_its_edge(edge):
    cal = gpmsa.Calibrator(_emulator(), seed=0, constraint=lambda th: th[0] < edge)
    post = cal.update(OBS)
    assert post.samples["t0"].max() < edge
    assert post.grids["t0"].cdf(edge) == pytest.approx(1.0, abs=1e-12)
