"""The numpy sampler's single steps against hand-computed Metropolis-Hastings decisions (session 88,
mutation testing of ``gpmsa.mcmc.sampler``): each proposal (theta's and a precision's uniform
walk, beta's walk on rho = exp(-beta/4), GPM/SA's proportional step with its Hastings factor,
a categorical theta's joint level move, the nugget-ridge move), each taken exactly when the
acceptance draw lies below its ratio, computed here from the reference likelihood and the
whole-problem prior; the running log prior and the acceptance counts they keep; ``run_chain``
as the plain tune-then-sweep loop. All deterministic (fixed uniforms, seeded generators)."""

import math

import numpy as np
import pytest
from _level_cases import level_function, level_sim
from threadpoolctl import threadpool_limits

import gpmsa
from gpmsa.mcmc import ridge, tuning
from gpmsa.mcmc.sampler import ChainState, default_widths, run_chain
from gpmsa.model.likelihood import log_likelihood, log_prior
from tests.gpmsa.test_core_mcmc import smooth_problem
from tests.gpmsa.test_ridge import small_scalar_problem

MARGIN = 1e-5
"""Relative margin of the acceptance draw about exp(ratio): the decision flips across it."""


@pytest.fixture(autouse=True)
def one_blas_thread():
    with threadpool_limits(1):
        yield


class FixedUniforms:
    """A generator stand-in whose ``random(shape)`` returns the given rows (checked shape)."""

    def __init__(self, rows):
        self.rows = np.asarray(rows, dtype=float)

    def random(self, shape):
        assert tuple(shape) == self.rows.shape, (shape, self.rows.shape)
        return self.rows.copy()


def log_post(prob, params) -> float:
    """Reference log posterior: the dense likelihood and the whole-problem prior."""
    lp = log_prior(prob, params)
    return lp if lp == -math.inf else lp + log_likelihood(prob, params)


def with_value(params, name, idx, value):
    out = {k: v.copy() for k, v in params.items()}
    out[name][idx] = value
    return out


def hand_candidate(name, x, width, u0, prop):
    """(candidate, log Hastings factor) as documented: uniform walks, beta on rho, GPM/SA's
    proportional step for precisions (None where the reverse step could not reach x)."""
    step = u0 - 0.5
    if name in ("betaU", "betaV"):
        r = math.exp(-x / 4) + width * step
        return (None, 0.0) if r <= 0 else (-4 * math.log(r), 0.0)
    if prop:
        w0 = max(1.0, x / 3)
        cand = x + 2 * w0 * step
        w1 = max(1.0, cand / 3)
        return (None, 0.0) if abs(cand - x) > w1 else (cand, math.log(w0 / w1))
    return x + width * step, 0.0


CASES = [
    # (name, idx, width, proportional, tempering beta, discrepancy)
    ("theta", (0,), 0.2, False, 1.0, None),
    ("theta", (0,), 0.2, False, 0.5, None),
    ("betaU", (0, 0), 0.3, False, 1.0, None),
    ("betaU", (1, 0), 0.3, False, 0.25, None),
    ("lamUz", (0,), 2.0, False, 1.0, None),
    ("lamOs", (0,), 30.0, False, 1.0, None),
    ("lamOs", (0,), 30.0, True, 1.0, None),  # x = 60: widths 20 -> cand/3, a Hastings factor
    ("lamWs", (0,), 5.0, True, 0.5, None),
    ("lamVz", (0,), 20.0, False, 1.0, "constant"),
    ("betaV", (0, 0), 0.3, False, 1.0, "constant"),
]


@pytest.mark.parametrize("case", CASES, ids=lambda c: f"{c[0]}{c[1]}-w{c[2]}-p{c[3]}-b{c[4]}")
def test_one_step_is_taken_exactly_below_its_metropolis_hastings_ratio(case):
    name, idx, width, prop, beta, disc = case
    prob, params = smooth_problem(disc)
    start = {k: v.copy() for k, v in prob.init.items()}
    x = float(start[name][idx])
    lp0 = log_post(prob, start)
    for u0 in (0.9, 0.1, 0.7, 0.3, 0.97, 0.03, 0.6, 0.4):  # a proposal the ratio makes uncertain
        cand, corr = hand_candidate(name, x, width, u0, prop)
        if cand is None:
            continue
        moved = with_value(start, name, idx, cand)
        lp_prior = log_prior(prob, moved)
        if lp_prior == -math.inf:
            continue
        d_ll = log_likelihood(prob, moved) - log_likelihood(prob, start)
        ratio = d_ll * beta + lp_prior - log_prior(prob, start) + corr
        if -6.0 < ratio < -1e-3:
            break
    else:
        pytest.fail("no proposal with an acceptance ratio in (e^-6, e^-0.001): change the case")
    for factor, taken in ((1 - MARGIN, True), (1 + MARGIN, False)):
        state = ChainState(prob, start, FixedUniforms([[u0, math.exp(ratio) * factor]]),
                           els=[(name, idx)])  # fmt: skip
        state.beta = beta
        acc = np.zeros(1)
        state.sweep(np.array([width]), prop, acc)
        got = float(state.params[name][idx])
        assert acc[0] == (1 if taken else 0), (name, u0, ratio, factor)
        assert got == pytest.approx(cand if taken else x, rel=1e-13)
        # the running log prior and the likelihood follow the state (log_post is what is drawn)
        want = log_post(prob, moved) if taken else lp0
        assert state.log_post() == pytest.approx(want, rel=1e-9, abs=1e-9)
        assert state.log_prior == pytest.approx(log_prior(prob, state.params), rel=1e-12)


@pytest.mark.parametrize(("u0", "reachable"), [(0.05, False), (0.1, False), (0.15, True)])
def test_a_proportional_step_the_reverse_cannot_reach_is_refused_before_the_likelihood(
    u0, reachable
):
    # lamOs = 60: w0 = 20, cand = 60 + 40 (u0 - 0.5); the reverse step reaches 60 only when
    # cand + cand/3 >= 60 (cand >= 45): u0 = 0.1 (cand 44) is refused, 0.15 (cand 46) is not
    prob, _ = smooth_problem()
    state = ChainState(prob, prob.init, FixedUniforms([[u0, 1e-300]]), els=[("lamOs", (0,))])
    calls = []
    original = state.lik.propose
    state.lik.propose = lambda *a: calls.append(a) or original(*a)
    acc = np.zeros(1)
    state.sweep(np.array([1.0]), True, acc)
    cand = 60.0 + 40.0 * (u0 - 0.5)
    assert bool(calls) == reachable and acc[0] == reachable
    assert state.params["lamOs"][0] == pytest.approx(cand if reachable else 60.0, rel=1e-14)


def test_a_beta_step_below_rho_zero_is_refused_before_the_likelihood():
    prob, _ = smooth_problem()  # betaU[0, 0] = 2: rho = 0.607; a width 2 reaches rho < 0
    for u0, reachable in ((0.1, False), (0.2, True)):  # rho + 2 (u0 - 0.5): -0.19, +0.007
        state = ChainState(prob, prob.init, FixedUniforms([[u0, 1e-300]]), els=[("betaU", (0, 0))])
        calls = []
        original = state.lik.propose
        state.lik.propose = lambda *a, calls=calls, original=original: (
            calls.append(a) or original(*a)
        )
        state.sweep(np.array([2.0]), False, np.zeros(1))
        assert bool(calls) == reachable
        if reachable:  # rho' = 0.00653: beta = -4 log(rho')
            rho = math.exp(-0.5) + 2.0 * (u0 - 0.5)
            assert calls[0][2] == pytest.approx(-4 * math.log(rho), rel=1e-14)


@pytest.mark.parametrize("disc", [None, "constant"])
def test_the_running_log_prior_and_likelihood_are_those_of_the_state_after_sweeps(disc):
    prob, _ = smooth_problem(disc)
    state = ChainState(prob, prob.init, np.random.default_rng(11))
    w = state.flat_widths(default_widths(prob))
    acc = np.zeros(len(state.els))
    for prop in (True, False):
        for _ in range(15):
            state.sweep(w, prop, acc)
    assert acc.sum() > 10  # the state moved
    assert state.log_prior == pytest.approx(log_prior(prob, state.params), rel=1e-10)
    assert state.log_post() == pytest.approx(log_post(prob, state.params), rel=1e-9)


def _level_problem():
    rng = np.random.default_rng(7)
    sim = level_sim(rng, 24)
    xo = np.linspace(0.1, 0.9, 4)[:, None]
    truth = np.column_stack([np.full(4, 0.4), np.full(4, 1)])
    yo = level_function(xo, truth) + rng.normal(0, 0.05, 4)
    return gpmsa.prepare(sim, gpmsa.ObsData(xo, yo)).problem


def test_the_joint_level_move_is_taken_exactly_below_its_ratio_with_the_shifts_prior():
    """A categorical theta's move to another level with k shifted by the table's offset: the
    ratio is the likelihood's and the shifted k's prior change; one acceptance counted."""
    prob = _level_problem()
    start = {k: v.copy() for k, v in prob.init.items()}
    probe = ChainState(prob, start, FixedUniforms([[0.5, 0.5]]), els=[("theta", (1,))])
    levels = probe.levels[0]
    assert probe.kinds == [3] and levels.size == 3
    offsets = np.array([[0.3], [0.0], [-0.25]])  # k's offset per level row
    rows = {float(v): r for r, v in enumerate(levels)}
    prior_k = prob.priors.scalar_log_prior("theta", 0)
    shifts = (rows, [[tuple(offsets[s] - offsets[r]) for s in range(3)] for r in range(3)],
              [0], [prior_k])  # fmt: skip
    x = float(start["theta"][1])
    others = levels[levels != x]
    done = 0
    for u0 in (0.25, 0.75):  # each other level
        cand = float(others[int(u0 * others.size)])
        moved = {k: v.copy() for k, v in start.items()}
        moved["theta"][1] = cand
        moved["theta"][0] += offsets[rows[cand], 0] - offsets[rows[x], 0]
        d_prior = log_prior(prob, moved) - log_prior(prob, start)
        assert d_prior != 0.0  # the shift's prior term enters the ratio
        ratio = log_likelihood(prob, moved) - log_likelihood(prob, start) + d_prior
        if not -20 < ratio < 30:
            continue
        a = min(ratio, 0.0)
        pairs = ((1 - MARGIN, True), (1 + MARGIN, False)) if ratio < 0 else ((0.5, True),)
        for factor, taken in pairs:
            state = ChainState(prob, start, FixedUniforms([[u0, math.exp(a) * factor]]),
                               els=[("theta", (1,))])  # fmt: skip
            state.level_shifts = {0: shifts}
            acc = np.zeros(1)
            state.sweep(np.array([1.0]), False, acc)
            assert acc[0] == (1 if taken else 0), (u0, ratio, factor)
            want = moved if taken else start
            np.testing.assert_allclose(state.params["theta"], want["theta"], rtol=1e-14)
            assert state.log_prior == pytest.approx(log_prior(prob, want), rel=1e-12)
            assert state.log_post() == pytest.approx(log_post(prob, want), rel=1e-9)
        done += 1
    assert done >= 1


def test_ridge_moves_are_taken_by_their_ratio_and_counted_one_each():
    prob = small_scalar_problem()
    assert ridge.applies(prob)
    state = ChainState(prob, prob.init, np.random.default_rng(0), ridge_moves=3)
    u = np.random.default_rng(5).random((60, 2))
    c = float(prob.lam_sim[0])
    s, t = float(prob.init["lamWs"][0]), float(prob.init["lamWOs"][0])
    taken = 0
    for u0, u1 in u:  # by hand: the ridge's documented proposal and acceptance
        n = 1 / (c * t) + 1 / s
        s2 = s * math.exp(ridge.WIDTH * (u0 - 0.5))
        if n - 1 / s2 <= 0:
            continue
        t2 = 1 / (c * (n - 1 / s2))
        old = {**prob.init, "lamWs": np.array([s]), "lamWOs": np.array([t])}
        new = {**prob.init, "lamWs": np.array([s2]), "lamWOs": np.array([t2])}
        ratio = (
            log_prior(prob, new) - log_prior(prob, old) + 2 * math.log(t2 / t) + math.log(s2 / s)
        )
        if math.log(u1) < ratio:
            s, t, taken = s2, t2, taken + 1
    ll0 = state.lik.loglik
    state.ridge_sweep(u)
    assert 0 < taken < len(u)
    assert state.ridge_accepted == taken
    assert state.params["lamWs"][0] == pytest.approx(s, rel=1e-12)
    assert state.params["lamWOs"][0] == pytest.approx(t, rel=1e-12)
    assert state.log_prior == pytest.approx(log_prior(prob, state.params), rel=1e-12)
    assert state.lik.loglik == ll0  # the likelihood is unchanged along the ridge


def test_a_chain_state_makes_no_ridge_moves_unless_asked():
    prob = small_scalar_problem()
    a = ChainState(prob, prob.init, np.random.default_rng(4))
    b = ChainState(prob, prob.init, np.random.default_rng(4), ridge_moves=0)
    w = a.flat_widths(default_widths(prob))
    for _ in range(5):
        a.sweep(w, False, np.zeros(len(w)))
        b.sweep(w, False, np.zeros(len(w)))
    assert a.ridge_moves == 0 and a.ridge_accepted == 0
    for name in prob.names:
        np.testing.assert_array_equal(a.params[name], b.params[name])


@pytest.mark.parametrize("tune", [False, True])
def test_run_chain_is_the_plain_tune_then_sweep_loop(tune):
    """``run_chain``: (tune ->) sweeps with the proportional step exactly when untuned (None),
    draws, log posterior, acceptance rates over the draws and the widths used, bit for bit."""
    prob, _ = smooth_problem()
    widths = default_widths(prob)
    n_iter, rounds, levels = 12, 2, 3
    draws, lp, rate, wid = run_chain(prob, n_iter, tune=tune, widths=widths,
                                     rng=np.random.default_rng(9), tune_rounds=rounds,
                                     tune_levels=levels)  # fmt: skip
    state = ChainState(prob, prob.init, np.random.default_rng(9))
    w = state.flat_widths(widths)
    names = [n for n, _ in state.els]
    if tune:
        w = tuning.tune_widths(state.sweep, names, w, rounds, levels)
    acc = np.zeros(len(state.els))
    want = {n: [] for n in prob.names}
    want_lp = []
    for _ in range(n_iter):
        state.sweep(w, not tune, acc)
        for n in prob.names:
            want[n].append(state.params[n].copy())
        want_lp.append(state.log_post())
    for n in prob.names:
        np.testing.assert_array_equal(draws[n], np.array(want[n]))
    np.testing.assert_array_equal(lp, want_lp)
    for i, (n, idx) in enumerate(state.els):
        assert rate[n][idx] == acc[i] / n_iter and wid[n][idx] == w[i]
    if not tune:  # the given widths, untouched
        assert all(wid[n][idx] == widths[n][idx] for n, idx in state.els)


def test_a_categorical_element_with_no_other_level_stays_without_a_proposal():
    prob = _level_problem()
    state = ChainState(prob, prob.init, FixedUniforms([[0.5, 1e-300]]), els=[("theta", (1,))])
    x = float(state.params["theta"][1])
    state.levels[0] = np.array([x])  # one level: nothing to move to
    calls = []
    state.lik.propose = lambda *a: calls.append(a)
    acc = np.zeros(1)
    state.sweep(np.array([1.0]), False, acc)
    assert not calls and acc[0] == 0 and state.params["theta"][1] == x


def test_the_acceptance_rate_of_one_draw_is_its_acceptances():
    prob, _ = smooth_problem()
    _, _, rate, _ = run_chain(prob, 1, tune=False, widths=default_widths(prob),
                              rng=np.random.default_rng(2))  # fmt: skip
    state = ChainState(prob, prob.init, np.random.default_rng(2))
    acc = np.zeros(len(state.els))
    state.sweep(state.flat_widths(default_widths(prob)), True, acc)
    assert acc.sum() > 0
    for i, (n, idx) in enumerate(state.els):
        assert rate[n][idx] == acc[i]
