"""The calibration-only model against dense formulas, adaptive quadrature and CORE's likelihood."""

import numpy as np
import pytest
from _calib_cases import road_emulator, road_obs, two_param_emulator, vector_emulator
from scipy.integrate import quad
from scipy.stats import gamma, multivariate_normal, norm

from gpmsa.calibration.calibrate import calibration_problem
from gpmsa.calibration.model import GridPredictor, LamOsPrior, chebyshev_plan, lamos_marginal
from gpmsa.calibration.observations import fixed_gp, reduce
from gpmsa.calibration.sampler import ThetaPredictive
from gpmsa.model.likelihood import log_likelihood


def dense_conditional(emu, x_unit, theta_unit, c=0):
    """mean and covariance of u_c at (x_j, theta) given w_c from the joint Gaussian (no solves
    shared with the code under test): joint covariance of [u; w], conditioned by numpy.linalg."""
    prm = emu.params
    beta = prm["betaU"][:, c]
    zt = np.hstack([emu.x_unit, emu.t_unit])
    zo = np.hstack([x_unit, np.tile(theta_unit, (x_unit.shape[0], 1))])

    def corr(a, b):
        d = a[:, None, :] - b[None, :, :]
        return np.exp(-np.sum(beta * d * d, axis=2))

    lam_uz, lam_ws, lam_wos = prm["lamUz"][c], prm["lamWs"][c], prm["lamWOs"][0]
    s_w = corr(zt, zt) / lam_uz + np.eye(len(zt)) * (1 / (emu.lam_sim[c] * lam_wos) + 1 / lam_ws)
    s_u = corr(zo, zo) / lam_uz + np.eye(len(zo)) / lam_ws
    s_uw = corr(zo, zt) / lam_uz
    mean = s_uw @ np.linalg.solve(s_w, emu.w[:, c])
    cov = s_u - s_uw @ np.linalg.solve(s_w, s_uw.T)
    return mean, cov


@pytest.mark.parametrize("theta", [0.0, 0.31, 0.77, 1.0])
def test_predict_matches_dense_conditional(theta):
    emu = road_emulator()
    gp = fixed_gp(emu)
    x = np.array([[0.2], [0.5], [0.93]])
    mean, cov = gp.predict(x, np.array([[theta]]))
    m_ref, c_ref = dense_conditional(emu, x, np.array([theta]))
    np.testing.assert_allclose(mean[0, 0], m_ref, rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(cov[0, 0], c_ref, rtol=1e-7, atol=1e-11)


def test_predict_vector_output_components():
    emu = vector_emulator()
    gp = fixed_gp(emu)
    x = np.array([[0.1], [0.6]])
    mean, cov = gp.predict(x, np.array([[0.4]]))
    for c in range(emu.p_u):
        m_ref, c_ref = dense_conditional(emu, x, np.array([0.4]), c)
        np.testing.assert_allclose(mean[0, c], m_ref, rtol=1e-8, atol=1e-10)
        np.testing.assert_allclose(cov[0, c], c_ref, rtol=1e-6, atol=1e-11)


def test_grid_predictor_chebyshev_matches_dense():
    gp = fixed_gp(road_emulator())
    theta = np.linspace(0, 1, 33)[:, None]
    pred = GridPredictor(gp, theta, chebyshev_plan(gp))
    assert pred.H is not None  # the expansion converged
    for xv in (0.0, 0.123, 0.5, 0.999, 1.0):
        x = np.array([[xv]])
        m1, c1 = pred.predict(x)
        m2, c2 = gp.predict(x, theta)
        np.testing.assert_allclose(m1, m2, rtol=0, atol=1e-11)
        np.testing.assert_allclose(c1, c2, rtol=1e-9, atol=1e-13)


def test_grid_predictor_outside_unit_range_uses_dense():
    gp = fixed_gp(road_emulator())
    theta = np.linspace(0, 1, 9)[:, None]
    x = np.array([[1.05]])
    m1, c1 = GridPredictor(gp, theta, chebyshev_plan(gp)).predict(x)
    m2, c2 = gp.predict(x, theta)
    np.testing.assert_array_equal(m1, m2)
    np.testing.assert_array_equal(c1, c2)


@pytest.mark.parametrize("shift", [0.0, 1.5, -3.0])
def test_lamos_marginal_matches_adaptive_quadrature(shift):
    gp = fixed_gp(road_emulator())
    theta = np.linspace(0, 1, 17)[:, None]
    mean, cov = gp.predict(np.array([[0.5]]), theta)
    u = np.array([0.1 + shift])
    prior = LamOsPrior(1.0, 0.001)
    marg = lamos_marginal(mean[:, 0], cov[:, 0], u, np.eye(1), prior)
    for g in (0, 5, 11, 16):
        m, v = mean[g, 0, 0], cov[g, 0, 0, 0]

        def f(lam, m=m, v=v):
            return norm.pdf(u[0], m, np.sqrt(v + 1 / lam)) * gamma.pdf(lam, 1.0, scale=1000.0)

        ref = np.log(quad(f, 0, np.inf, limit=1000, epsabs=0, epsrel=1e-13)[0])
        assert abs(marg.loglik[g] - ref) < 1e-6
    cond = np.exp(marg.log_cond(np.arange(17)))
    np.testing.assert_allclose(cond.sum(axis=1), 1.0, rtol=1e-12)


def test_lamos_marginal_multivariate_truncated_prior():
    rng = np.random.default_rng(0)
    G, d = 4, 3
    a = rng.standard_normal((G, d, d))
    cov = a @ a.transpose(0, 2, 1) * 0.01 + 0.002 * np.eye(d)
    mean = rng.standard_normal((G, d)) * 0.1
    u = rng.standard_normal(d) * 0.1
    s_obs = np.array([[1.0, 0.3, 0.0], [0.3, 1.0, 0.2], [0.0, 0.2, 1.0]])
    prior = LamOsPrior(2.5, 0.01, 5.0, 5000.0)
    marg = lamos_marginal(mean, cov, u, np.linalg.cholesky(s_obs), prior)
    z = gamma.cdf(5000, 2.5, scale=100) - gamma.cdf(5, 2.5, scale=100)
    for g in range(G):

        def f(lam, g=g):
            dens = multivariate_normal.pdf(u, mean[g], cov[g] + s_obs / lam)
            return dens * gamma.pdf(lam, 2.5, scale=100) / z

        ref = np.log(quad(f, 5, 5000, limit=500, epsabs=0, epsrel=1e-12)[0])
        assert abs(marg.loglik[g] - ref) < 1e-6


def test_conditional_likelihood_differences_match_core_likelihood():
    """At fixed lamOs, our log p(u | theta, lamOs) differs between thetas exactly as CORE's
    full GPM/SA log-likelihood does (its first term is constant in theta)."""
    emu = road_emulator()
    x_obs, y_obs = road_obs()
    problem = calibration_problem(emu, x_obs, y_obs)
    data = reduce(emu, x_obs, y_obs)
    gp = fixed_gp(emu)
    lam = 700.0
    thetas = np.array([[0.2], [0.45], [0.6], [0.9]])
    mean, cov = gp.predict(data.x, thetas)
    var = cov[:, 0, 0, 0] + data.obs.sig_obs[0, 0] / lam
    ours = -0.5 * (np.log(var) + (data.z[0] - mean[:, 0, 0]) ** 2 / var)
    core = np.array(
        [log_likelihood(problem, {**problem.init, "theta": t, "lamOs": np.array([lam])})
         for t in thetas]
    )  # fmt: skip
    np.testing.assert_allclose(ours - ours[0], core - core[0], rtol=0, atol=1e-8)


def test_lamos_marginal_scalar_rows_that_underflow_fall_back_to_log_space():
    """A sharp lamOs prior far from what the residuals want: the linear-space pass underflows
    and those rows are recomputed in log space."""
    mean = np.array([[0.0], [0.5], [4.0]])
    cov = np.full((3, 1, 1), 0.01)
    u = np.array([0.0])
    prior = LamOsPrior(3000.0, 3.0)
    marg = lamos_marginal(mean, cov, u, np.eye(1), prior)
    assert np.all(np.isfinite(marg.loglik))
    for g in range(3):

        def f(lam, g=g):
            logp = norm.logpdf(0.0, mean[g, 0], np.sqrt(0.01 + 1 / lam))
            return np.exp(logp + gamma.logpdf(lam, 3000.0, scale=1 / 3.0) + 700.0)

        ref = np.log(quad(f, 800, 1250, points=[1000], limit=500, epsrel=1e-12)[0]) - 700.0
        assert abs(marg.loglik[g] - ref) < 1e-6


@pytest.mark.parametrize("case", ["road", "vector", "two"])
def test_sampler_chebyshev_predictive_matches_dense(case):
    if case == "road":
        emu, (x, y) = road_emulator(), road_obs()
    elif case == "vector":
        emu = vector_emulator()
        x, y = [[0.4]], [np.sin(np.pi * np.linspace(0, 1, 8) * 0.9)]
    else:
        emu, x, y = two_param_emulator(), [[0.3]], [[0.9]]
    data = reduce(emu, x, y)
    fast = ThetaPredictive(fixed_gp(emu), data)
    dense = ThetaPredictive(fixed_gp(emu), data)
    dense.cheb = dense.cheb2 = None
    assert fast.cheb is not None or fast.cheb2 is not None
    rng = np.random.default_rng(0)
    for theta in rng.uniform(0, 1, (20, emu.q)):
        (e1, y1), (e2, y2) = fast.at(list(theta)), dense.at(list(theta))
        np.testing.assert_allclose(e1, e2, rtol=1e-9, atol=1e-14)
        np.testing.assert_allclose(y1, y2, rtol=1e-8, atol=1e-12)
