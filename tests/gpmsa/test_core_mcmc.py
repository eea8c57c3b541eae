"""Each Metropolis update leaves its full conditional invariant: chains vs 1-D quadrature."""

import numpy as np
import pytest
from threadpoolctl import threadpool_limits

from gpmsa.mcmc.sampler import ChainState, default_widths, elements
from gpmsa.mcmc.tuning import choose_widths, fit_logistic, level_widths
from gpmsa.model.data import ObsData, SimData
from gpmsa.model.likelihood import log_likelihood
from gpmsa.model.problem import prepare
from tests.gpmsa.test_core_likelihood import random_problem

N_UPDATES = 8_000
N_BATCH = 40


@pytest.fixture(autouse=True)
def one_blas_thread():
    with threadpool_limits(1):
        yield


def smooth_problem(discrepancy=None):
    """A small smooth calibration problem at a plausible state (m = 24, two observations)."""
    rng = np.random.default_rng(4)
    m = 24
    x = (rng.permutation(m) + rng.random(m)) / m
    t = (rng.permutation(m) + rng.random(m)) / m
    y = np.sin(3 * x) + 1.5 * t**2 + 0.02 * rng.standard_normal(m)
    sim = SimData(x=x, t=t, y=y)
    xo = np.array([0.3, 0.7])
    obs = ObsData(x=xo[:, None], y=(np.sin(3 * xo) + 1.5 * 0.4**2 + 0.05)[:, None])
    prob = prepare(sim, obs, discrepancy=discrepancy).problem
    state = {"betaU": np.array([[2.0], [1.0]]), "lamUz": np.array([1.5]),
             "lamWs": np.array([3000.0]), "lamWOs": np.array([3000.0]),
             "theta": np.array([0.45]), "lamOs": np.array([60.0])}  # fmt: skip
    if discrepancy:
        state.update(betaV=np.array([[1.0]]), lamVz=np.array([40.0]))
    return prob.with_init(state), state


def conditional_moments(prob, state_params, name, idx):
    """Mean and variance of element (name, idx) under its full conditional, by quadrature.

    beta elements are integrated over rho = exp(-beta/4) in (0, 1), the scale their random walk
    and prior live on; other elements over their own scale.
    """
    pri = prob.priors.scalar_log_prior(name)

    def logpost(x):
        prm = {k: v.copy() for k, v in state_params.items()}
        prm[name][idx] = x
        lp = pri(x)
        return lp + log_likelihood(prob, prm) if lp > -np.inf else -np.inf

    if name == "betaU" or name == "betaV":
        rho = np.linspace(1e-4, 1 - 1e-6, 801)
        beta = -4 * np.log(rho)
        lp = np.array([logpost(b) for b in beta])
        values, grid = beta, rho
    else:
        g = prob.priors
        lo = 0.0 if name == "theta" else getattr(g, name).lower
        hi = 1.0 if name == "theta" else min(getattr(g, name).upper, 1e6)
        coarse = (
            np.linspace(lo, hi, 2001)[1:-1]
            if name == "theta"
            else np.geomspace(max(lo, 1e-3), hi, 400)[1:-1]
        )
        lpc = np.array([logpost(x) for x in coarse])
        keep = coarse[lpc > lpc.max() - 40]
        a = max(lo, keep.min() - (keep.max() - keep.min()) * 0.05)
        b = min(hi, keep.max() + (keep.max() - keep.min()) * 0.05)
        grid = np.linspace(a, b, 801)[1:-1]
        lp = np.array([logpost(x) for x in grid])
        values = grid
    dens = np.exp(lp - lp.max())
    wts = np.gradient(grid) * dens
    wts /= wts.sum()
    mean = float(np.sum(wts * values))
    return mean, float(np.sum(wts * (values - mean) ** 2))


def run_single(prob, name, idx, width, prop_mh, seed):
    state = ChainState(prob, prob.init, np.random.default_rng(seed), els=[(name, idx)])
    acc = np.zeros(1)
    out = np.empty(N_UPDATES)
    for i in range(N_UPDATES):
        state.sweep(np.array([width]), prop_mh, acc)
        out[i] = state.params[name][idx]
    return out[1000:], acc[0] / N_UPDATES


def batch_se(x):
    b = x[: len(x) // N_BATCH * N_BATCH].reshape(N_BATCH, -1).mean(axis=1)
    return b.std(ddof=1) / np.sqrt(N_BATCH)


TARGETS = [
    # (name, index, proportional step for precisions)
    ("theta", (0,), False),
    ("betaU", (0, 0), False),
    ("betaU", (1, 0), False),
    ("lamUz", (0,), False),
    ("lamUz", (0,), True),
    ("lamWs", (0,), False),
    ("lamWOs", (0,), True),
    ("lamOs", (0,), True),
    ("lamOs", (0,), False),
    ("betaV", (0, 0), False),
    ("lamVz", (0,), False),
]


@pytest.mark.parametrize("target", TARGETS, ids=lambda t: f"{t[0]}{t[1]}{'-prop' if t[2] else ''}")
def test_single_update_samples_its_full_conditional(target):
    name, idx, prop = target
    prob, params = smooth_problem("constant" if name in ("betaV", "lamVz") else None)
    mean, var = conditional_moments(prob, params, name, idx)
    width = 2.5 * np.sqrt(var)
    if name in ("betaU", "betaV"):  # the walk is on rho = exp(-beta/4): d rho = rho/4 d beta
        width *= np.exp(-mean / 4) / 4
    x, rate = run_single(prob, name, idx, width, prop, seed=5)
    assert 0.03 < rate < 0.98, f"acceptance {rate} gives a useless test"
    se = batch_se(x)
    assert abs(x.mean() - mean) < 4.5 * se + 1e-9 * abs(mean), (x.mean(), mean, se)
    sq = (x - mean) ** 2
    assert abs(sq.mean() - var) < 4.5 * batch_se(sq) + 1e-9, (sq.mean(), var)


def test_out_of_bounds_proposal_is_rejected_without_likelihood_call():
    prob, params, _ = random_problem(3, 1, 1, 1, 2, 0, True)
    prob = prob.with_init({**params, "lamUz": np.array([0.31])})
    state = ChainState(prob, prob.init, np.random.default_rng(0), els=[("lamUz", (0,))])
    calls = []
    original = state.lik.propose
    state.lik.propose = lambda *a: calls.append(a) or original(*a)
    acc = np.zeros(1)
    for _ in range(200):
        state.sweep(np.array([100.0]), False, acc)  # most proposals fall below 0.3 or far up
    below = [c for c in calls if c[2] <= 0.3]
    assert calls and not below
    assert state.params["lamUz"][0] > 0.3


def test_sweep_order_and_elements_follow_gpmsa():
    prob, _, _ = random_problem(0, 2, 1, 2, 2, 1, False)
    els = elements(prob)
    names = [n for n, _ in els]
    order = ["theta", "betaV", "betaU", "lamVz", "lamUz", "lamWs", "lamWOs", "lamOs"]
    assert names == sorted(names, key=order.index)
    betas = [i for n, i in els if n == "betaU"]
    assert betas[:3] == [(0, 0), (1, 0), (2, 0)] and betas[3] == (0, 1)  # column-major
    fixed = prob.with_init({}, fixed=frozenset({"betaU", "lamUz", "lamWs", "lamWOs"}))
    assert {n for n, _ in elements(fixed)} == {"theta", "betaV", "lamVz", "lamOs"}
    w = default_widths(prob)
    assert (
        w["theta"][0] == 0.2
        and w["betaU"][0, 0] == 0.1
        and w["lamOs"][0] == prob.init["lamOs"][0] / 2
    )


def test_logistic_fit_recovers_known_coefficients_and_target_width():
    rng = np.random.default_rng(0)
    widths = np.geomspace(0.01, 10, 20)
    b0, b1 = 0.5, -1.3
    p = 1 / (1 + np.exp(-(b0 + b1 * np.log(widths))))
    k = rng.binomial(2000, p)
    b = fit_logistic(np.log(widths), k, 2000)
    assert b == pytest.approx([b0, b1], abs=0.05)
    cands = level_widths(["theta"], np.array([0.2]), 20)
    assert cands.shape == (20, 1) and cands[9, 0] < 0.2 < cands[10, 0]
    assert cands[0, 0] == pytest.approx(0.2 * 2.0**-9.5)
    assert cands[-1, 0] == pytest.approx(0.2 * 20.0 ** (9.5 * 2 / 19))
    acc = np.round(50 / (1 + np.exp(-(b0 + b1 * np.log(cands[:, 0])))))
    chosen = choose_widths(np.array([0.2]), cands, acc[:, None], 50)
    expected = np.exp((np.log(1 / (np.e - 1)) - b0) / b1)
    assert chosen[0] == pytest.approx(expected, rel=0.15)
    flat = choose_widths(np.array([0.2]), cands, np.full((20, 1), 25.0), 50)
    assert flat[0] == 0.2  # no slope: keep the default


def test_sample_shapes_fixed_params_and_arviz():
    from gpmsa.backends import get

    prob, params = smooth_problem()
    fixed = prob.with_init(params, fixed=frozenset({"betaU", "lamUz", "lamWs", "lamWOs"}))
    chains = get("numpy").sample(fixed, n_iter=40, n_chains=2, tune=False, seed=1)
    assert chains.draws["theta"].shape == (2, 40, 1) and chains.log_post.shape == (2, 40)
    assert np.all(chains.draws["betaU"] == params["betaU"])  # fixed: never moves
    assert np.isnan(chains.step_widths["lamUz"]).all() and chains.step_widths["theta"].shape == (
        2,
        1,
    )
    assert np.ptp(chains.draws["theta"]) > 0 and 0 < chains.accept_rate["theta"].mean() < 1
    assert not np.array_equal(chains.draws["theta"][0], chains.draws["theta"][1])
    idata = chains.to_arviz()
    assert idata.posterior["theta"].shape == (2, 40, 1) and "lp" in idata.sample_stats
