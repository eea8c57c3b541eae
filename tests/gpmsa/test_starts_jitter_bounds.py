"""Dispersed ("jitter") starts of a precision whose prior bounds its jitter range cannot reach,
or bounds narrower than the jitter's margins."""

import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.mcmc import starts
from gpmsa.model.priors import GammaPrior, Priors


def _data():
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(25, 1)), rng.uniform(size=(25, 1))
    return gpmsa.SimData(x=x, t=t, y=x + t, x_names=["x"], t_names=["t"])


def _problem(**priors):
    return gpmsa.prepare(_data(), priors=Priors(**priors)).problem


def _jitter(problem):
    seq = np.random.SeedSequence(3)
    return starts.draw_start(problem, "jitter", starts.start_generator(seq))


@pytest.mark.parametrize("bounds", [(1e4, 1e5), (0.5, 2.0)])
def test_a_jitter_range_outside_the_prior_bounds_centres_on_the_priors_median(bounds):
    """lamWs starts at 1000; its jitter [100, 10000] missed bounds (1e4, 1e5): numpy's bare
    'ValueError: high - low < 0' once, then a GPMSAError ('cannot reach the bounds'); now the
    jitter centres on the prior's median inside the bounds (``starts.default_start``)."""
    problem = _problem(lamWs=GammaPrior(1.0, 0.0025, *bounds))
    start = _jitter(problem)
    assert bounds[0] < start["lamWs"][0] < bounds[1]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)  # chains of 8 draws
        emu = gpmsa.fit(
            _data(),
            n_iter=10,
            tune=False,
            seed=0,
            n_chains=2,
            n_jobs=1,
            priors=Priors(lamWs=GammaPrior(1.0, 0.0025, *bounds)),
            init="jitter",
        )
    assert np.all((emu.draws["lamWs"] > bounds[0]) & (emu.draws["lamWs"] < bounds[1]))


def test_bounds_narrower_than_the_jitter_margins_start_at_the_gpmsa_value():
    """lamUz starts at 1 inside bounds (0.9995, 1.0005), narrower than the 1e-3 margins of the
    cut: the jitter range was empty (a crash); it starts at GPM/SA's value, inside the prior."""
    problem = _problem(lamUz=GammaPrior(5.0, 5.0, 0.9995, 1.0005))
    start = _jitter(problem)
    assert start["lamUz"].tolist() == problem.init["lamUz"].tolist()
    assert np.isfinite(problem.priors.log_prior("lamUz", start["lamUz"]))


def test_jitter_starts_inside_reachable_bounds_are_unchanged():
    """Where the cut is not empty the start is drawn as before (the same numbers)."""
    problem = _problem(lamWs=GammaPrior(1.0, 0.0025, 2000.0, 3000.0))
    a, b = _jitter(problem), _jitter(problem)
    assert 2000.0 < a["lamWs"][0] < 3000.0 and a["lamWs"][0] == b["lamWs"][0]
