"""Posterior and its exact grid representation."""

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest
from matplotlib.figure import Figure
from scipy.stats import norm

from gpmsa import GPMSAError, Posterior, ResourceLimitError
from gpmsa.calibration.posterior import GridMarginal


def gaussian_grid(mu=3.0, sd=0.7, n=201):
    nodes = np.linspace(mu - 9 * sd, mu + 9 * sd, n)
    return GridMarginal.from_log_density(nodes, norm.logpdf(nodes, mu, sd) + 17.0)


def test_grid_moments_of_a_resolved_gaussian():
    g = gaussian_grid()
    assert g.mean() == pytest.approx(3.0, abs=1e-12)
    assert g.sd() == pytest.approx(0.7, rel=1e-10)
    assert float(np.sum(g.weights * g.density)) == pytest.approx(1.0, rel=1e-13)


def test_grid_cdf_ppf_are_inverse_and_close_to_the_gaussian():
    g = gaussian_grid()
    q = np.array([0.001, 0.05, 0.3, 0.5, 0.9, 0.999])
    x = g.ppf(q)
    np.testing.assert_allclose(g.cdf(x), q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(x, norm.ppf(q, 3.0, 0.7), atol=2e-3)  # O(h^2) interpolation
    assert g.cdf(-100.0) == 0.0 and g.cdf(100.0) == 1.0


def test_grid_draws_follow_the_density():
    g = gaussian_grid()
    draws = g.sample(np.random.default_rng(0), 40_000)
    se = 0.7 / np.sqrt(draws.size)
    assert abs(draws.mean() - 3.0) < 4 * se
    assert abs(draws.std() - 0.7) < 4 * 0.7 / np.sqrt(2 * draws.size) + 1e-3


def test_posterior_from_samples():
    rng = np.random.default_rng(1)
    s = {"GD": rng.normal(400, 20, 20_000), "lamOs": rng.gamma(2.0, 500.0, 20_000)}
    post = Posterior(s, info={"method": "mcmc"})
    assert post.mean("GD") == pytest.approx(s["GD"].mean())
    assert post.sd("GD") == pytest.approx(s["GD"].std(ddof=1))
    lo, hi = post.interval("GD", 0.9)
    assert lo == pytest.approx(np.quantile(s["GD"], 0.05))
    assert hi == pytest.approx(np.quantile(s["GD"], 0.95))
    assert post.prob_above("GD", 420) == pytest.approx(np.mean(s["GD"] > 420))
    summ = post.summary()
    assert set(summ) == {"GD", "lamOs"} and summ["GD"]["n_draws"] == 20_000
    assert not summ["GD"]["exact_grid"]


def test_posterior_grid_summaries_come_from_the_grid():
    g = gaussian_grid(400.0, 20.0)
    calls = []

    def draw():
        calls.append(1)
        return {"GD": g.sample(np.random.default_rng(2), 1000)}

    post = Posterior(grids={"GD": g}, draw=draw, info={"names": ("GD",)})
    assert post.mean("GD") == pytest.approx(400.0, abs=1e-9)
    assert post.prob_above("GD", 400.0) == pytest.approx(0.5, abs=1e-9)
    assert post.quantile("GD", 0.95) == pytest.approx(norm.ppf(0.95, 400, 20), abs=0.1)
    assert not calls  # draws are lazy
    assert post.samples["GD"].shape == (1000,) and len(calls) == 1
    assert post.samples["GD"].shape == (1000,) and len(calls) == 1  # drawn once


def test_posterior_arviz_and_plot():
    rng = np.random.default_rng(3)
    chains = {"GD": rng.normal(400, 20, (2, 500)), "lamOs": rng.gamma(2.0, 500.0, (2, 500))}
    post = Posterior({k: v.reshape(-1) for k, v in chains.items()}, chains=chains)
    idata = post.to_arviz()
    assert idata.posterior["GD"].shape == (2, 500)
    fig = post.plot("GD")
    assert isinstance(fig, Figure) and len(fig.axes) == 2
    assert fig.axes[0].get_xlabel() == "GD"
    post = Posterior(post.samples, chains=chains, info={"units": {"GD": "1e-6 m^3"}})
    assert post.plot("GD").axes[0].get_xlabel() == "GD (1e-6 m^3)"  # calibrate's units
    assert post.plot("GD", unit="um^3").axes[1].get_ylabel() == "GD (um^3)"


def test_posterior_bad_arguments():
    post = Posterior({"GD": np.arange(10.0)})
    with pytest.raises(GPMSAError, match="unknown parameter 'gd'"):
        post.mean("gd")
    with pytest.raises(GPMSAError, match=r"q must lie in \[0, 1\], got 1.5"):
        post.quantile("GD", 1.5)
    for level in (1.0, "0.9", True, [0.9], np.nan):
        with pytest.raises(GPMSAError, match=r"level must be a number in \(0, 1\), got"):
            post.interval("GD", level)
    with pytest.raises(GPMSAError, match="value must be finite"):
        post.prob_above("GD", np.nan)
    with pytest.raises(GPMSAError, match="needs samples or a draw"):
        Posterior()
    with pytest.raises(
        ResourceLimitError, match=r"Posterior.plot: a histogram of 1000000000 bins needs about"
    ):
        post.plot("GD", bins=10**9)
    for bins in (0, 2.5, "auto"):
        with pytest.raises(GPMSAError, match="bins must be an integer >= 1"):
            post.plot("GD", bins=bins)


@pytest.mark.parametrize(
    ("samples", "match"),
    [
        ([1.0, 2.0], "samples must be a dict"),
        (
            {"a": []},
            r"samples\['a'\] must be the draws \(n_draws,\) of one scalar parameter, at "
            r"least one, got shape \(0,\)",
        ),  # fmt: skip
        ({"a": np.ones((5, 2))}, r"got shape \(5, 2\) \(name each element of a vector"),
        ({"a": [np.nan, 1.0]}, r"samples\['a'\] must be finite"),
        ({"a": ["x", "y"]}, r"samples\['a'\] must be a numeric array"),
        ({"a": np.ones(3, complex)}, r"samples\['a'\] must hold real numbers"),
        ({1: [1.0]}, "parameter names must be strings"),
    ],
)
def test_posterior_samples_are_checked_on_construction(samples, match):
    with pytest.raises(GPMSAError, match=match):
        Posterior(samples)


def test_the_sd_of_one_draw_is_an_error_not_nan():
    with pytest.raises(GPMSAError, match="needs at least 2 draws"):
        Posterior({"a": [1.0]}).sd("a")
    row = Posterior({"a": [1.0]}).summary()["a"]  # the summary says it has no sd
    assert row["mean"] == row["median"] == 1.0 and np.isnan(row["sd"]) and row["n_draws"] == 1


@pytest.mark.parametrize(
    ("chains", "match"),
    [
        ([1.0], "chains must be a dict"),
        ({"a": "x"}, r"chains\['a'\] must be a numeric array"),
        ({"a": [[np.nan, 1.0]]}, r"chains\['a'\] must be finite"),
        ({"a": np.ones((2, 2, 2))}, r"chains\['a'\] must be \(n_chains, n_draws\)"),
        ({"a": [[1.0, 2.0]]}, r"chains lacks \['b'\]: give the chains of every parameter"),
    ],
)
def test_posterior_chains_are_checked_on_construction(chains, match):
    with pytest.raises(GPMSAError, match=match):
        Posterior({"a": [1.0, 2.0], "b": [3.0, 4.0]}, chains=chains)


def test_the_hdi_is_the_shortest_interval_and_reaches_a_bound_where_mass_piles_up():
    g = gaussian_grid()
    lo, hi = g.hdi(0.9)  # symmetric: the HDI is the central interval
    assert (lo, hi) == pytest.approx(tuple(norm.ppf([0.05, 0.95], 3.0, 0.7)), abs=2e-3)
    # skewed: exponential density on [0, 5]; its HDI starts at 0 and holds the level
    nodes = np.linspace(0.0, 5.0, 2001)
    expo = GridMarginal.from_log_density(nodes, -nodes)
    lo, hi = expo.hdi(0.9)
    assert lo == 0.0 and float(expo.cdf(hi) - expo.cdf(lo)) == pytest.approx(0.9, abs=1e-9)
    central = expo.ppf(np.array([0.05, 0.95]))
    assert hi - lo < central[1] - central[0] and central[0] > 0
    post = Posterior(grids={"x": expo}, draw=lambda: {}, info={"names": ("x",)})
    assert post.hdi("x", 0.9) == (lo, hi)


def test_the_hdi_of_draws_is_arviz_and_bad_arguments_are_named():
    draws = np.random.default_rng(4).exponential(size=20_000)
    post = Posterior(samples={"x": draws})
    lo, hi = post.hdi("x", 0.9)
    assert lo == pytest.approx(0.0, abs=0.01) and hi == pytest.approx(-np.log(0.1), rel=0.03)
    lazy = Posterior(draw=lambda: {"v": np.ones((20_000, 2))})  # checked when first drawn
    with pytest.raises(GPMSAError, match=r"samples\['v'\] must be the draws \(n_draws,\) of one"):
        lazy.hdi("v")
    with pytest.raises(GPMSAError, match="unknown parameter"):
        post.hdi("y")
    with pytest.raises(GPMSAError, match="level"):
        post.hdi("x", 1.5)


@pytest.mark.parametrize(
    ("nodes", "log_density", "message"),
    [
        ([0.5], [0.0], "at least 2 finite nodes"),
        ([0.0, np.nan, 1.0], [0.0, 0.0, 0.0], "finite and strictly increasing"),
        ([1.0, 0.5, 0.0], [0.0, 0.0, 0.0], "strictly increasing"),
        ([0.0, 0.5, 0.5], [0.0, 0.0, 0.0], "strictly increasing"),
        ([0.0, 0.5, 1.0], [0.0, 0.0], r"one value per node \(3,\), got \(2,\)"),
        ([0.0, 0.5, 1.0], [0.0, np.nan, 0.0], "NaN or \\+inf"),
        ([0.0, 0.5, 1.0], [0.0, np.inf, 0.0], "NaN or \\+inf"),
        ([0.0, 0.5, 1.0], [-np.inf] * 3, "no mass"),
    ],
)
def test_a_grid_marginal_of_bad_nodes_or_densities_is_refused(nodes, log_density, message):
    """Before: one node, unsorted nodes, NaN or no mass gave a NaN density (mean NaN) silently;
    a length mismatch failed inside numpy's matmul."""
    with pytest.raises(GPMSAError, match=message):
        GridMarginal.from_log_density(np.array(nodes), np.array(log_density))
    g = GridMarginal.from_log_density(np.array([0.0, 1.0]), np.array([-np.inf, 0.0]))
    assert g.mean() == pytest.approx(1.0) and g.ppf(1.0) == 1.0  # trapezoid moments


def test_a_lazy_draw_lacking_an_announced_parameter_is_named():
    """Before: summary() (or mean of a name only the draw had to give) raised a bare KeyError."""
    g = gaussian_grid()
    post = Posterior(grids={"b": g}, draw=lambda: {"a": np.arange(5.0)}, info={"names": ["a", "b"]})
    assert post.mean("b") == pytest.approx(3.0)  # from the grid: nothing drawn yet
    with pytest.raises(GPMSAError, match=r"returned samples of \('a',\).*\['b'\]"):
        post.summary()
    lazy = Posterior(draw=lambda: {"a": np.arange(5.0)}, info={"names": ["b"]})
    with pytest.raises(GPMSAError, match=r"\['b'\]"):
        lazy.mean("b")
    ok = Posterior(grids={"b": g}, draw=lambda: {"b": np.arange(5.0)}, info={"names": ["b"]})
    assert ok.summary()["b"]["n_draws"] == 5
