"""A callable prior that is zero on part of the domain (a truncated prior, written as a function)
on the one-parameter grid: the density used to ramp to zero across the cell beyond its zero
edge, so that ``update(prior=lambda gd: np.where(gd >= c, 0, -inf))`` was not the posterior of
``constraint=lambda th: th[0] >= c``: on the road case up to 0.12 sd off in its quantiles and
0.07 sd in its mean, silently. The edge is now located by bisection and cut, as a constraint's
is."""

from functools import cache

import numpy as np
import pytest
from _calib_cases import road_emulator, road_obs
from scipy.integrate import cumulative_trapezoid
from test_grid_one_param_edges_s57 import observations, vague_lamos_emulator

from gpmsa import Calibrator
from gpmsa.calibration.observations import reduce

LEVELS = np.array([0.001, 0.01, 0.05, 0.25, 0.5, 0.75, 0.95, 0.99, 0.999])
FREE_MEAN, FREE_SD = 426.6, 28.6  # the road case's posterior without the cut


@pytest.mark.parametrize("offset", [-3.0, -0.5, 0.0, 0.5, 2.0, 4.0])
@pytest.mark.parametrize("side", ["above", "below"])
def test_a_callable_prior_with_zeros_cuts_like_the_constraint(offset, side):
    """The same truncation as a prior and as a constraint: one posterior (was 0.008-0.12 sd
    apart in the quantiles)."""
    cut = FREE_MEAN + offset * FREE_SD
    x, y = road_obs()
    if side == "above":
        constraint, prior = (
            (lambda th: th[0] >= cut),
            (lambda gd: np.where(gd >= cut, 0.0, -np.inf)),
        )
    else:
        constraint, prior = (
            (lambda th: th[0] <= cut),
            (lambda gd: np.where(gd <= cut, 0.0, -np.inf)),
        )
    by_constraint = Calibrator(road_emulator(), constraint=constraint).update(x, y)
    by_prior = Calibrator(road_emulator()).update(x, y, prior=prior)
    sd = by_constraint.sd("GD")
    expected = by_constraint.quantile("GD", LEVELS)
    np.testing.assert_allclose(by_prior.quantile("GD", LEVELS), expected, rtol=0, atol=1e-6 * sd)
    assert by_prior.mean("GD") == pytest.approx(by_constraint.mean("GD"), abs=1e-6 * sd)
    assert by_prior.sd("GD") == pytest.approx(sd, rel=1e-6)
    inside = by_prior.samples["GD"] >= cut if side == "above" else by_prior.samples["GD"] <= cut
    assert inside.all()


@cache
def road_dense_log_posterior() -> tuple[np.ndarray, np.ndarray]:
    """(native GD nodes, log posterior without a user's prior) of the road case's observation
    on 200,001 nodes (the Calibrator's per-node likelihood, lamOs integrated): the same for
    every prior, so computed once (3 s); read-only."""
    cal = Calibrator(road_emulator())
    std = cal.emulator.standardizer
    u = np.linspace(0.0, 1.0, 200_001)
    data = reduce(cal.emulator, *road_obs(), False)
    logp = np.concatenate([cal._combine(cal._marginals(data, t)) + cal._theta_prior_at(t, None)
                           for t in np.array_split(u[:, None], 40)])  # fmt: skip
    nodes = u * (std.t_max[0] - std.t_min[0]) + std.t_min[0]
    nodes.setflags(write=False)
    logp.setflags(write=False)
    return nodes, logp


def dense_reference(prior) -> tuple[float, float, np.ndarray]:
    """(mean, sd, quantiles at LEVELS) of the road case's exact posterior with a finite
    ``prior`` (native GD -> log density) on 200,001 nodes (`road_dense_log_posterior`), cut
    where it is -inf at a node (the cut's error is under 1e-5 of the range)."""
    nodes, logp = road_dense_log_posterior()
    logp = logp + prior(nodes)
    f = np.exp(logp - logp.max())
    cdf = cumulative_trapezoid(f, nodes, initial=0.0)
    f, cdf = f / cdf[-1], cdf / cdf[-1]
    mean = np.trapezoid(nodes * f, nodes)
    sd = np.sqrt(np.trapezoid((nodes - mean) ** 2 * f, nodes))
    return mean, sd, np.interp(LEVELS, cdf, nodes)


def test_a_truncated_gaussian_prior_matches_a_dense_grid():
    """A Gaussian prior cut to an interval that crosses the peak (zero below 410 and above 470):
    both edges cut, the prior's slope kept at the inserted points. The ramp made the quantiles
    0.060 sd, the mean 0.028 sd and the sd 1.6 % off the dense grid (now 0.004 sd, 1e-4 sd and
    0.06 %)."""
    x, y = road_obs()

    def prior(gd):
        return np.where((gd >= 410.0) & (gd <= 470.0), -0.5 * ((gd - 430.0) / 25.0) ** 2, -np.inf)

    cal = Calibrator(road_emulator())
    post = cal.update(x, y, prior=prior)
    mean, sd, quantiles = dense_reference(prior)
    assert np.max(np.abs(post.quantile("GD", LEVELS) - quantiles)) < 0.01 * sd
    assert post.mean("GD") == pytest.approx(mean, abs=0.005 * sd)
    assert post.sd("GD") == pytest.approx(sd, rel=0.005)
    assert np.isfinite(post.info["log_evidence"])
    draws = post.samples
    assert draws["GD"].min() >= 410.0 and draws["GD"].max() <= 470.0
    assert np.all(draws["lamOs"] > 0)


@pytest.mark.parametrize("offset", [-1.0, 0.0, 2.0])
def test_a_refined_grid_cuts_a_callable_prior_like_the_constraint(offset):
    """A narrow posterior (6 observations, sd ~5e-4 of the range) on a refined grid, cut by the
    prior at its peak: the refined grid's edge is cut too."""
    emu = vague_lamos_emulator()
    x, y = observations(6)
    free = Calibrator(emu).update(x, y)
    cut = free.mean("t") + offset * free.sd("t")
    by_constraint = Calibrator(emu, constraint=lambda th: th[0] >= cut).update(x, y)
    by_prior = Calibrator(emu).update(x, y, prior=lambda t: np.where(t >= cut, 0.0, -np.inf))
    assert by_prior.info["refined"]
    sd = by_constraint.sd("t")
    expected = by_constraint.quantile("t", LEVELS)
    np.testing.assert_allclose(by_prior.quantile("t", LEVELS), expected, rtol=0, atol=1e-6 * sd)
    assert by_prior.samples["t"].min() >= cut


@pytest.mark.parametrize("end", ["lower", "upper"])
def test_a_prior_zero_only_at_the_domain_end_is_no_error(end):
    """A prior that vanishes at an end of the domain (log(GD - GD_min), a Gamma-like prior): the
    edge lies within float64 of the end node in native units, so the point bisection inserted
    there duplicated the node's native GD and update raised 'a grid marginal's nodes must be
    finite and strictly increasing' (it worked before the zero region was cut)."""
    emu = road_emulator()
    x, y = road_obs()
    lo, hi = emu.standardizer.t_min[0], emu.standardizer.t_max[0]

    def prior(gd):
        with np.errstate(divide="ignore"):
            return np.log(np.maximum(gd - lo if end == "lower" else hi - gd, 0.0))

    post = Calibrator(emu).update(x, y, prior=prior)
    nodes = post.grids["GD"].nodes
    assert np.all(np.diff(nodes) > 0)
    dense = dense_reference(prior)
    assert post.mean("GD") == pytest.approx(dense[0], abs=0.005 * dense[1])


@pytest.mark.parametrize(("node", "strict"), [(60, True), (64, True), (70, False), (70, True)])
@pytest.mark.parametrize("as_prior", [False, True])
def test_an_edge_on_a_grid_node_is_cut_there(node, strict, as_prior):
    """A constraint or callable prior whose edge is a grid node's native value (GD > node, GD >=
    node): the bisection's point on the node's side had the node's native GD, and update raised
    'strictly increasing' (the constraint since its edges were cut, the prior since 851a31f)."""
    x, y = road_obs()
    c = Calibrator(road_emulator()).theta_grid[node]

    def allowed(gd):
        return gd > c if strict else gd >= c

    if as_prior:
        post = Calibrator(road_emulator()).update(
            x, y, prior=lambda gd: np.where(allowed(gd), 0.0, -np.inf)
        )
    else:
        post = Calibrator(road_emulator(), constraint=lambda th: allowed(th[0])).update(x, y)
    gm = post.grids["GD"]
    assert np.all(np.diff(gm.nodes) > 0)
    assert float(gm.ppf(0.0)) == pytest.approx(c, abs=1e-9)
    assert allowed(post.samples["GD"]).all()
