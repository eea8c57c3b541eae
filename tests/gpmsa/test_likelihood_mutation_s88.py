"""The GPM/SA log-likelihood (reference and incremental) against a dense multivariate normal
built by hand from the model's covariance, in the corners the older dense test leaves out (the
mutation testing of session 88): categorical inputs, a mean basis (restricted likelihood),
several discrepancy precision groups, unobserved directions (``null_term``), a non-positive
definite covariance (-inf), and the log prior with held elements."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.stats import multivariate_normal

from gpmsa.mcmc.sampler import elements
from gpmsa.model.likelihood import (
    IncrementalLikelihood,
    log_likelihood,
    log_posterior,
    log_prior,
)
from gpmsa.model.mean_basis import MeanBasis
from gpmsa.model.priors import GammaPrior, Priors
from gpmsa.model.problem import ObsProblem, Problem

LOG_2PI = math.log(2 * math.pi)


def _kernel(a: np.ndarray, b: np.ndarray, beta: np.ndarray, cat: np.ndarray) -> np.ndarray:
    """exp(-sum_k beta_k d_k): d_k the squared difference, or 1/4 between two levels of a
    categorical input k (0 on one level)."""
    out = np.zeros((a.shape[0], b.shape[0]))
    for k in range(a.shape[1]):
        if cat[k]:
            d = 0.25 * (a[:, k, None] != b[None, :, k])
        else:
            d = (a[:, k, None] - b[None, :, k]) ** 2
        out += beta[k] * d
    return np.exp(-out)


def _mvn(x: np.ndarray, mean: np.ndarray, cov: np.ndarray) -> float:
    """log N(x; mean, cov) without the 2 pi constant (as the likelihood drops it)."""
    return float(multivariate_normal(mean, cov).logpdf(x)) + 0.5 * x.size * LOG_2PI


def dense_reference(prob: Problem, prm: dict) -> float:
    """log N(w_j; H b_j, S_j) - log det(H^T S_j^-1 H) / 2 for each component (b_j the GLS
    coefficients; no H: mean 0), plus log N(z; mu, C) with mu the conditional mean of the
    observations' weights given w (plus h b_j) and C the conditional covariance, the
    discrepancy blocks of their groups and sig_obs / lamOs, less n_null log(lamOs) / 2."""
    cat = np.zeros(prob.p + prob.q, bool) if prob.categorical is None else prob.categorical
    zt = np.hstack([prob.x_sim, prob.t_sim])
    m, mb = prob.m, prob.mean_basis
    H = None if mb is None else mb.matrix(zt)
    total, parts = 0.0, []
    for j in range(prob.p_u):
        S = _kernel(zt, zt, prm["betaU"][:, j], cat) / prm["lamUz"][j]
        S += np.eye(m) * (1 / (prob.lam_sim[j] * prm["lamWOs"][0]) + 1 / prm["lamWs"][j])
        w = prob.w[:, j]
        b = None
        if H is None:
            total += _mvn(w, np.zeros(m), S)
        else:
            Si_H = np.linalg.solve(S, H)
            b = np.linalg.solve(H.T @ Si_H, Si_H.T @ w)
            total += _mvn(w, H @ b, S) - 0.5 * np.linalg.slogdet(H.T @ Si_H)[1]
        parts.append((S, b))
    obs = prob.obs
    if obs is None:
        return total
    n, p_v = obs.n, obs.p_v
    xt = np.hstack([obs.x, np.tile(prm["theta"], (n, 1))])
    C = obs.sig_obs / prm["lamOs"][0]
    mu = np.zeros(C.shape[0])
    for j, (S, b) in enumerate(parts):
        beta = prm["betaU"][:, j]
        su = _kernel(xt, xt, beta, cat) / prm["lamUz"][j] + np.eye(n) / prm["lamWs"][j]
        suw = _kernel(xt, zt, beta, cat) / prm["lamUz"][j]
        o = 0 if obs.scalar_out else n * (p_v + j)
        C[o : o + n, o : o + n] += su - suw @ np.linalg.solve(S, suw.T)
        resid = prob.w[:, j] if b is None else prob.w[:, j] - H @ b
        mu[o : o + n] = suw @ np.linalg.solve(S, resid)
        if b is not None:
            mu[o : o + n] += mb.matrix(xt) @ b
    if p_v:
        groups = (0,) if obs.scalar_out else (obs.v_groups or (0,) * p_v)
        for i, g in enumerate(groups):
            sv = _kernel(obs.x, obs.x, prm["betaV"][:, g], cat[: prob.p]) / prm["lamVz"][g]
            C[i * n : (i + 1) * n, i * n : (i + 1) * n] += sv
    return total + _mvn(obs.z, mu, C) - 0.5 * obs.n_null * math.log(prm["lamOs"][0])


def make_problem(seed, *, n=3, p_u=2, p_v=2, scalar=False, groups=None, cat=False, mean=None,
                 n_null=0, fixed_elements=None, priors=None, m=12):  # fmt: skip
    """A small random problem: p = 2 known inputs, q = 2 parameters, m runs; with ``cat``
    the second known input and the second parameter categorical (levels 0, 0.5, 1)."""
    rng = np.random.default_rng(seed)
    p, q = 2, 2
    x, t = rng.random((m, p)), rng.random((m, q))
    x_obs = rng.random((n, p))
    if cat:
        x[:, 1] = rng.integers(0, 3, m) / 2
        t[:, 1] = rng.integers(0, 3, m) / 2
        x_obs[:, 1] = [0.0, 0.5, 1.0, 0.5, 0.0][:n]
    mask = np.array([False, True, False, True]) if cat else None
    w = rng.standard_normal((m, p_u)) + (2.0 if mean else 0.0)
    lam_sim = rng.uniform(0.5, 2.0, p_u)
    N = n if scalar else n * (p_v + p_u)
    A = rng.standard_normal((N, N))
    sig = A @ A.T / N + 0.5 * np.eye(N)
    u = rng.standard_normal((n, p_u))
    v = np.zeros((n, 0)) if scalar else rng.standard_normal((n, p_v))
    G = 1 if groups is None else max(groups) + 1
    obs = ObsProblem(x_obs, u, v, sig, scalar, (), None, p_v, v_groups=groups, n_null=n_null)
    params = {
        "betaU": rng.uniform(0.5, 3.0, (p + q, p_u)),
        "lamUz": rng.uniform(0.8, 3.0, p_u),
        "lamWs": rng.uniform(80, 2000, p_u),
        "lamWOs": rng.uniform(80, 2000, 1),
        "theta": np.array([rng.uniform(0.2, 0.8), 0.5 if cat else rng.uniform(0.2, 0.8)]),
        "lamOs": rng.uniform(1, 50, 1),
    }
    if p_v:
        params.update(betaV=rng.uniform(0.5, 3.0, (p, G)), lamVz=rng.uniform(1, 30, G))
    mb = None if mean is None else MeanBasis(mean, p + q)
    prob = Problem(x, t, w, lam_sim, priors or Priors().with_data((0, 0)), params, frozenset(),
                   obs, categorical=mask, mean_basis=mb,
                   fixed_elements=fixed_elements or {})  # fmt: skip
    return prob, params


CASES = {
    "categorical": {"cat": True},
    "linear mean": {"mean": "linear"},
    "constant mean, categorical, scalar": dict(
        mean="constant", cat=True, scalar=True, p_v=1, p_u=1
    ),
    "two groups, three v": {"p_v": 3, "groups": (1, 0, 1)},
    "unobserved directions": {"n_null": 3, "p_v": 1},
    "one scalar observation": {"n": 1, "scalar": True, "p_v": 0, "p_u": 1},
    "two runs": {"m": 2},  # the packed triangle of one block (two runs)
    "one run": {"m": 1, "p_v": 1},
}


@pytest.mark.parametrize("case", CASES)
def test_reference_and_incremental_match_a_dense_normal(case):
    prob, prm = make_problem(5, **CASES[case])
    want = dense_reference(prob, prm)
    assert log_likelihood(prob, prm) == pytest.approx(want, rel=1e-9, abs=1e-8)
    lik = IncrementalLikelihood(prob, prm)
    assert lik.loglik == pytest.approx(want, rel=1e-9, abs=1e-8)


@pytest.mark.parametrize("case", CASES)
def test_incremental_proposals_match_a_dense_normal(case):
    prob, prm = make_problem(6, **CASES[case])
    lik = IncrementalLikelihood(prob, prm)
    rng = np.random.default_rng(1)
    levels = np.array([0.0, 0.5, 1.0])
    for name, idx in elements(prob):
        if prob.categorical is not None and name == "theta" and idx == (1,):
            cand = float(levels[levels != lik.params["theta"][1]][0])  # another level
        else:
            cand = float(lik.params[name][idx]) * rng.uniform(0.6, 1.4)
        trial = {k: v.copy() for k, v in lik.params.items()}
        trial[name][idx] = cand
        got = lik.propose(name, idx, cand)
        assert got == pytest.approx(dense_reference(prob, trial), rel=1e-9, abs=1e-8), name
        lik.accept()  # every proposal taken: each one starts from the last
        assert lik.loglik == pytest.approx(dense_reference(prob, lik.params), rel=1e-9)
    theta = np.array([0.3, 1.0]) if prob.categorical is not None else np.array([0.3, 0.6])
    got = lik.propose_theta(theta)
    assert got == pytest.approx(dense_reference(prob, {**lik.params, "theta": theta}), rel=1e-9)
    lik.accept()
    assert np.array_equal(lik.params["theta"], theta)


def test_a_covariance_that_is_not_positive_definite_gives_minus_infinity():
    prob, prm = make_problem(2, p_v=1)
    for name, value in (("lamUz", [-1.0, 1.0]), ("lamOs", [-1.0]), ("lamVz", [-1e-3])):
        bad = {**prm, name: np.array(value)}
        assert log_likelihood(prob, bad) == -np.inf, name
        lik = IncrementalLikelihood(prob, prm)
        assert lik.propose(name, (0,), value[0]) == -np.inf, name
        assert lik.propose(name, (0,), float(prm[name][0])) == pytest.approx(
            dense_reference(prob, prm), rel=1e-9
        )  # a rejected -inf proposal leaves the state as it was
    one, prm1 = make_problem(2, n=1, scalar=True, p_v=0, p_u=1)
    lik = IncrementalLikelihood(one, prm1)
    assert lik.propose("lamOs", (0,), -1.0) == -np.inf  # one scalar observation: var < 0
    bad_w = {**prm, "lamWs": np.array([-1.0, prm["lamWs"][1]])}
    sim_only = Problem(prob.x_sim, prob.t_sim, prob.w, prob.lam_sim, prob.priors,
                       {k: prm[k] for k in ("betaU", "lamUz", "lamWs", "lamWOs")})  # fmt: skip
    assert log_likelihood(sim_only, bad_w) == -np.inf


def test_log_prior_takes_off_the_held_elements_own_priors():
    priors = Priors(theta_mean=(0.3, 0.7), theta_sd=(0.2, 0.4), rhoV_a=(1.0, 3.0),
                    rhoV_b=(0.1, 0.5), lamVz=(GammaPrior(2.0, 0.1), GammaPrior(3.0, 0.5)),
                    ).with_data((0, 0))  # fmt: skip
    # per-element and per-group priors: a held element's own prior is its element's, its group's
    held = {"betaU": frozenset({(2, 1)}), "theta": frozenset({(1,)}),
            "lamVz": frozenset({(1,)}), "betaV": frozenset({(0, 1)})}  # fmt: skip
    prob, prm = make_problem(3, p_v=2, groups=(0, 1), priors=priors, fixed_elements=held)
    f = priors.scalar_log_prior
    want = 0.0
    for name, idx in elements(prob):  # the sampled elements' own priors, one by one
        col = idx[-1] if name != "theta" else idx[0]
        want += f(name, col)(float(prm[name][idx]))
    assert log_prior(prob, prm) == pytest.approx(want, rel=1e-12)
    assert log_posterior(prob, prm) == pytest.approx(want + log_likelihood(prob, prm), rel=1e-12)
    # a categorical theta element held: its uniform prior counts 0 in the whole-array prior too
    cprob, cprm = make_problem(3, cat=True, fixed_elements={"theta": frozenset({(1,)})})
    want = Priors().with_data((0, 0)).scalar_log_prior("theta", 0)(cprm["theta"][0])
    assert want < 0.0
    for name in ("betaU", "betaV", "lamVz", "lamUz", "lamWs", "lamWOs", "lamOs"):
        want += cprob.priors.log_prior(name, cprm[name])
    assert log_prior(cprob, cprm) == pytest.approx(want, rel=1e-12)


@pytest.mark.parametrize("var", [0.0, -0.5, -2.0])
def test_one_scalar_observation_of_no_positive_variance_is_minus_infinity(var):
    """The 1 x 1 shortcut answers as the Cholesky path does: -inf, not an error."""
    prob, prm = make_problem(2, n=1, scalar=True, p_v=0, p_u=1)
    lik = IncrementalLikelihood(prob, prm)
    c = prob.obs.sig_obs / prm["lamOs"][0]
    assert lik._vu([(np.zeros(1), var - c)], None, prm) == -np.inf
    r = float(prob.obs.z[0] - 0.25)
    got = lik._vu([(np.array([0.25]), 2.0 - c)], None, prm)
    assert got == pytest.approx(-0.5 * math.log(2.0) - 0.25 * r * r, rel=1e-12)
