"""Mutation testing of control.estimate (s88): hand-built grids that pin `favoured_edge` exactly
(the Bayes factor 20 as a strict bound, the 5% margin with a node exactly on it at either end,
a zero prior as no evidence, an uneven prior, a grid with a node inside the lower margin but
none inside the upper one), and `Estimate`'s defaults and checks at their boundaries."""

import numpy as np
import pytest

from control import ControlError, Estimate
from control.estimate import EDGE_BAYES_FACTOR, EDGE_MARGIN, favoured_edge, graver_fault, run_text


def edge(nodes, ratio, prior=None):
    """`favoured_edge` where the posterior-to-prior mass ratio at ``nodes`` is ``ratio`` (up to
    a constant)."""
    nodes = np.asarray(nodes, dtype=float)
    prior = np.full(nodes.size, 1.0 / nodes.size) if prior is None else np.asarray(prior)
    posterior = prior * np.asarray(ratio, dtype=float)
    return favoured_edge(nodes, posterior / posterior.sum(), prior)


def test_the_documented_constants():
    assert EDGE_BAYES_FACTOR == 20.0 and EDGE_MARGIN == 0.05


def test_a_bayes_factor_just_above_twenty_names_the_edge_just_below_does_not():
    nodes = [10.0, 50.0, 100.0]
    assert edge(nodes, [1.0, 1.0, 20.5]) == "upper"
    assert edge(nodes, [1.0, 1.0, 19.5]) == ""
    assert edge(nodes, [20.5, 1.0, 1.0]) == "lower"
    assert edge(nodes, [19.5, 1.0, 1.0]) == ""
    assert edge(nodes, [1.0, 1.0, 1.0]) == ""


def test_a_node_exactly_on_the_margin_is_inside():
    # 100 * (1 - 0.05) == 95.0 and 100 * (1 + 0.05) == 105.0 exactly: those nodes are compared
    # with the edge (factor 10 < 20), nodes beyond the margin (96, 104) are not
    assert edge([10.0, 50.0, 95.0, 100.0], [1.0, 1.0, 100.0, 1000.0]) == ""
    assert edge([100.0, 105.0, 150.0, 200.0], [1000.0, 100.0, 1.0, 1.0]) == ""
    # against the nodes inside only (factor 1000), the edge is named
    assert edge([10.0, 50.0, 100.0], [1.0, 1.0, 1000.0]) == "upper"
    assert edge([100.0, 150.0, 200.0], [1000.0, 1.0, 1.0]) == "lower"


def test_nodes_within_the_margin_of_an_edge_carry_no_evidence_against_it():
    nodes = [10.0, 50.0, 94.0, 96.0, 100.0]
    # 96 lies within 5% of the edge: its ratio (500) is not compared; 94 (10) is
    assert edge(nodes, [1.0, 1.0, 10.0, 500.0, 1000.0]) == "upper"
    # 94 lies 6% inside: compared (factor 10), so no edge; a 10% margin would name one
    assert edge(nodes, [1.0, 1.0, 100.0, 500.0, 1000.0]) == ""
    low = [100.0, 104.0, 106.0, 150.0, 200.0]
    assert edge(low, [1000.0, 500.0, 10.0, 1.0, 1.0]) == "lower"
    assert edge(low, [1000.0, 500.0, 100.0, 1.0, 1.0]) == ""


def test_a_grid_with_no_node_inside_the_upper_margin_names_no_edge():
    # 100 >= 95.1 * 1.05 (a node inside the lower margin) but 95.1 > 100 * 0.95 (none inside
    # the upper one): no edge, whatever the data, and no error
    assert edge([95.1, 100.0], [1.0, 1000.0]) == ""
    assert edge([95.1, 100.0], [1000.0, 1.0]) == ""


def test_a_node_the_prior_excludes_is_no_evidence_even_with_posterior_mass():
    nodes = np.array([10.0, 50.0, 100.0])
    prior = np.array([0.5, 0.5, 0.0])
    assert favoured_edge(nodes, np.array([0.1, 0.1, 0.8]), prior) == ""
    assert favoured_edge(nodes, np.array([0.8, 0.1, 0.1]), prior[::-1]) == ""
    assert favoured_edge(nodes, np.array([0.05, 0.05, 0.9]), np.array([0.5, 0.49, 0.01])) == "upper"


def test_the_evidence_is_the_posterior_to_prior_ratio_under_an_uneven_prior():
    nodes = [10.0, 50.0, 100.0]
    prior = [0.6, 0.3, 0.1]
    assert edge(nodes, [1.0, 1.0, 25.0], prior) == "upper"  # top mass 0.25 < 0.36 at 10
    assert edge(nodes, [25.0, 1.0, 1.0], prior[::-1]) == "lower"
    assert edge(nodes, [1.0, 1.0, 15.0], [0.01, 0.01, 0.98]) == ""  # most mass, factor 15


def test_an_estimate_s_defaults_are_none_but_latency_zero():
    e = Estimate(time=1.0, position=2.0, status="filling")
    assert e.latency_s == 0.0 and e.reason == "" and e.domain_edge == ""
    assert np.isnan(e.gd_mean) and np.isnan(e.gd_sd) and np.isnan(e.prob_change)
    assert np.isnan(e.data_time) and np.isnan(e.plausibility_p) and np.isnan(e.speed)
    assert all(np.isnan(v) for v in e.interval) and e.posterior is None and e.feature is None
    assert not e.ok and np.isnan(e.prob_above(1.0)) and np.isnan(e.quantile(0.5))


def ok(**fields):
    return Estimate(time=0.0, position=0.0, status="ok", **fields)


def test_an_interval_may_be_a_single_point_but_not_reversed():
    assert ok(interval=(1.0, 1.0)).interval == (1.0, 1.0)
    e = ok(interval=(np.float32(0.5), np.float64(2.0)))
    assert e.interval == (0.5, 2.0) and all(type(v) is float for v in e.interval)
    for bad in ((1.0, 0.999), (np.nan, 1.0), (1.0, np.nan)):
        with pytest.raises(ControlError, match=r"interval must have lo <= hi \(or be two NaNs\)"):
            ok(interval=bad)
    for bad in ((1.0,), (1.0, 2.0, 3.0), (1.0, "2"), (True, 2.0), np.array([1.0, 2.0])):
        with pytest.raises(ControlError, match=r"interval must be a pair \(lo, hi\)"):
            ok(interval=bad)


def test_the_posterior_s_numbers_belong_to_an_ok_estimate_only():
    for name, value in (("gd_mean", 1.0), ("gd_sd", 0.0), ("interval", (0.0, 0.0)),
                        ("domain_edge", "upper")):  # fmt: skip
        with pytest.raises(ControlError, match=rf"a 'stale' estimate has no {name} "):
            Estimate(time=0.0, position=0.0, status="stale", **{name: value})
    assert ok(domain_edge="lower").domain_edge == "lower"
    for bad in ("left", None):
        with pytest.raises(ControlError, match="domain_edge must be '' or one of"):
            ok(domain_edge=bad)
    with pytest.raises(ControlError, match="posterior must be a gpmsa.Posterior or None"):
        ok(posterior="p")


def test_quantile_takes_zero_and_one_and_prob_above_any_finite_value():
    e = ok()  # no posterior: NaN, after the argument is checked
    assert np.isnan(e.quantile(0)) and np.isnan(e.quantile(1.0)) and np.isnan(e.prob_above(-1e300))
    for bad in (-1e-12, 1.0 + 1e-12, np.nan, True, "0.5"):
        with pytest.raises(ControlError, match="q must be a probability in"):
            e.quantile(bad)
    for bad in (np.inf, -np.inf, np.nan, None, False):
        with pytest.raises(ControlError, match="value must be a finite GD"):
            e.prob_above(bad)


def test_a_bayes_factor_of_exactly_twenty_is_not_above_it():
    nodes, ones = np.array([10.0, 50.0, 100.0]), np.ones(3)  # log(20) - log(1) == log(20)
    assert favoured_edge(nodes, np.array([1.0, 1.0, 20.0]), ones) == ""
    assert favoured_edge(nodes, np.array([20.0, 1.0, 1.0]), ones) == ""
    assert favoured_edge(nodes, np.array([1.0, 1.0, 20.000001]), ones) == "upper"


def test_of_two_equally_implausible_blocks_the_earlier_is_the_graver():
    first = Estimate(time=1.0, position=0.0, status="implausible", plausibility_p=0.01)
    second = Estimate(time=2.0, position=0.0, status="implausible", plausibility_p=0.01)
    assert graver_fault(first, second) is first and graver_fault(second, first) is second


def test_run_text_gives_no_span_without_positions():
    assert run_text(["ok"], [0.0, 1.0], [], "sensor") == "1 estimate: ok 1; 2 sensor samples"
    assert run_text(["ok"], [], [0.0, 1.0], "IMU") == "1 estimate: ok 1; 0 IMU samples"
