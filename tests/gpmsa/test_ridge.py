"""The move along the nugget ridge samples its conditional exactly, and mixes the ridge."""

import numpy as np
import pytest
from threadpoolctl import threadpool_limits

import gpmsa
from gpmsa import backends
from gpmsa.mcmc import ridge
from gpmsa.mcmc.diagnostics import ess
from gpmsa.mcmc.sampler import ChainState


@pytest.fixture(autouse=True)
def one_blas_thread():
    """BatchState and ChainState used directly: LAPACK on one thread, as the samplers run it."""
    with threadpool_limits(1):
        yield


@pytest.fixture(scope="module")
def scalar_problem():
    """A small simulation-only scalar-output problem (p_u = 1) at a plausible state."""
    return small_scalar_problem()


def small_scalar_problem():
    """`scalar_problem`, made anew (also for test_sampler_mutation_s88)."""
    rng = np.random.default_rng(2)
    m = 20
    x, t = (rng.permutation(m) + rng.random(m)) / m, (rng.permutation(m) + rng.random(m)) / m
    sim = gpmsa.SimData(x=x, t=t, y=np.sin(3 * x) + t**2 + 0.05 * rng.standard_normal(m))
    prob = gpmsa.prepare(sim).problem
    state = {"betaU": [[2.0], [1.0]], "lamUz": [1.5], "lamWs": [400.0], "lamWOs": [900.0]}
    return prob.with_init(state)


def ridge_moments(prob) -> tuple[float, float]:
    """Mean and variance of lamWs along the ridge through prob.init, by quadrature of
    g_s(s) g_t(t(s)) t(s)^2 (the density of s given the nugget; docs of gpmsa.mcmc.ridge)."""
    pri = prob.priors
    c = float(prob.lam_sim[0])
    s0, t0 = float(prob.init["lamWs"][0]), float(prob.init["lamWOs"][0])
    n = 1.0 / (c * t0) + 1.0 / s0
    s = np.geomspace(1.0 / n * (1 + 1e-9), 1e5, 200_001)
    t = 1.0 / (c * (n - 1.0 / s))

    def log_gamma(g, x):
        inside = (x > g.lower) & (x < g.upper)
        return np.where(inside, (g.a - 1) * np.log(x) - g.b * x, -np.inf)

    log_f = log_gamma(pri.lamWs, s) + log_gamma(pri.lamWOs, t) + 2.0 * np.log(t)
    f = np.exp(log_f - np.max(log_f))
    w = np.gradient(s) * f
    w /= w.sum()
    mean = float(w @ s)
    return mean, float(w @ (s - mean) ** 2)


def _check(draws: np.ndarray, mean: float, var: float) -> None:
    """draws (chains, n) of lamWs: mean and variance within 4.5 Monte-Carlo standard errors."""
    n_eff = ess(draws)
    assert n_eff > 500, f"ESS {n_eff:.0f}: too few for the check"
    sd = np.sqrt(var)
    assert abs(draws.mean() - mean) < 4.5 * sd / np.sqrt(n_eff), (draws.mean(), mean)
    sq = (draws - mean) ** 2
    kurt = np.mean(sq**2) / var**2
    assert abs(sq.mean() - var) < 4.5 * var * np.sqrt((kurt - 1) / n_eff), (sq.mean(), var)


def test_numpy_ridge_move_samples_the_conditional_and_keeps_the_likelihood(scalar_problem):
    prob = scalar_problem
    mean, var = ridge_moments(prob)
    chains = []
    for seed in range(4):
        state = ChainState(prob, prob.init, np.random.default_rng(seed))
        ll0 = state.lik.loglik
        rng = np.random.default_rng(100 + seed)
        out = np.empty(6000)
        for i in range(out.size):
            state.ridge_sweep(rng.random((1, 2)))
            out[i] = state.params["lamWs"][0]
        nugget = 1 / (prob.lam_sim[0] * state.params["lamWOs"][0]) + 1 / state.params["lamWs"][0]
        n0 = 1 / (prob.lam_sim[0] * prob.init["lamWOs"][0]) + 1 / prob.init["lamWs"][0]
        assert nugget == pytest.approx(n0, rel=1e-12) and state.lik.loglik == ll0
        assert 0.1 < state.ridge_accepted / out.size < 0.95
        chains.append(out[500:])
    _check(np.array(chains), mean, var)


def test_torch_ridge_move_samples_the_same_conditional(scalar_problem):
    torch = pytest.importorskip("torch")
    from gpmsa.backends.torch_backend import BatchState

    prob = scalar_problem
    mean, var = ridge_moments(prob)
    state = BatchState(prob, 64, torch.float64, "cpu", ridge_moves=1)
    ll0 = state.loglik.clone()
    gen = torch.Generator().manual_seed(3)
    out = np.empty((64, 400))
    for i in range(out.shape[1]):
        state.ridge_sweep(torch.rand((1, 2, 64), generator=gen, dtype=torch.float64))
        out[:, i] = state.params["lamWs"][:, 0].numpy()
    assert torch.equal(state.loglik, ll0)
    _check(out[:, 100:], mean, var)


def test_ridge_applies_only_where_the_likelihood_is_unchanged():
    from _backend_cases import multi_problem, road_problem

    assert ridge.applies(road_problem(False).problem)
    assert not ridge.applies(road_problem(True).problem)  # lamWs enters the observation term
    assert not ridge.applies(multi_problem().problem)  # p_u = 2: lamWOs is shared
    fixed = road_problem(False).problem
    fixed = fixed.with_init({}, fixed=frozenset({"lamWOs"}))
    assert not ridge.applies(fixed)
    for bad in (-1, 2.5, "5", 10**6):  # a million moves per sweep: the fit would never end
        with pytest.raises(gpmsa.GPMSAError, match=r"ridge_moves must be an integer in \[0, 10"):
            backends.get("numpy").sample(fixed, n_iter=5, ridge_moves=bad)


def test_ridge_moves_mix_lamws_and_lamwos_on_the_road_case():
    """GPM/SA's sweep alone crawls along the ridge; with the moves lamWs mixes like the rest."""
    from _backend_cases import road_problem

    prob = road_problem(False).problem
    kw = {"n_iter": 600, "n_chains": 2, "seed": 1, "tune_rounds": 10, "n_jobs": 1}
    with_moves = backends.get("numpy").sample(prob, **kw)
    without = backends.get("numpy").sample(prob, ridge_moves=0, **kw)
    assert with_moves.info["ridge_moves"] == ridge.N_MOVES and without.info["ridge_moves"] == 0
    e_with = ess(with_moves.draws["lamWs"][:, 200:, 0])
    e_without = ess(without.draws["lamWs"][:, 200:, 0])
    assert e_with > 4 * e_without, (e_with, e_without)
