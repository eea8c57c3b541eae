"""Chains' starts are drawn and checked in the parent process, before any chain is launched:
a start where a prior has no density is a plain GPMSAError, not a ChainError from a worker."""

import numpy as np
import pytest

import gpmsa
from gpmsa.mcmc import sampler, starts
from gpmsa.model.priors import GammaPrior, Priors


def _problem(**priors):
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(25, 1)), rng.uniform(size=(25, 1))
    data = gpmsa.SimData(x=x, t=t, y=x + t, x_names=["x"], t_names=["t"])
    return gpmsa.prepare(data, priors=Priors(**priors)).problem


@pytest.mark.parametrize("n_jobs", [1, 2])
def test_an_unreachable_jitter_start_is_a_plain_gpmsa_error_before_any_chain(n_jobs, monkeypatch):
    """A start outside lamWs's bounds (1e4, 1e5) (once GPM/SA's 1000 under "jitter", which now
    starts inside them; here a given one): before, 'ChainError: chain 0 of 2 failed:
    GPMSAError: ...' raised in a worker; now the GPMSAError itself, no chain run."""
    problem = _problem(lamWs=GammaPrior(1.0, 0.0025, 1e4, 1e5))

    def launched(*args, **kwargs):
        raise AssertionError("a chain was launched")

    monkeypatch.setattr(sampler, "run_chains", launched)
    given = {"lamWs": np.full((2, problem.p_u), 1000.0)}
    with pytest.raises(gpmsa.GPMSAError, match="lamWs .* outside the bounds") as info:
        sampler.sample(problem, n_iter=5, n_chains=2, init=given, seed=0, n_jobs=n_jobs)
    assert type(info.value) is gpmsa.GPMSAError


def test_the_starts_drawn_in_the_parent_are_the_chains_starts():
    """The chains start where ``draw_start`` puts them on their own start generator (the same
    values as when the worker drew them)."""
    problem = _problem()
    chains = sampler.sample(problem, n_iter=3, n_chains=2, init="prior", seed=4, tune=False,
                            n_jobs=1)  # fmt: skip
    for c, s in enumerate(np.random.SeedSequence(4).spawn(2)):
        want = starts.draw_start(problem, "prior", starts.start_generator(s))
        for name in problem.names:
            np.testing.assert_array_equal(chains.info["starts"][name][c], want[name])
