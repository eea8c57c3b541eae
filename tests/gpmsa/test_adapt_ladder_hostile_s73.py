"""The adaptive ladder in hostile cases (session 73 review): swap rates stuck at 0 for one
neighbour pair and 1 for the other drive a log gap down by ~20 ln(1 + rounds / 200); after
200 x 20 rounds the averaged ladder's rungs merged (1, 1, 4) or crossed the hottest
(1, 4.000000000000078, 4). The ladder returned must stay a ladder: 1, strictly increasing,
finite, the hottest unchanged (else the starting one stays)."""

import numpy as np
import pytest

from gpmsa.mcmc import tempering


class _Stuck:
    """A copy whose log-likelihood is set by its temperature alone (``loglik_at(beta)``)."""

    def __init__(self, loglik_at):
        self.beta, self.loglik_at, self.loglik = 1.0, loglik_at, 0.0

    def sweep(self, widths, prop_mh, accepted):
        self.loglik = self.loglik_at(self.beta)

    def exchange(self, other):
        self.loglik, other.loglik = other.loglik, self.loglik


def _adapt(start, loglik_at, n_rounds):
    states = [_Stuck(loglik_at) for _ in start]
    for s, t in zip(states, start, strict=True):
        s.beta = 1.0 / t
    out = tempering.adapt_ladder(states, start, np.random.default_rng(0), ["theta"],
                                 np.array([0.1]), n_rounds, 20, lambda n: None)  # fmt: skip
    return out, [s.beta for s in states]


@pytest.mark.parametrize(
    ("start", "loglik_at"),
    [((1.0, 2.0, 4.0), lambda b: 0.0 if b in (1.0, 0.25) else -1e30),  # rates 0, 1: rung 1 -> 1
     ((1.0, 2.0, 4.0), lambda b: -1e30 if b == 0.25 else 0.0),  # rates 1, 0: rung 1 -> 4
     ((1.0, 1 + 1e-12, 1 + 2e-12), lambda b: 0.0 if b in (1.0, 1 / (1 + 2e-12)) else -1e30)],
)  # fmt: skip
def test_adapted_ladder_stays_strictly_increasing(start, loglik_at):
    out, betas = _adapt(start, loglik_at, 200)
    assert out[0] == 1.0 and out[-1] == start[-1], out
    assert np.all(np.isfinite(out)) and np.all(np.diff(out) > 0), out
    assert betas == [1.0 / t for t in out]
