"""The GPM/SA log-likelihood against a direct dense formula; the incremental form against both."""

import numpy as np
import pytest

from gpmsa.mcmc.sampler import elements
from gpmsa.model.correlation import correlation
from gpmsa.model.likelihood import IncrementalLikelihood, log_likelihood, log_posterior, log_prior
from gpmsa.model.priors import Priors
from gpmsa.model.problem import ObsProblem, Problem


def random_problem(seed: int, p: int, q: int, p_u: int, n: int, p_v: int, scalar: bool):
    """A small random problem (no data pipeline: the likelihood sees only unit-scale arrays)."""
    rng = np.random.default_rng(seed)
    m = 14
    x, t = rng.random((m, p)), rng.random((m, q))
    w = rng.standard_normal((m, p_u))
    lam_sim = rng.uniform(0.5, 2.0, p_u)
    obs = None
    if n:
        N = n if scalar else n * (p_v + p_u)
        A = rng.standard_normal((N, N))
        sig = A @ A.T / N + 0.5 * np.eye(N)
        u = rng.standard_normal((n, p_u))
        v = np.zeros((n, 0)) if scalar else rng.standard_normal((n, p_v))
        obs = ObsProblem(rng.random((n, p)), u, v, sig, scalar, (), None, p_v)
    params = {
        "betaU": rng.uniform(0.2, 3.0, (p + q, p_u)),
        "lamUz": rng.uniform(0.5, 3.0, p_u),
        "lamWs": rng.uniform(80, 2000, p_u),
        "lamWOs": rng.uniform(80, 2000, 1),
    }
    if n:
        params.update(theta=rng.uniform(0.1, 0.9, q), lamOs=rng.uniform(1, 50, 1))
        if p_v:
            params.update(betaV=rng.uniform(0.2, 3.0, (p, 1)), lamVz=rng.uniform(1, 30, 1))
    prob = Problem(x, t, w, lam_sim, Priors().with_data((0, 0)), params, frozenset(), obs)
    return prob, params, p_v


def dense_loglik(prob: Problem, prm: dict, p_v: int) -> float:
    """-1/2 log det S - 1/2 z^T S^-1 z for the joint vector [v; u; w] (or [u + v; w])."""
    m, p_u = prob.m, prob.p_u
    zt = np.hstack([prob.x_sim, prob.t_sim])
    blocks_w = []
    for j in range(p_u):
        S = correlation(zt, None, prm["betaU"][:, j]) / prm["lamUz"][j]
        S += np.eye(m) * (1 / (prob.lam_sim[j] * prm["lamWOs"][0]) + 1 / prm["lamWs"][j])
        blocks_w.append(S)
    obs = prob.obs
    if obs is None:
        cov = np.zeros((m * p_u, m * p_u))
        for j, S in enumerate(blocks_w):
            cov[j * m : (j + 1) * m, j * m : (j + 1) * m] = S
        z = prob.w.T.reshape(-1)
    else:
        n = obs.n
        xt = np.hstack([obs.x, np.tile(prm["theta"], (n, 1))])
        n_obs = n if obs.scalar_out else n * (p_v + p_u)
        tot = n_obs + m * p_u
        cov = np.zeros((tot, tot))
        for j, S in enumerate(blocks_w):
            o = n_obs + j * m
            cov[o : o + m, o : o + m] = S
            su = (
                correlation(xt, None, prm["betaU"][:, j]) / prm["lamUz"][j]
                + np.eye(n) / prm["lamWs"][j]
            )
            suw = correlation(xt, zt, prm["betaU"][:, j]) / prm["lamUz"][j]
            ou = 0 if obs.scalar_out else n * (p_v + j)
            cov[ou : ou + n, ou : ou + n] += su
            cov[ou : ou + n, o : o + m] = suw
            cov[o : o + m, ou : ou + n] = suw.T
        if p_v:
            sv = correlation(obs.x, None, prm["betaV"][:, 0]) / prm["lamVz"][0]
            for i in range(1 if obs.scalar_out else p_v):
                cov[i * n : (i + 1) * n, i * n : (i + 1) * n] += sv
        cov[:n_obs, :n_obs] += obs.sig_obs / prm["lamOs"][0]
        z = np.concatenate([obs.z, prob.w.T.reshape(-1)])
    sign, logdet = np.linalg.slogdet(cov)
    assert sign > 0
    return -0.5 * logdet - 0.5 * float(z @ np.linalg.solve(cov, z))


CASES = [
    # (p, q, p_u, n, p_v, scalar)
    (1, 1, 1, 0, 0, True),
    (2, 1, 3, 0, 0, False),
    (1, 1, 1, 3, 0, True),
    (1, 1, 1, 1, 0, True),
    (2, 1, 1, 1, 1, True),
    (1, 1, 1, 2, 1, True),
    (2, 2, 2, 3, 0, False),
    (1, 2, 3, 4, 2, False),
]


@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("seed", [0, 1])
def test_reference_loglik_matches_dense_formula(case, seed):
    prob, prm, p_v = random_problem(seed, *case)
    assert log_likelihood(prob, prm) == pytest.approx(
        dense_loglik(prob, prm, p_v), rel=1e-9, abs=1e-7
    )


@pytest.mark.parametrize("case", CASES)
def test_incremental_matches_reference_through_proposals(case):
    prob, prm, _ = random_problem(7, *case)
    lik = IncrementalLikelihood(prob, prm)
    assert lik.loglik == pytest.approx(log_likelihood(prob, prm), rel=1e-10, abs=1e-8)
    rng = np.random.default_rng(3)
    for name, idx in elements(prob) * 2:
        cand = float(lik.params[name][idx]) * rng.uniform(0.7, 1.3)
        trial = {k: v.copy() for k, v in lik.params.items()}
        trial[name][idx] = cand
        got = lik.propose(name, idx, cand)
        assert got == pytest.approx(log_likelihood(prob, trial), rel=1e-10, abs=1e-8), name
        if rng.random() < 0.5:
            lik.accept()
        expected = log_likelihood(prob, lik.params)
        assert lik.loglik == pytest.approx(expected, rel=1e-10, abs=1e-8)


def test_log_posterior_adds_priors_of_sampled_params_only():
    prob, prm, _ = random_problem(2, 1, 1, 1, 2, 0, True)
    pri = prob.priors
    expected = sum(pri.log_prior(k, prm[k]) for k in prm)
    assert log_prior(prob, prm) == pytest.approx(expected)
    fixed = Problem(prob.x_sim, prob.t_sim, prob.w, prob.lam_sim, pri, prm,
                    frozenset({"betaU", "lamUz", "lamWs", "lamWOs"}), prob.obs)  # fmt: skip
    lp = pri.log_prior("theta", prm["theta"]) + pri.log_prior("lamOs", prm["lamOs"])
    assert log_posterior(fixed, prm) == pytest.approx(log_likelihood(prob, prm) + lp)


def test_priors_match_gpmsa_formulas_and_bounds():
    pri = Priors()
    # Gamma(5, 5) on lamUz, lower bound 0.3 (open)
    assert pri.log_prior("lamUz", np.array([2.0])) == pytest.approx(4 * np.log(2.0) - 10.0)
    assert pri.log_prior("lamUz", np.array([0.3])) == -np.inf
    assert pri.log_prior("lamWs", np.array([1e5])) == -np.inf
    # Beta(1, 0.1) on rho = exp(-beta/4), capped at 0.999
    rho = np.exp(-0.25 * 0.8)
    assert pri.log_prior("betaU", np.array([0.8])) == pytest.approx(-0.9 * np.log1p(-rho))
    assert pri.log_prior("betaU", np.array([1e-6])) == pytest.approx(-0.9 * np.log(1 - 0.999))
    assert pri.log_prior("betaU", np.array([0.0])) == -np.inf
    assert pri.log_prior("theta", np.array([1.0])) == -np.inf
    for name, x in [("theta", 0.3), ("betaU", 1.7), ("lamOs", 12.0), ("lamWOs", 500.0)]:
        f = pri.scalar_log_prior(name)
        assert f(x) == pytest.approx(pri.log_prior(name, np.array([x])))
    corrected = pri.with_data((10.0, 2.0), (1.5, 0.25))
    assert corrected.lamWOs.a == 15.0 and corrected.lamWOs.b == pytest.approx(2.005)
    assert corrected.lamOs.a == 2.5 and corrected.with_data((1, 1)) is corrected
    assert Priors.from_dict(corrected.to_dict()) == corrected
