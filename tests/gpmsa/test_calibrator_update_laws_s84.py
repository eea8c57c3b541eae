"""The Calibrator's grid update against a dense brute-force grid (session 84, mutation testing of
the online grid path): with a firm theta prior the posterior is the likelihood times that prior,
on the fixed grid and on a refined one (mean, sd and, for one parameter, the evidence), and a
user prior reaches the update in the shapes its docstring states."""

from __future__ import annotations

import numpy as np
import pytest
from _calib_cases import one_t_emulator, two_param_emulator
from scipy.integrate import trapezoid

import gpmsa
from gpmsa import Calibrator

X2 = [[0.2], [0.5], [0.8]]
Y2 = [[float(np.sin(2 * x + 0.9) + 0.4 * x)] for x in (0.2, 0.5, 0.8)]  # a = 0.6, b = 0.5


def _dense_one(emu, x, y, mean: float, sd: float) -> tuple[float, float, float]:
    """(mean, sd, log evidence) of the likelihood (a 4097-node grid) times the truncated normal
    theta prior (mean, sd) on the unit scale."""
    g, ll = Calibrator(emu, method="grid", n_grid=4097).log_likelihood_grid(x, y)
    lo, hi = emu.domain["t"]
    u = (g - lo) / (hi - lo)
    lp = -0.5 * ((u - mean) / sd) ** 2
    f = np.exp(ll + lp - np.max(ll + lp))
    z = trapezoid(f, g)
    m = trapezoid(g * f, g) / z
    s = np.sqrt(trapezoid((g - m) ** 2 * f, g) / z)
    evidence = np.log(trapezoid(np.exp(ll + lp), u)) - np.log(trapezoid(np.exp(lp), u))
    return m, s, evidence


@pytest.mark.parametrize(("n_grid", "refined"), [(33, False), (9, True)])
def test_one_parameter_posterior_is_the_likelihood_times_a_firm_theta_prior(n_grid, refined):
    emu, x, y = one_t_emulator()
    firm = emu.with_calibration_priors(theta_mean=0.4, theta_sd=0.1)
    mean, sd, evidence = _dense_one(firm, x, y, 0.4, 0.1)
    post = Calibrator(firm, method="grid", n_grid=n_grid).update(x, y)
    assert post.info["refined"] is refined
    assert post.mean("t") == pytest.approx(mean, abs=0.002 * sd)
    assert post.sd("t") == pytest.approx(sd, rel=0.002)
    assert post.info["log_evidence"] == pytest.approx(evidence, abs=1e-4)
    free = Calibrator(emu, method="grid", n_grid=n_grid).update(x, y)
    assert free.mean("t") - post.mean("t") > 1.0 * sd  # the prior (at 0.4) moves it a long way


def test_two_parameter_posterior_is_the_likelihood_times_a_firm_theta_prior():
    emu = two_param_emulator().with_calibration_priors(theta_mean=0.3, theta_sd=0.08)
    g, ll = Calibrator(emu, method="grid", n_grid=97).log_likelihood_grid(X2, Y2)
    lo = np.array([emu.domain["a"][0], emu.domain["b"][0]])
    hi = np.array([emu.domain["a"][1], emu.domain["b"][1]])
    u = (g - lo) / (hi - lo)
    logp = ll - 0.5 * np.sum(((u - 0.3) / 0.08) ** 2, axis=1)
    f = np.exp(logp - logp.max()).reshape(97, 97)
    axes = [g[::97, 0], g[:97, 1]]
    post = Calibrator(emu, method="grid", n_grid=17).update(X2, Y2)
    assert post.info["refined"] is True
    for k, name in enumerate(("a", "b")):
        marg = trapezoid(f, axes[1], axis=1) if k == 0 else trapezoid(f, axes[0], axis=0)
        z = trapezoid(marg, axes[k])
        m = trapezoid(axes[k] * marg, axes[k]) / z
        s = np.sqrt(trapezoid((axes[k] - m) ** 2 * marg, axes[k]) / z)
        assert post.mean(name) == pytest.approx(m, abs=0.03 * s)
        assert post.sd(name) == pytest.approx(s, rel=0.03)


def test_a_callable_prior_gets_a_vector_for_one_parameter_and_pairs_for_two():
    emu, x, y = one_t_emulator()
    shapes = []

    def prior(t):
        shapes.append(np.shape(t))
        return -0.5 * ((np.asarray(t) - 0.5) / 0.2) ** 2

    cal = Calibrator(emu, method="grid", n_grid=33)
    post = cal.update(x, y, prior=prior)
    assert shapes and all(len(s) == 1 for s in shapes)  # (k,), as the docstring says
    table = prior(cal.theta_grid)
    same = Calibrator(emu, method="grid", n_grid=33).update(x, y, prior=table)
    assert post.mean("t") == pytest.approx(same.mean("t"), abs=1e-3 * same.sd("t"))
    shapes.clear()
    two = Calibrator(two_param_emulator(), method="grid", n_grid=17)
    two.update(X2, Y2, prior=lambda t: (shapes.append(np.shape(t)), -np.sum(t**2, axis=1))[1])
    assert shapes and all(len(s) == 2 and s[1] == 2 for s in shapes)


def test_a_two_parameter_prior_on_the_square_grid_is_the_flat_one():
    cal = Calibrator(two_param_emulator(), method="grid", n_grid=17)
    g = cal.theta_grid
    flat = -0.5 * ((g[:, 0] - 0.55) / 0.05) ** 2 - 0.5 * ((g[:, 1] - 0.4) / 0.1) ** 2
    square = flat.reshape(17, 17)  # rows: the first parameter
    a = cal.update(X2, Y2, prior=flat, seed=1)
    b = cal.update(X2, Y2, prior=square, seed=1)
    for name in ("a", "b"):
        assert b.mean(name) == a.mean(name) and b.sd(name) == a.sd(name)
    assert b.info["resolution"] == a.info["resolution"]
    c = cal.update(X2, Y2, prior=square.T.copy(), seed=1)  # the transpose is another prior
    assert abs(c.mean("a") - a.mean("a")) > 0.1 * a.sd("a")


def test_expected_inverse_lamos_is_given_at_the_nodes_of_a_trimmed_marginal():
    emu, x, y = one_t_emulator()
    cal = Calibrator(emu, method="grid", n_grid=129)
    free = cal.update(x, y)
    prior = np.zeros(129)
    prior[:20] = -np.inf  # zero below: the marginal keeps node 19 and those above
    post = cal.update(x, y, prior=prior)
    assert post.info["refined"] is False
    nodes = post.grids["t"].nodes
    np.testing.assert_array_equal(nodes, cal.theta_grid[19:])
    inv = post.info["expected_inv_lamOs"]
    assert len(inv) == nodes.size  # E[1/lamOs | data, theta] per node: the prior's no matter
    np.testing.assert_allclose(inv, free.info["expected_inv_lamOs"][19:], rtol=1e-12)


def test_a_resolved_two_parameter_update_reports_its_resolution_and_ridge_measure():
    cal = Calibrator(two_param_emulator(), method="grid", n_grid=33)
    post = cal.update(X2[:1], Y2[:1])
    assert post.info["refined"] is False
    res, sds = post.info["resolution"], post.info["conditional_sds"]
    assert len(res) == 2 and all(isinstance(r, float) and r >= 1.5 for r in res)
    assert len(sds) == 2 and all(s > 0.5 for s in sds)


def test_a_gridded_prior_with_zeros_holds_along_a_refined_level():
    """A categorical and a continuous parameter: a gridded prior zero below a line keeps the
    refined levels' posterior at zero there (its zero edges kept on the refined axis)."""
    rng = np.random.default_rng(2)
    x = rng.random((60, 1))
    t = np.column_stack([np.arange(60) % 3, rng.random(60)])
    f = lambda x, t: np.sin(3 * x[:, 0]) + t[:, 1] + 0.5 * t[:, 0]  # noqa: E731
    sim = gpmsa.SimData(x, t, f(x, t), x_names=["s"], t_names=["kind", "k"],
                        t_categorical=["kind"])  # fmt: skip
    emu = gpmsa.Emulator.from_params(sim, {"betaU": [[2.0], [1.0], [1.0]], "lamUz": [1.0],
                                           "lamWs": [1e4], "lamWOs": [1e5]})  # fmt: skip
    xo = np.linspace(0.1, 0.9, 6)[:, None]
    yo = f(xo, np.tile([1, 0.4], (6, 1))) + rng.normal(0, 0.002, 6)
    cal = Calibrator(emu, n_grid=17, seed=1)
    grid = cal.theta_grid
    prior = np.where(grid[:, 1] < 0.36, -np.inf, 0.0)  # zero up to the node below 0.36
    edge = grid[:, 1][grid[:, 1] < 0.36].max()
    post = cal.update(xo, yo, prior=prior)
    free = cal.update(xo, yo)
    assert post.info["refined"] and free.info["refined"]
    assert post.grids["k"].cdf(edge) == 0.0
    assert free.grids["k"].cdf(edge) > 1e-8  # the prior cuts what mass the data leave there
