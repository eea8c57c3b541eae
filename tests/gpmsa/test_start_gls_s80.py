"""A chain's start at log-likelihood -inf whose Sigma_W factors is no nugget refusal.

``ChainState.check_start`` refuses a start whose Sigma_W does not factor in float64, naming
the nugget (`gpmsa.model.nugget`). A component also fails where Sigma_W factors but its mean
basis's GLS term (H' Sigma_W^-1 H) does not: a callable basis of nearly collinear columns,
which ``check_rank`` accepts (condition number 2e12 on 40 runs), ran before from GPM/SA's start
(its first accepted proposal leaves -inf) and was refused with "its nugget ... = 0.002",
GPM/SA's default nugget, as if too small for float64.
"""

import math
from dataclasses import replace

import numpy as np
import pytest

import gpmsa
from gpmsa.mcmc.sampler import ChainState
from gpmsa.model.mean_basis import MeanBasis
from gpmsa.model.problem import prepare


def _smooth(m: int) -> gpmsa.SimData:
    rng = np.random.default_rng(0)
    x, t = rng.random((m, 1)), rng.random((m, 1))
    return gpmsa.SimData(x=x, t=t, y=x + t)


def _with_basis(fn, k: int):
    problem = prepare(_smooth(40), mean_basis="constant").problem
    return replace(problem, mean_basis=MeanBasis("callable", 2, fn=fn, k=k))


def test_a_start_whose_gls_term_does_not_factor_is_not_refused_as_a_nugget():
    # a zero column: H' Sigma_W^-1 H singular exactly, Sigma_W itself factors at the start
    problem = _with_basis(lambda z: np.column_stack([np.ones(len(z)), np.zeros(len(z))]), 2)
    state = ChainState(problem, problem.init, np.random.default_rng(0))
    assert state.loglik == -math.inf and not state.lik.comps[0].ok  # the case
    state.check_start()  # before: GPMSAError "Sigma_W ... its nugget ... = 0.002 ..."


def test_a_start_whose_sigma_w_does_not_factor_is_still_refused_naming_the_nugget():
    problem = _with_basis(lambda z: np.ones((len(z), 1)), 1)
    held = {**problem.init, "lamWs": np.array([1e18]), "lamWOs": np.array([1e18])}
    held["betaU"] = np.full_like(problem.init["betaU"], 0.01)
    state = ChainState(problem, held, np.random.default_rng(0))
    with pytest.raises(gpmsa.GPMSAError, match=r"component 0 is not positive definite in "
                       r"float64 at the chain's start: its nugget .* = 2e-18"):  # fmt: skip
        state.check_start()
