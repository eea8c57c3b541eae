"""Posterior, GridMarginal and LevelMarginal against hand-computed values (mutation testing of
gpmsa/calibration/posterior.py found each one free): trapezoid moments of a 3-node grid, its
CDF and quantiles cell by cell, a level posterior's lower quantiles and HDI, draws' summaries
against numpy."""

import dataclasses
import pickle
import typing

import numpy as np
import pytest
from scipy.stats import norm

from gpmsa import GPMSAError, Posterior
from gpmsa.calibration.posterior import GridMarginal, LevelMarginal, trapezoid_weights


def log(values: list[float]) -> np.ndarray:
    """Natural log, -inf at 0 without numpy's warning."""
    with np.errstate(divide="ignore"):
        return np.log(np.array(values))


def ramp_down() -> GridMarginal:
    """Nodes 0, 1, 3; density 1/2, 1/2, 0 (trapezoid weights 1/2, 3/2, 1: integral 1); cells
    of mass 1/2 each. CDF: x/2 on [0, 1]; 1/2 + (x-1)/2 - (x-1)^2/8 on [1, 3]."""
    return GridMarginal.from_log_density(np.array([0.0, 1.0, 3.0]), log([1.0, 1.0, 0.0]))


def two_lumps() -> GridMarginal:
    """Nodes 0..3, density 1, 0, 0, 1: mass 1/2 in [0, 1], none in [1, 2], 1/2 in [2, 3]."""
    return GridMarginal.from_log_density(np.arange(4.0), log([1.0, 0.0, 0.0, 1.0]))


def test_trapezoid_weights_of_uneven_nodes():
    np.testing.assert_array_equal(trapezoid_weights(np.array([0.0, 1.0, 3.0])), [0.5, 1.5, 1.0])
    np.testing.assert_array_equal(trapezoid_weights(np.array([0.0, 0.5])), [0.25, 0.25])


def test_grid_moments_of_a_three_node_triangle():
    """Density 1/3, 2/3, 1/3 on 0, 1, 2 (weights 1/2, 1, 1/2): mean 1, variance 1/3."""
    g = GridMarginal.from_log_density(np.array([0.0, 1.0, 2.0]), log([1.0, 2.0, 1.0]) + 5.0)
    np.testing.assert_allclose(g.density, [1 / 3, 2 / 3, 1 / 3], rtol=1e-15)
    np.testing.assert_array_equal(g.weights, [0.5, 1.0, 0.5])
    assert g.mean() == pytest.approx(1.0, rel=1e-15)
    assert g.sd() == pytest.approx(np.sqrt(1 / 3), rel=1e-15)


def test_grid_moments_and_given_weights_of_an_uneven_grid():
    g = ramp_down()
    np.testing.assert_array_equal(g.density, [0.5, 0.5, 0.0])
    np.testing.assert_array_equal(g.weights, [0.5, 1.5, 1.0])
    assert g.mean() == 0.75  # 1.5 * 0.5 * 1
    assert g.sd() == pytest.approx(np.sqrt(0.25 * 0.75**2 + 0.75 * 0.25**2), rel=1e-15)
    # the grid's weights when given are used as they are (here: twice the trapezoid's)
    g2 = GridMarginal.from_log_density(g.nodes, log([1.0, 1.0, 0.0]), 2 * g.weights)
    np.testing.assert_array_equal(g2.density, [0.25, 0.25, 0.0])


def test_grid_cdf_cell_by_cell():
    g = ramp_down()
    x = np.array([-1.0, 0.0, 0.5, 1.0, 2.0, 3.0, 5.0])
    np.testing.assert_allclose(g.cdf(x), [0.0, 0.0, 0.25, 0.5, 0.875, 1.0, 1.0], rtol=1e-15)
    assert g.cdf(2.0).shape == ()


def test_grid_quantiles_cell_by_cell():
    g = ramp_down()
    q = np.array([0.0, 0.25, 0.5, 0.875, 1.0])
    np.testing.assert_allclose(g.ppf(q), [0.0, 0.5, 1.0, 2.0, 3.0], rtol=1e-15, atol=0)
    # a rising cell from zero density: F = (x - 2)^2 / 2 above 1/2, x = 2 + sqrt(2 (q - 1/2))
    h = two_lumps()
    np.testing.assert_allclose(
        h.ppf(np.array([0.0, 0.125, 0.5, 0.625, 1.0])),
        [0.0, 1 - np.sqrt(0.75), 1.0, 2.5, 3.0],
        rtol=1e-15,
    )
    np.testing.assert_allclose(h.cdf(np.array([1.0, 1.5, 2.0, 2.5])), [0.5, 0.5, 0.5, 0.625])


def test_grid_hdi_where_the_density_piles_up_at_an_end():
    """Density 2x on [0, 1] (CDF x^2): the shortest interval of mass 1/2 is [sqrt(1/2), 1];
    density 2 (1 - x): [0, 1 - sqrt(1/2)]."""
    up = GridMarginal.from_log_density(np.array([0.0, 1.0]), log([0.0, 1.0]))
    assert up.hdi(0.5) == pytest.approx((np.sqrt(0.5), 1.0), rel=1e-14)
    down = GridMarginal.from_log_density(np.array([0.0, 1.0]), log([1.0, 0.0]))
    assert down.hdi(0.5) == pytest.approx((0.0, 1 - np.sqrt(0.5)), abs=1e-14)
    assert down.hdi(np.float32(0.5)) == pytest.approx((0.0, 1 - np.sqrt(0.5)), abs=1e-7)


def test_level_marginal_moments_cdf_and_quantiles():
    m = LevelMarginal.from_probabilities([1.0, 2.0, 4.0], [1.0, 2.0, 1.0])
    np.testing.assert_array_equal(m.density, [0.25, 0.5, 0.25])
    np.testing.assert_array_equal(m.weights, [1.0, 1.0, 1.0])
    assert m.probabilities() == {1.0: 0.25, 2.0: 0.5, 4.0: 0.25}
    assert m.mean() == 2.25
    assert m.sd() == pytest.approx(np.sqrt(1.1875), rel=1e-15)
    x = np.array([0.5, 1.0, 1.5, 2.0, 3.0, 4.0, 9.0])
    np.testing.assert_array_equal(m.cdf(x), [0.0, 0.25, 0.25, 0.75, 0.75, 1.0, 1.0])
    q = np.array([0.0, 0.25, 0.26, 0.75, 0.76, 1.0])
    np.testing.assert_array_equal(m.ppf(q), [1.0, 1.0, 2.0, 2.0, 4.0, 4.0])
    # a level without mass holds no quantile, not even q = 0
    z = LevelMarginal.from_probabilities([0.0, 1.0, 2.0, 3.0], [0.0, 1.0, 0.0, 1.0])
    np.testing.assert_array_equal(z.ppf(np.array([0.0, 0.5, 0.51, 1.0])), [1.0, 1.0, 3.0, 3.0])


def test_level_marginal_mean_is_clipped_to_the_levels():
    """One level with all the mass: its code exactly, though the dot product rounds off it."""
    m = LevelMarginal.from_probabilities([0.1, 0.2, 0.3], [0.0, 0.0, 3.0])
    assert m.mean() == 0.3 and m.sd() == 0.0


@pytest.mark.parametrize(
    ("probabilities", "level", "expected"),
    [
        ([0.25, 0.5, 0.25], 0.5, (1.0, 1.0)),  # one level holds it
        ([0.25, 0.5, 0.25], 0.75, (0.0, 1.0)),  # the first of two as short, as heavy
        ([0.3, 0.25, 0.45], 0.5, (1.0, 2.0)),  # of two as short, the heavier
        ([0.25, 0.25, 0.5], 0.75, (1.0, 2.0)),
        ([0.4, 0.2, 0.4], 0.9, (0.0, 2.0)),  # all of them
    ],
)
def test_level_marginal_hdi(probabilities, level, expected):
    m = LevelMarginal.from_probabilities([0.0, 1.0, 2.0], probabilities)
    assert m.hdi(level) == expected


def test_level_marginal_hdi_takes_a_mass_that_rounds_below_the_level():
    """Levels 0 and 1 hold 0.8, though the cumulative sum's 0.7 + 0.1 rounds below it."""
    m = LevelMarginal.from_probabilities([0.0, 1.0, 2.0], [0.7, 0.1, 0.2])
    assert 0.7 + 0.1 < 0.8
    assert m.hdi(0.8) == (0.0, 1.0)


@pytest.mark.parametrize(
    ("levels", "probabilities", "message"),
    [
        ([], [], "one probability per level"),
        ([[0.0, 1.0]], [[0.5, 0.5]], "one probability per level"),
        ([0.0, 1.0], [1.0], r"levels \(2,\) and probabilities \(1,\)"),
        ([1.0, 0.0], [0.5, 0.5], "finite and strictly increasing"),
        ([0.0, 0.0], [0.5, 0.5], "finite and strictly increasing"),
        ([0.0, np.inf], [0.5, 0.5], "finite and strictly increasing"),
        ([0.0, 1.0], [0.5, -0.5], "finite, non-negative and not all 0"),
        ([0.0, 1.0], [0.0, 0.0], "finite, non-negative and not all 0"),
        ([0.0, 1.0], [np.inf, 1.0], "finite, non-negative and not all 0"),
    ],
)
def test_level_marginal_refusals(levels, probabilities, message):
    with pytest.raises(GPMSAError, match=message):
        LevelMarginal.from_probabilities(levels, probabilities)


def test_a_single_level_marginal_is_its_level():
    m = LevelMarginal.from_probabilities([3.0], [2.0])
    assert (m.mean(), m.sd(), m.hdi(0.9), float(m.ppf(0.5))) == (3.0, 0.0, (3.0, 3.0), 3.0)


def test_draws_summaries_against_numpy():
    a = np.array([3.0, 1.0, 4.0, 1.0, 5.0, 9.0, 2.0, 6.0])
    b = np.arange(8.0) ** 2
    post = Posterior({"a": a, "b": b}, info={"method": "mcmc"})
    assert post.names == ("a", "b")
    assert post.mean("a") == np.mean(a) == 3.875
    assert post.sd("a") == np.std(a, ddof=1)
    q = np.array([0.0, 0.1, 0.5, 0.9, 1.0])
    np.testing.assert_array_equal(post.quantile("a", q), np.quantile(a, q))
    assert post.quantile("a", 0.3) == np.quantile(a, 0.3)
    assert isinstance(post.quantile("a", 0.3), float)
    assert post.interval("a", 0.8) == (np.quantile(a, 0.1), np.quantile(a, 0.9))
    assert post.interval("a") == (np.quantile(a, 0.05), np.quantile(a, 0.95))
    assert post.prob_above("a", 4.0) == 0.375 and post.prob_above("a", 0.5) == 1.0
    s = post.summary(0.5)
    assert list(s["a"]) == ["mean", "sd", "q25", "median", "q75", "n_draws", "exact_grid", "held"]
    assert s["a"] == {
        "mean": 3.875,
        "sd": np.std(a, ddof=1),
        "q25": np.quantile(a, 0.25),
        "median": 3.5,
        "q75": np.quantile(a, 0.75),
        "n_draws": 8,
        "exact_grid": False,
        "held": False,
    }


def test_the_mean_of_equal_draws_is_their_value_and_their_sd_zero():
    post = Posterior({"a": np.full(3, 0.1), "b": np.array([0.1, 0.1, 0.2])})
    assert np.mean(np.full(3, 0.1)) != 0.1  # numpy rounds off the value
    assert post.mean("a") == 0.1 and post.sd("a") == 0.0
    assert post.mean("b") == np.mean([0.1, 0.1, 0.2])


def test_one_draw_has_a_mean_no_sd_and_a_summary_sd_of_nan():
    post = Posterior({"a": [2.5]})
    assert post.mean("a") == 2.5
    with pytest.raises(GPMSAError, match=r"the sd of 'a' needs at least 2 draws, the posterior"):
        post.sd("a")
    s = post.summary()["a"]
    assert np.isnan(s["sd"]) and s["mean"] == s["q5"] == s["median"] == s["q95"] == 2.5
    assert repr(post) == "Posterior(a=2.5, method=?)"
    two = Posterior({"a": [2.0, 4.0]})
    assert two.sd("a") == np.sqrt(2.0) and two.summary()["a"]["sd"] == np.sqrt(2.0)


def test_grid_summaries_come_from_the_grid_and_n_draws_from_the_draws():
    g = ramp_down()
    drawn = {"t": np.array([0.0, 1.0, 2.0, 3.0]), "u": np.array([1.0, 2.0, 3.0, 4.0])}
    post = Posterior(grids={"t": g}, draw=lambda: drawn, info={"names": ["t", "u"]})
    assert post.names == ("t", "u")
    assert post.mean("t") == 0.75 and post.sd("t") == g.sd()
    np.testing.assert_allclose(post.quantile("t", [0.25, 0.875]), [0.5, 2.0], rtol=1e-15)
    assert post.interval("t", 0.5) == pytest.approx((0.5, 1.0 + 2 - np.sqrt(2.0)), rel=1e-14)
    assert post.prob_above("t", 2.0) == pytest.approx(0.125, rel=1e-14)
    assert post.hdi("t", 0.5) == g.hdi(0.5)
    s = post.summary(0.5)
    assert s["t"]["exact_grid"] and not s["u"]["exact_grid"]
    assert s["t"]["n_draws"] == 4 and s["t"]["mean"] == 0.75 and s["t"]["sd"] == g.sd()
    assert s["t"]["median"] == 1.0 and s["u"]["median"] == 2.5
    assert not s["t"]["held"]


def test_a_level_grid_in_a_posterior():
    m = LevelMarginal.from_probabilities([1.0, 2.0, 4.0], [1.0, 2.0, 1.0])
    post = Posterior(grids={"c": m}, draw=lambda: {"c": np.array([1.0, 2.0])})
    assert post.mean("c") == 2.25 and post.sd("c") == m.sd()
    assert post.quantile("c", 0.26) == 2.0 and post.interval("c", 0.5) == (1.0, 2.0)
    assert post.prob_above("c", 2.0) == 0.25 and post.prob_above("c", 0.0) == 1.0
    assert post.hdi("c", 0.5) == (2.0, 2.0)


def test_held_is_true_only_for_a_listed_name_whose_draws_are_one_value():
    post = Posterior(
        {"a": [1.0, 1.0, 1.0], "b": [1.0, 2.0, 3.0], "c": [5.0, 5.0, 5.0]},
        info={"held": ["a", "b", 7]},
    )
    s = post.summary()
    assert (s["a"]["held"], s["b"]["held"], s["c"]["held"]) == (True, False, False)
    assert s["a"]["sd"] == 0.0


def test_the_chains_summary_adds_ess_and_rhat():
    from gpmsa.mcmc import diagnostics

    rng = np.random.default_rng(5)
    chains = {"a": rng.normal(size=(2, 100))}
    post = Posterior({"a": chains["a"].reshape(-1)}, chains=chains)
    s = post.summary()["a"]
    assert s["ess"] == diagnostics.ess(chains["a"]) and s["rhat"] == diagnostics.rhat(chains["a"])
    assert "ess" not in Posterior({"a": chains["a"].reshape(-1)}).summary()["a"]


def test_repr_shows_three_parameters_and_how_many_more():
    post = Posterior({n: [1.0, 3.0] for n in "abcde"}, info={"method": "grid"})
    assert repr(post) == "Posterior(a=2±1.41, b=2±1.41, c=2±1.41, +2 more, method=grid)"
    three = Posterior({n: [1.0, 3.0] for n in "abc"})
    assert repr(three) == "Posterior(a=2±1.41, b=2±1.41, c=2±1.41, method=?)"


def test_a_lazily_drawn_posterior_pickles_with_its_draws():
    calls = []

    def draw():
        calls.append(1)
        return {"a": np.array([1.0, 2.0, 4.0])}

    post = Posterior(draw=draw, info={"names": ["a"]})
    back = pickle.loads(pickle.dumps(post))
    assert len(calls) == 1 and back._draw is None
    np.testing.assert_array_equal(back.samples["a"], [1.0, 2.0, 4.0])
    assert back.mean("a") == post.mean("a") == 7 / 3


@pytest.mark.parametrize("grid", [False, True])
@pytest.mark.parametrize(
    "call",
    [
        lambda p, n: p.mean(n),
        lambda p, n: p.sd(n),
        lambda p, n: p.quantile(n, 0.5),
        lambda p, n: p.interval(n),
        lambda p, n: p.hdi(n),
        lambda p, n: p.prob_above(n, 0.0),
        lambda p, n: p.plot(n),
    ],
)
def test_every_summary_names_an_unknown_parameter(call, grid):
    drawn = {"a": np.array([1.0, 2.0, 3.0])}
    if grid:
        post = Posterior(grids={"a": ramp_down()}, draw=lambda: drawn, info={"names": ["a"]})
    else:
        post = Posterior(drawn)
    with pytest.raises(GPMSAError, match=r"unknown parameter 'b'; this posterior has \('a',\)"):
        call(post, "b")
    with pytest.raises(GPMSAError, match=r"name must be a parameter name \(str\), got 0"):
        call(post, 0)


def test_the_top_quantile_is_the_last_node_where_the_cells_sum_past_1():
    """The cells' masses of this grid sum to 1 + 2e-16: q = 1 is still the last node."""
    nodes = np.linspace(0.2, 5.8, 51)
    g = GridMarginal.from_log_density(nodes, norm.logpdf(nodes, 3.0, 0.7))
    mass = 0.5 * np.diff(nodes) * (g.density[:-1] + g.density[1:])
    assert np.cumsum(mass)[-1] > 1.0
    assert g.ppf(1.0) == 5.8 and g.cdf(5.8) == 1.0


@pytest.mark.parametrize(
    "marginal",
    [ramp_down(), LevelMarginal.from_probabilities([1.0, 2.0], [1.0, 3.0])],
    ids=["grid", "levels"],
)
def test_marginals_are_frozen_and_compared_by_identity(marginal):
    with pytest.raises(dataclasses.FrozenInstanceError):
        marginal.nodes = np.zeros(2)
    twin = type(marginal)(marginal.nodes, marginal.density, marginal.weights)
    assert marginal == marginal and marginal != twin  # arrays have no single truth value
    assert len({marginal, twin}) == 2


def test_the_plot_labels_its_trace_and_lays_out_its_two_panels():
    fig = Posterior({"a": np.arange(10.0)}).plot("a")
    hist, trace = fig.axes
    assert (hist.get_xlabel(), trace.get_xlabel(), trace.get_ylabel()) == ("a", "draw", "a")
    # tight_layout: the panels use the figure's width, past the default margins (0.125, 0.9)
    assert hist.get_position().x0 < 0.1 and trace.get_position().x1 > 0.95


@pytest.mark.parametrize("offset", [-1000.0, 0.0, 1000.0])
def test_a_log_density_is_taken_up_to_any_additive_constant(offset):
    g = GridMarginal.from_log_density(np.array([0.0, 1.0, 2.0]), log([1.0, 2.0, 1.0]) + offset)
    np.testing.assert_allclose(g.density, [1 / 3, 2 / 3, 1 / 3], rtol=1e-12)  # (1000's ulp)


def test_the_cdf_at_every_node_is_the_running_sum_of_the_cells():
    """Exactly, the last node's 1 included (the ramp's formula at a cell's end can round off)."""
    nodes = np.linspace(0.2, 5.8, 51)
    g = GridMarginal.from_log_density(nodes, norm.logpdf(nodes, 3.0, 0.7))
    cum = np.cumsum(0.5 * np.diff(nodes) * (g.density[:-1] + g.density[1:]))
    np.testing.assert_array_equal(g.cdf(nodes), np.clip(np.append(0.0, cum) / cum[-1], 0, 1))
    assert g.cdf(5.8) == 1.0
    # one cell, 4/7 to 1, density rising 1:4: its ramp formula at its end gives 1 - 2e-16
    g = GridMarginal.from_log_density(np.array([4.0, 7.0]) / 7.0, np.log([1.0, 4.0]))
    assert g.cdf(1.0) == 1.0 and g.cdf(2.0) == 1.0
    # and 1 ulp below the last node of this one it rounds to 1 + 2e-16: a probability is <= 1
    g = GridMarginal.from_log_density(np.array([1.0, 2.0, 4.0]) / 3.0, np.log([4.0, 4.0, 1.0]))
    assert g.cdf(np.nextafter(4.0 / 3.0, 0.0)) == 1.0


def test_the_lowest_quantile_is_where_the_mass_starts():
    """Density 0, 0, 1, 1 on 0..3: no quantile lies in the empty first cell."""
    g = GridMarginal.from_log_density(np.arange(4.0), log([0.0, 0.0, 1.0, 1.0]))
    np.testing.assert_allclose(g.ppf(np.array([0.0, 1.0 / 3.0])), [1.0, 2.0], rtol=1e-15)
    assert g.hdi(0.99)[0] >= 1.0


def test_a_levels_quantile_at_its_own_cdf_is_that_level():
    """Where the running sum of the probabilities ends below 1 (1 - 2e-16 here) too."""
    m = LevelMarginal.from_probabilities(np.arange(4.0), [2.0, 5.0 / 3.0, 2.0, 3.0])
    assert np.cumsum(m.density)[-1] < 1.0
    np.testing.assert_array_equal(m.ppf(m.cdf(m.nodes)), m.nodes)


def test_a_held_name_with_a_grid_is_not_held():
    post = Posterior(grids={"t": ramp_down()}, draw=lambda: {"t": np.ones(3)}, info={"held": ["t"]})
    assert post.summary()["t"]["held"] is False


def test_the_plot_of_a_level_grid_bars_the_draws_share_of_each_level():
    m = LevelMarginal.from_probabilities([1.0, 2.0, 4.0], [1.0, 2.0, 1.0])
    draws = {"c": np.array([1.0, 2.0, 2.0, 2.0])}
    fig = Posterior(grids={"c": m}, draw=lambda: draws).plot("c")
    hist = fig.axes[0]
    assert [b.get_height() for b in hist.patches] == [0.25, 0.75, 0.0]
    assert [b.get_x() + b.get_width() / 2 for b in hist.patches] == pytest.approx([1, 2, 4])
    assert [b.get_width() for b in hist.patches] == pytest.approx([0.4] * 3, rel=1e-12)
    np.testing.assert_array_equal(hist.lines[0].get_ydata(), [0.25, 0.5, 0.25])
    assert hist.get_ylabel() == "probability"


def test_the_plot_draws_fifty_bars_and_a_trace_per_chain():
    chains = {"a": np.arange(20.0).reshape(2, 10)}
    fig = Posterior({"a": chains["a"].reshape(-1)}, chains=chains).plot("a")
    hist, trace = fig.axes
    assert len(hist.patches) == 50
    assert len(trace.lines) == 2
    assert {line.get_linewidth() for line in trace.lines} == {0.5}
    assert tuple(fig.get_size_inches()) == (9.0, 3.5)
    for line, chain in zip(trace.lines, chains["a"], strict=True):
        np.testing.assert_array_equal(line.get_ydata(), chain)


def test_the_chains_of_lazily_drawn_samples_are_checked_once_drawn():
    """Before: chains given with a draw callable were never checked against its samples: a
    parameter the chains lacked made summary() raise a bare KeyError, and chains that were not
    the draws split into chains were kept as the posterior's traces."""
    lacking = Posterior(
        draw=lambda: {"a": np.arange(4.0), "b": np.arange(4.0)},
        chains={"a": np.arange(4.0).reshape(2, 2)},
    )
    with pytest.raises(GPMSAError, match=r"chains lacks \['b'\]: give the chains of every"):
        lacking.summary()
    other = Posterior(draw=lambda: {"a": np.arange(4.0)}, chains={"a": np.ones((2, 2))})
    with pytest.raises(GPMSAError, match=r"chains\['a'\] of shape \(2, 2\) are not samples\['a'\]"):
        other.mean("a")
    good = Posterior(draw=lambda: {"a": np.arange(4.0)}, chains={"a": np.arange(4.0).reshape(2, 2)})
    assert good.mean("a") == 1.5 and good.summary()["a"]["n_draws"] == 4


def test_marginal_reprs():
    g = GridMarginal.from_log_density(np.array([-0.1234567, 0.5, 1.2345678]), np.zeros(3))
    assert repr(g) == "GridMarginal(3 nodes on [-0.1235, 1.235], mean=0.5556, sd=0.482)"
    g = GridMarginal.from_log_density(np.array([-0.0, 3.0]), np.zeros(2))
    assert repr(g) == "GridMarginal(2 nodes on [0, 3], mean=1.5, sd=1.5)"
    m = LevelMarginal.from_probabilities([1.0, 2.0, 4.0], [1.0, 2.0, 1.0])
    assert repr(m) == "LevelMarginal({1: 0.25, 2: 0.5, 4: 0.25})"


def test_a_level_hdi_takes_a_mass_at_the_level_within_its_tolerance():
    """0.5000000000005 less its 1e-12 relative tolerance is 0.5 exactly: level 1 holds it."""
    m = LevelMarginal.from_probabilities([0.0, 1.0, 2.0], [0.25, 0.5, 0.25])
    assert 0.5000000000005 * (1.0 - 1e-12) == 0.5
    assert m.hdi(0.5000000000005) == (1.0, 1.0)


def test_one_chain_may_be_given_as_its_draws():
    x = np.array([1.0, 2.0, 3.0, 4.0])
    post = Posterior({"a": x}, chains={"a": x})
    assert post.chains["a"].shape == (1, 4)
    np.testing.assert_array_equal(post.chains["a"][0], x)


def test_the_plot_of_recorded_levels_bars_the_draws_share_of_each_level():
    post = Posterior({"c": np.array([0.0, 2.0, 2.0, 2.0])}, info={"levels": {"c": [2, 0, 1]}})
    hist = post.plot("c").axes[0]
    assert [b.get_height() for b in hist.patches] == [0.25, 0.0, 0.75]
    assert [b.get_x() for b in hist.patches] == pytest.approx([-0.2, 0.8, 1.8], rel=1e-12)
    assert [b.get_width() for b in hist.patches] == pytest.approx([0.4] * 3, rel=1e-12)
    assert hist.get_ylabel() == "probability" and not hist.lines  # no mean line between levels


@pytest.mark.parametrize("cls", [GridMarginal, LevelMarginal])
def test_the_marginals_type_hints_resolve(cls):
    for name in ("from_log_density", "from_probabilities", "mean", "sd", "cdf", "ppf", "hdi"):
        if hasattr(cls, name):
            assert "return" in typing.get_type_hints(getattr(cls, name))
