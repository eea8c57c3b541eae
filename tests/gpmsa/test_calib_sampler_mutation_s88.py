"""The fast calibration sampler's single steps against hand-computed Metropolis-Hastings decisions
(session 88, mutation testing of ``gpmsa.calibration.sampler``): theta's uniform walk, lamOs's
uniform walk and GPM/SA's proportional step with its Hastings factor, and the move between
emulator parameter sets, each taken exactly when its acceptance draw lies below the ratio of
``log_post_at`` (the sampler's log posterior at a state, checked against dense solves in
test_mcmc_bound_s80); the acceptance counts and the chain's recorded log posterior.
Deterministic."""

import math

import numpy as np
import pytest
from _calib_cases import categorical_emulator, two_param_emulator
from _level_cases import level_function, level_sim

from gpmsa import Emulator
from gpmsa.calibration import sampler as smp
from gpmsa.calibration.observations import fixed_gp, reduce, theta_levels

XO, YO = np.array([[0.3], [0.8]]), np.array([[0.75], [1.0]])
MARGIN = 1e-6
THETA0, LAM0 = [0.45, 0.6], 60.0


def _sampler(n_sets: int = 1) -> smp.CalibrationSampler:
    emu = two_param_emulator()
    data = reduce(emu, XO, YO, False)
    sets = [emu.params] + [{**emu.params, "lamUz": emu.params["lamUz"] * f} for f in (0.3,)]
    gps = [fixed_gp(emu, p) for p in sets[:n_sets]]
    return smp.CalibrationSampler(gps, data, emu.priors)


def _uniforms(q: int, element: int, u0: float, u1: float, rest: float = 0.5) -> list[float]:
    """2 (q + 2) uniforms: every other element's step u = 0.5 (a proposal of its own value,
    so it cannot move), ``element``'s (u0, u1)."""
    u = [rest, 0.5] * (q + 2)
    u[2 * element], u[2 * element + 1] = u0, u1
    return u


def _decide(s, start, cand, corr=0.0):
    ratio = s.log_post_at(cand) - s.log_post_at(start) + corr
    assert math.isfinite(ratio)
    return ratio


CASES = [("theta0", 0, 0.2, False), ("theta1", 1, 0.2, False), ("lamOs", 2, 40.0, False),
         ("lamOs-prop", 2, 1.0, True)]  # fmt: skip


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_one_step_is_taken_exactly_below_its_metropolis_hastings_ratio(case):
    _, el, width, prop = case
    s = _sampler()
    q = s.q
    start = (list(THETA0), LAM0, 0)
    widths = [0.2, 0.2, width]
    for u0 in (0.9, 0.1, 0.75, 0.25, 0.6, 0.4, 0.55, 0.45, 0.52, 0.48):
        step = u0 - 0.5
        theta, lam, corr = list(THETA0), LAM0, 0.0
        if el < q:
            theta[el] += widths[el] * step
        elif prop:  # w0 = 20; cand = 60 + 40 step; the reverse width max(1, cand/3)
            w0 = max(1.0, LAM0 / 3)
            lam = LAM0 + 2 * w0 * step
            w1 = max(1.0, lam / 3)
            if LAM0 > lam + w1:
                continue
            corr = math.log(w0 / w1)
            assert corr != 0.0
        else:
            lam = LAM0 + width * step
        cand = (theta, lam, 0)
        ratio = _decide(s, start, cand, corr)
        if -6.0 < ratio < -1e-3:
            break
    else:
        pytest.fail("no proposal with an acceptance ratio in (e^-6, e^-0.001): change the case")
    for factor, taken in ((1 - MARGIN, True), (1 + MARGIN, False)):
        state = smp._State(s, list(THETA0), LAM0, 0)
        acc = np.zeros(q + 1)
        state.sweep(widths, prop, acc, _uniforms(q, el, u0, math.exp(ratio) * factor))
        assert acc[el] == (1 if taken else 0), (case, u0, ratio, factor)
        want = cand if taken else start
        assert state.theta == pytest.approx(want[0], rel=1e-14)
        assert state.lam == pytest.approx(want[1], rel=1e-14)
        assert state.log_post() == pytest.approx(s.log_post_at(want), rel=1e-12, abs=1e-12)


@pytest.mark.parametrize(("u0", "reachable"), [(0.1, False), (0.15, True)])
def test_a_proportional_lamos_step_the_reverse_cannot_reach_is_refused(u0, reachable):
    # lamOs = 60: cand = 60 + 40 (u0 - 0.5); its reverse reaches 60 only where cand >= 45
    s = _sampler()
    state = smp._State(s, list(THETA0), LAM0, 0)
    acc = np.zeros(3)
    state.sweep([0.2, 0.2, 1.0], True, acc, _uniforms(2, 2, u0, 1e-300))
    assert acc[2] == reachable
    assert state.lam == pytest.approx(60 + 40 * (u0 - 0.5) if reachable else LAM0, rel=1e-14)


def test_a_lamos_step_to_zero_or_below_is_refused():
    s = _sampler()
    state = smp._State(s, list(THETA0), 1.0, 0)
    acc = np.zeros(3)
    state.sweep([0.2, 0.2, 4.0], False, acc, _uniforms(2, 2, 0.1, 1e-300))  # 1 - 1.6
    assert acc[2] == 0 and state.lam == 1.0
    state.sweep([0.2, 0.2, 4.0], False, acc, _uniforms(2, 2, 0.3, 1e-300))  # 1 - 0.8 = 0.2
    assert acc[2] == 1 and state.lam == pytest.approx(0.2, rel=1e-14)


def test_the_move_between_emulator_sets_is_taken_by_its_likelihood_ratio():
    s = _sampler(n_sets=2)
    start = (list(THETA0), LAM0, 0)
    ratio = s.log_post_at((list(THETA0), LAM0, 1)) - s.log_post_at(start)
    assert ratio != 0.0
    a = min(ratio, 0.0)
    assert ratio > -20
    # the set from the first uniform, the decision from the second: (0.7, 1e-9) moves to set 1,
    # (0.2, 0.9) stays at set 0 (a proposal of the current set)
    cases = (
        (0.7, 1 - MARGIN, True),
        (0.7, 1 + MARGIN, ratio >= 0),
        (0.2, 1e-9, True),
        (0.7, 1e-9 / math.exp(a), True),
        (0.2, 0.9 / math.exp(a), True),
    )
    for u_set, factor, moves in cases:  # fmt: skip
        state = smp._State(s, list(THETA0), LAM0, 0)
        u = [0.5, 0.5] * 3 + [u_set, math.exp(a) * factor]  # theta and lamOs stay (u = 0.5)
        state.sweep([0.2, 0.2, 1.0], False, np.zeros(3), u)
        want_k = (1 if u_set >= 0.5 else 0) if moves else 0
        assert state.k == want_k, (u_set, factor, ratio)
        assert state.log_post() == pytest.approx(s.log_post_at((list(THETA0), LAM0, want_k)),
                                                 rel=1e-12)  # fmt: skip


def test_a_run_records_the_states_it_sweeps():
    """``run`` without tuning: the draws, log posterior and acceptance rates are those of the
    sweeps it makes with the generator's rows (the proportional step, as untuned)."""
    s = _sampler()
    res = s.run(30, np.random.default_rng(4), tune=False)
    state = smp._State(s, *s._initial())
    rows = np.random.default_rng(4).random((30, 8)).tolist()
    acc = np.zeros(3)
    w = [smp.THETA_WIDTH] * 2 + [s.init_lamos / 2]
    for i, row in enumerate(rows):
        state.sweep(w, True, acc, row)
        assert res.theta[i].tolist() == state.theta and res.lamOs[i] == state.lam
        assert res.log_post[i] == state.log_post()
    np.testing.assert_array_equal(res.accept_rate, acc / 30)
    assert 0 < acc.min() and acc.max() < 30


@pytest.mark.parametrize("n_levels", [2, 3])
def test_a_categorical_element_moves_to_another_level_below_its_ratio(n_levels):
    """Two levels or more: the element proposes another level (uniformly) and takes it exactly
    below the posterior ratio (the prior is uniform over the levels)."""
    emu = categorical_emulator()
    levels = theta_levels(emu)[0][:n_levels]
    data = reduce(emu, [[0.3], [0.6]], [[1.3], [1.6]], False)  # y = x + 1: the second level
    s = smp.CalibrationSampler([fixed_gp(emu, emu.params)], data, emu.priors,
                               theta_levels=[levels])  # fmt: skip
    x = levels[0]
    for u0 in (0.0, 0.99) if n_levels == 3 else (0.0,):
        cand = levels[1 + int(u0 * (n_levels - 1))]
        ratio = s.log_post_at(([cand], LAM0, 0)) - s.log_post_at(([x], LAM0, 0))
        assert math.isfinite(ratio) and ratio != 0.0
        for factor, taken in ((1 - MARGIN, True), (1 + MARGIN, ratio >= 0)):
            state = smp._State(s, [x], LAM0, 0)
            acc = np.zeros(2)
            u = [u0, math.exp(min(ratio, 0.0)) * factor, 0.5, 0.5, 0.5, 0.5]
            state.sweep([0.2, 1.0], False, acc, u)
            assert acc[0] == taken and state.theta == [cand if taken else x], (u0, factor)


def test_a_categorical_element_after_a_continuous_one_draws_its_level_from_its_own_uniform():
    """theta = (k, kind): kind's level comes from its own step uniform (u[2]), not another's."""
    rng = np.random.default_rng(3)
    sim = level_sim(rng, 24)
    params = {"betaU": [[1.0], [1.0], [1.0]], "lamUz": [1.0], "lamWs": [1e3], "lamWOs": [1e3]}
    emu = Emulator.from_params(sim, params)
    xo = np.array([[0.3], [0.6]])
    yo = level_function(xo, np.array([[0.4, 1.0], [0.4, 1.0]]))[:, None]
    lv = theta_levels(emu)
    assert lv[0] is None and len(lv[1]) == 3
    s = smp.CalibrationSampler([fixed_gp(emu, emu.params)], reduce(emu, xo, yo, False),
                               emu.priors, theta_levels=lv)  # fmt: skip
    x = s.init_theta[1]
    others = [v for v in lv[1] if v != x]
    for u_level, want in ((0.1, others[0]), (0.9, others[1])):
        state = smp._State(s, list(s.init_theta), LAM0, 0)
        acc = np.zeros(3)
        # k's step 0.5 (no move) with acceptance draw 1 - u_level, kind's (u_level, 1e-300)
        state.sweep([0.2, 0.2, 1.0], False, acc, [0.5, 1 - u_level, u_level, 1e-300] + [0.5] * 4)
        assert acc[1] == 1 and state.theta[1] == want, (u_level, state.theta)
