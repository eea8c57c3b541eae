"""A Metropolis-Hastings test draws u from ``Generator.random``, which gives 0.0 with chance 2**-53
a draw; the numpy samplers took ``math.log(u)``, so such a draw raised "math domain error" and
ended the chain (the tempering helper found it in ``swap``; the same test stood in the element
sweep, the joint level move, the ridge move, the fast calibration sampler and the study
sampler). ``gpmsa.mcmc.acceptance.log_uniform`` reads u = 0 as log u = -inf: the move is
taken unless its ratio is -inf, and every u > 0 decides as before."""

import math

import numpy as np
import pytest
from test_calib_sampler_mutation_s88 import LAM0, THETA0, _sampler, _uniforms
from test_sampler_mutation_s88 import FixedUniforms
from threadpoolctl import threadpool_limits

from gpmsa.calibration import sampler as smp
from gpmsa.mcmc.acceptance import log_uniform
from gpmsa.mcmc.sampler import ChainState
from tests.gpmsa.test_core_mcmc import smooth_problem
from tests.gpmsa.test_ridge import small_scalar_problem


@pytest.fixture(autouse=True)
def one_blas_thread():
    with threadpool_limits(1):
        yield


def test_log_uniform_is_math_log_above_zero_and_minus_inf_at_zero():
    assert log_uniform(0.0) == -math.inf
    for u in (5e-324, 1e-300, 0.25, 0.5, 1.0 - 2**-53):
        assert log_uniform(u) == math.log(u)


@pytest.mark.parametrize("element", [("lamUz", (0,)), ("betaU", (0, 0)), ("lamWOs", (0,))])
def test_an_element_step_at_a_zero_uniform_is_taken(element):
    prob, _ = smooth_problem()
    state = ChainState(prob, prob.init, FixedUniforms([[0.6, 0.0]]), els=[element])
    acc = np.zeros(1)
    state.sweep(np.array([0.01]), False, acc)  # ValueError: math domain error before
    assert acc[0] == 1


def test_a_ridge_move_at_a_zero_uniform_is_taken():
    prob = small_scalar_problem()
    state = ChainState(prob, prob.init, np.random.default_rng(0), ridge_moves=1)
    before = float(state.params["lamWs"][0])
    state.ridge_sweep(np.array([[0.6, 0.0]]))  # ValueError before
    assert float(state.params["lamWs"][0]) != before


@pytest.mark.parametrize("element", [0, 1, 2])
def test_a_fast_calibration_step_at_a_zero_uniform_is_taken(element):
    s = _sampler()
    state = smp._State(s, list(THETA0), LAM0, 0)
    acc = [0] * (s.q + 1)
    state.sweep([0.05, 0.05, 5.0], False, acc, _uniforms(s.q, element, 0.6, 0.0))
    assert acc[element] == 1


def test_a_study_sweep_at_zero_uniforms_takes_its_theta_and_group_moves():
    from test_study_basis_s68 import _data, _fit_source

    from gpmsa.model.problem import prepare
    from gpmsa.studies import continuation as cont
    from gpmsa.studies.sampler import StudyState

    src = _fit_source()
    sim, obs = _data()
    preps = [prepare(sim, o) for o in obs]
    problems = [p.problem for p in preps]
    start = cont.chain_starts(src, cont.fit_starts(src, problems, preps, obs, 2))[0]
    state = StudyState(problems, src.layout, src.hyper, *start, np.random.default_rng(0))
    G, H = state.layout.n_elements, len(state.group_els)
    rows = np.tile([0.5, 0.0], (G + 2 * H, 1))  # no step, u = 0: every ratio 0 is taken
    state.rng = FixedUniforms(rows)
    sizes = sum(state.sizes)
    acc = np.zeros(G + sizes + 2 * H)
    widths = np.full(acc.size, 0.1)
    state.sweep(widths, False, acc)  # ValueError: math domain error before
    free = [e for e in range(G) if e not in state.held and state.levels[e] is None]
    assert free and all(acc[e] == 1 for e in free)
    assert all(acc[G + sizes + k] == 1 for k in range(2 * H))
