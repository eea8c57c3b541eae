"""The grid machinery's laws, function by function (session 84, mutation testing of
gpmsa.calibration.grid): interpolation exact where the log density is linear (bilinear) and in
the density next to a zero, the nearest node by brute force, marginals cut to their support
with one zero node kept, spreads, runs, valleys, modes and resolutions of densities whose
values are known in closed form, the core's tails holding at most TAIL_MASS, and refined axes
that cover each unresolved mode with the stated nodes."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.stats import norm

from gpmsa.calibration.grid import (
    IQR_PER_SD,
    MIN_MODE_NODES,
    MODE_MASS,
    N_REFINE,
    RESOLVE_SD,
    SAME_NODE,
    TAIL_MASS,
    _core,
    _finer_axis,
    _mode_stats,
    _modes,
    _one_resolved_peak,
    _resolution,
    _runs,
    _spread,
    _valleys,
    conditional_sds,
    interp_log,
    nearest,
    refined_axis,
    trimmed_marginal,
    with_edges,
    zero_edges,
)


def test_nearest_is_the_brute_force_nearest_node():
    rng = np.random.default_rng(3)
    nodes = np.sort(rng.uniform(0.0, 1.0, 9))
    mid = 0.5 * (nodes[:-1] + nodes[1:])
    values = np.concatenate([rng.uniform(-0.2, 1.2, 400), nodes, mid - 1e-9, mid + 1e-9])
    brute = np.argmin(np.abs(values[:, None] - nodes[None, :]), axis=1)
    np.testing.assert_array_equal(nearest(nodes, values), brute)
    assert nearest(nodes, np.array([-5.0, 5.0])).tolist() == [0, 8]


def test_interp_log_is_exact_for_a_linear_and_a_bilinear_log_density():
    axis = np.linspace(0.0, 1.0, 7)
    points = np.random.default_rng(0).uniform(0.0, 1.0, (50, 2))
    line = interp_log(3.0 * axis - 1.0, axis, points[:, :1])
    np.testing.assert_allclose(line, 3.0 * points[:, 0] - 1.0, rtol=0, atol=1e-12)
    x, y = np.meshgrid(axis, axis, indexing="ij")  # first parameter slowest
    table = (1.0 + 2.0 * x - 3.0 * y + 0.5 * x * y).ravel()
    px, py = points.T
    np.testing.assert_allclose(interp_log(table, axis, points),
                               1.0 + 2.0 * px - 3.0 * py + 0.5 * px * py, atol=1e-12)  # fmt: skip


def test_interp_log_smooth_is_exact_for_a_gaussian_log_density():
    axis = np.linspace(0.0, 1.0, 9)
    quadratic = lambda t: -4.0 * (t - 0.3) ** 2 + 0.5 * t  # noqa: E731
    points = np.linspace(0.01, 0.99, 23)[:, None]
    smooth = interp_log(quadratic(axis), axis, points, smooth=True)
    np.testing.assert_allclose(smooth, quadratic(points[:, 0]), atol=1e-12)
    linear = interp_log(quadratic(axis), axis, points)
    assert np.max(np.abs(linear - quadratic(points[:, 0]))) > 1e-2  # the cubic's, not these


def test_interp_log_is_linear_in_the_density_next_to_a_zero():
    axis = np.array([0.0, 1.0, 2.0, 3.0])
    table = np.array([-np.inf, np.log(4.0), np.log(2.0), -np.inf])
    s = np.array([0.0, 0.25, 0.5, 1.0, 1.5, 2.0, 2.75, 3.0])
    got = interp_log(table, axis, s[:, None])
    with np.errstate(divide="ignore"):
        want = np.log([0.0, 1.0, 2.0, 4.0, np.sqrt(8.0), 2.0, 0.5, 0.0])  # cell 1-2 in the log
    np.testing.assert_allclose(got, want, rtol=1e-12)
    assert not np.isnan(got).any()
    assert np.all(interp_log(np.full(4, -np.inf), axis, s[:, None]) == -np.inf)


def test_with_edges_inserts_the_boundary_and_maps_each_point_to_its_allowed_node():
    nodes = np.linspace(0.0, 1.0, 5)
    free = 2.0 * nodes
    ok = np.array([True, True, True, False, False])
    edges = (np.array([2]), np.array([0.6]), np.array([0.6000001]))
    x, logd, lik = with_edges(nodes, free, ok, edges)
    np.testing.assert_allclose(x, [0.0, 0.25, 0.5, 0.6, 0.6000001, 0.75, 1.0])
    np.testing.assert_allclose(logd[:4], [0.0, 0.5, 1.0, 1.2], rtol=1e-12)
    assert np.all(logd[4:] == -np.inf)
    assert lik.tolist() == [0, 1, 2, 2, 2, 3, 4]  # an inserted point: its allowed neighbour
    same = with_edges(nodes, free, ok, (np.array([2]), np.array([0.5]), np.array([0.75])))
    np.testing.assert_array_equal(same[0], nodes)  # a point on a node is that node
    none = (np.array([], int), np.array([]), np.array([]))
    plain = with_edges(nodes, free, np.ones(5, bool), none)
    np.testing.assert_array_equal(plain[0], nodes)
    np.testing.assert_array_equal(plain[2], np.arange(5))


def test_with_edges_adds_the_prior_at_the_nodes_and_the_allowed_inserted_points():
    nodes = np.linspace(0.0, 1.0, 5)
    ok = np.array([False, False, True, True, True])
    prior = lambda p: -p  # noqa: E731
    edges = (np.array([1]), np.array([0.4]), np.array([0.45]))
    x, logd, lik = with_edges(nodes, np.zeros(5), ok, edges, prior)
    np.testing.assert_allclose(x, [0.0, 0.25, 0.4, 0.45, 0.5, 0.75, 1.0])
    assert np.all(logd[:3] == -np.inf)
    np.testing.assert_allclose(logd[3:], [-0.45, -0.5, -0.75, -1.0], rtol=1e-12)
    assert lik.tolist() == [0, 1, 2, 2, 2, 3, 4]


def test_trimmed_marginal_keeps_one_zero_node_each_side_of_the_support():
    nodes = np.linspace(0.0, 7.0, 8)
    with np.errstate(divide="ignore"):
        logd = np.log([0.0, 0.0, 0.0, 1.0, 2.0, 1.0, 0.0, 0.0])
    gm, kept = trimmed_marginal(nodes, logd)
    assert kept == slice(2, 7)
    np.testing.assert_array_equal(gm.nodes, nodes[2:7])
    np.testing.assert_allclose(gm.density, [0.0, 0.25, 0.5, 0.25, 0.0])
    gm, kept = trimmed_marginal(nodes[2:], logd[2:])
    assert kept == slice(0, 5) and gm.nodes.size == 5
    edge = np.array([-np.inf, 0.0, 0.0])
    gm, kept = trimmed_marginal(np.arange(3.0), edge)
    assert kept == slice(0, 3) and gm.nodes.size == 3
    w = np.array([0.25, 0.5, 0.5, 0.25])
    gm, kept = trimmed_marginal(np.arange(4.0), np.zeros(4), w)
    assert kept == slice(0, 4)
    np.testing.assert_array_equal(gm.weights, w)  # the given weights, all nodes positive


def test_spread_is_the_sd_of_a_normal_and_the_iqr_where_tails_are_heavy():
    axis = np.linspace(-10.0, 10.0, 2001)
    assert _spread(axis, norm.pdf(axis, 1.0, 1.5)) == pytest.approx(1.5, rel=2e-3)
    heavy = norm.pdf(axis, 0.0, 0.5) + 0.2 * norm.pdf(axis, 0.0, 5.0)
    s = _spread(axis, heavy)
    cdf = np.cumsum(heavy) / heavy.sum()
    iqr = np.interp(0.75, cdf, axis) - np.interp(0.25, cdf, axis)
    assert s == pytest.approx(iqr / IQR_PER_SD, rel=1e-2)
    assert s < 0.5 * np.sqrt((axis**2) @ heavy / heavy.sum())


def test_runs_split_at_gaps_below_the_cutoff_and_dips_are_local_minima():
    d = np.array([0.0, 1.0, 3.0, 2.0, 2.5, 1e-14, 1e-14, 4.0, 1.0, 1e-14 * 4.0, 0.0])
    first, last, dips = _runs(d)
    assert first.tolist() == [1, 7] and last.tolist() == [4, 9]  # 4e-14 is at the cutoff
    assert dips.tolist() == [3]  # 5-6 are flat: no dip
    first, last, _ = _runs(np.ones(5))
    assert (first.tolist(), last.tolist()) == ([0], [4])


def test_one_resolved_peak_only_for_one_wide_peak_without_a_valley():
    axis = np.linspace(0.0, 1.0, 101)
    h = axis[1]
    assert _one_resolved_peak(axis, norm.pdf(axis, 0.5, 5.0 * h))
    assert not _one_resolved_peak(axis, norm.pdf(axis, 0.5, 3.0 * h))  # narrow
    left = norm.pdf(axis, 0.3, 8.0 * h) + 0.2 * norm.pdf(axis, 0.8, 5.0 * h)
    right = left[::-1].copy()
    assert not _one_resolved_peak(axis, left) and not _one_resolved_peak(axis, right)
    assert _modes(axis, left)[2].tolist() == [False]  # what _modes decides instead
    assert _one_resolved_peak(axis, np.exp(-5.0 * axis) + 0.0)  # falling from the first node
    assert _one_resolved_peak(axis, np.exp(5.0 * axis))  # rising to the last


def test_valleys_separate_peaks_only_below_half_the_lower_peak():
    d = np.array([0.0, 2.0, 4.0, 1.4, 3.0, 1.0, 0.0])
    assert _valleys(d, np.array([3]), 0, 6) == [3]  # 1.4 < 0.5 * min(4, 3)
    d[3] = 1.5  # not below half the lower side's highest
    assert _valleys(d, np.array([3]), 0, 6) == []
    d[3] = 1.49
    assert _valleys(d, np.array([3]), 0, 6) == [3]
    assert _valleys(d, np.array([3]), 0, 3) == []  # a dip on the run's end is not inside
    assert _valleys(d, np.array([3]), 3, 6) == []  # a dip on the run's end is not inside


def test_mode_stats_mass_spread_and_spacing_of_a_mode():
    axis = np.array([0.0, 0.1, 0.2, 0.3, 0.4, 0.6, 1.0])
    d = np.array([0.0, 1.0, 2.0, 1.0, 0.0, 0.0, 0.0])
    mass, spread, spacing = _mode_stats(axis, d, 1, 3)
    assert spacing == pytest.approx(0.1)  # nodes 0..4, one more each side
    assert mass == pytest.approx(4.0 * 0.1)
    assert spread == pytest.approx(_spread(axis[1:4], d[1:4]))
    _, _, end = _mode_stats(axis, np.array([0, 0, 0, 0, 0, 1.0, 1.0]), 5, 6)
    assert end == pytest.approx(0.3)  # nodes 4..6 (none beyond the end)


def test_modes_flag_a_narrow_peak_and_leave_a_wide_or_negligible_one():
    axis = np.linspace(0.0, 1.0, 101)
    h = axis[1]
    wide = norm.pdf(axis, 0.5, 5.0 * h)
    assert _modes(axis, wide)[2].tolist() == [False]
    narrow = norm.pdf(axis, 0.5, 2.0 * h)
    first, last, unresolved = _modes(axis, narrow)
    assert unresolved.tolist() == [True] and first[0] < 50 < last[0]
    two = norm.pdf(axis, 0.15, 2.0 * h) + norm.pdf(axis, 0.75, 5.0 * h)
    assert _modes(axis, two)[2].tolist() == [True, False]  # two runs: the narrow one refined
    joined = norm.pdf(axis, 0.3, 6.0 * h) + norm.pdf(axis, 0.6, 2.0 * h)  # one run, a valley
    assert _modes(axis, joined)[2].tolist() == [True]
    tiny = norm.pdf(axis, 0.3, 6.0 * h) + 1e-11 * norm.pdf(axis, 0.9, 1.0 * h)
    assert _modes(axis, tiny)[2].tolist() == [False, False]  # under MODE_MASS: left
    small = norm.pdf(axis, 0.3, 6.0 * h) + 10 * MODE_MASS * norm.pdf(axis, 0.9, 1.0 * h)
    assert _modes(axis, small)[2].tolist() == [False, True]
    apart = np.array([0.0, 1.0, 2.0, 1.0, 0.0, 0.0, 0.0, 1.0, 3.0, 1.0, 0.0])  # no dip
    assert _modes(np.arange(11.0), apart)[2].tolist() == [True, True]


def test_finer_axis_covers_each_unresolved_region_with_the_stated_nodes():
    axis = np.linspace(0.0, 1.0, 11)
    modes = (np.array([3, 7]), np.array([5, 8]), np.array([True, False]))
    finer = _finer_axis(axis, modes, 9, None, 2.0)
    region = np.linspace(0.2, 0.6, 9)  # nodes 2..6: max(9, 2 * 4 + 1)
    np.testing.assert_allclose(finer, np.concatenate([region, axis[7:10]]))  # 6..9 as they are
    wider = _finer_axis(axis, modes, 5, None, 3.0)
    np.testing.assert_allclose(wider[:13], np.linspace(0.2, 0.6, 13))  # ceil(3 * 4) + 1
    keep = np.array([0.4 + 0.5 * SAME_NODE * 0.05, 0.9])
    kept = _finer_axis(axis, modes, 9, keep, 2.0)
    assert keep[0] in kept and 0.4 not in kept  # within SAME_NODE spacings: gives way to it
    off = _finer_axis(axis, modes, 9, np.array([0.4 + 2 * SAME_NODE * 0.05]), 2.0)
    assert off.size == finer.size + 1 and 0.4 in off
    assert np.all(np.diff(kept) > 0.0) and kept.size == finer.size


def test_finer_axis_shares_the_nodes_beyond_refine_modes():
    axis = np.linspace(0.0, 1.0, 41)
    first, last = np.array([2, 12, 22, 32]), np.array([4, 14, 24, 34])
    finer = _finer_axis(axis, (first, last, np.ones(4, bool)), 30, None, 1.25)
    assert finer.size == 4 * 15  # max(2 * 30 // 4, MIN_MODE_NODES) each, disjoint regions
    few = _finer_axis(axis, (first, last, np.ones(4, bool)), 10, None, 1.25)
    assert few.size == 4 * MIN_MODE_NODES


def test_zero_edges_are_both_lines_of_each_cell_the_zero_region_crosses():
    axis = np.linspace(0.0, 1.0, 6)
    logp = np.array([0.0, 0.0, -np.inf, -np.inf, 0.0, 0.0])
    np.testing.assert_allclose(zero_edges([axis], logp)[0], axis[[1, 2, 3, 4]])
    two = np.zeros((6, 6))
    two[4:, :] = -np.inf  # the first parameter's last two rows
    lines = zero_edges([axis, axis], two.ravel())
    np.testing.assert_allclose(lines[0], axis[[3, 4]])
    assert lines[1].size == 0


def test_conditional_sds_of_a_correlated_normal_in_node_spacings():
    axis = np.linspace(-6.0, 6.0, 241)
    h = axis[1] - axis[0]
    x, y = np.meshgrid(axis, axis, indexing="ij")
    sx, sy, rho = 1.0, 0.5, 0.8
    z = (x / sx) ** 2 - 2 * rho * (x / sx) * (y / sy) + (y / sy) ** 2
    logp = (-0.5 * z / (1 - rho**2)).ravel()
    cx, cy = conditional_sds([axis, axis], logp)
    assert cx == pytest.approx(sx * np.sqrt(1 - rho**2) / h, rel=2e-3)
    assert cy == pytest.approx(sy * np.sqrt(1 - rho**2) / h, rel=2e-3)
    alternating = np.cumsum(np.r_[0.0, np.tile([h, 2 * h], 120)]) - 6.0 * 1.5
    x, y = np.meshgrid(alternating, axis, indexing="ij")
    logp = -0.5 * ((x / sx) ** 2 + (y / sy) ** 2)
    cx, cy = conditional_sds([alternating, axis], logp.ravel())
    assert cx == pytest.approx(sx / (2 * h), rel=5e-3)  # the wider interval next to a node
    assert cy == pytest.approx(sy / h, rel=5e-3)


def test_resolution_is_the_sd_in_node_spacings_and_zero_for_a_spike():
    axis = np.linspace(0.0, 1.0, 201)
    h = axis[1]
    assert _resolution(axis, norm.pdf(axis, 0.5, 6 * h)) == pytest.approx(6.0, rel=1e-3)
    two = norm.pdf(axis, 0.25, 3 * h) + norm.pdf(axis, 0.7, 3 * h)
    assert _resolution(axis, two) == pytest.approx(3.0, rel=1e-3)
    spike = norm.pdf(axis, 0.3, 6 * h)
    spike[150] = 1e-6 * spike.max()  # a peak on one node, above MODE_MASS of the mass
    assert _resolution(axis, spike) == 0.0
    spike[150] = 1e-2 * MODE_MASS * spike.max()  # below: left out
    assert _resolution(axis, spike) == pytest.approx(6.0, rel=1e-3)
    alternating = np.cumsum(np.r_[0.0, np.tile([h, 2 * h], 100)]) / (300 * h)
    wide = norm.pdf(alternating, 0.5, 0.04)
    assert _resolution(alternating, wide) == pytest.approx(0.04 / (2 / 300), rel=5e-3)


def test_the_core_holds_all_but_tail_mass_with_one_more_node_each_side():
    axis = np.linspace(-10.0, 10.0, 2001)
    d = norm.pdf(axis, 1.0, 1.0)
    c0, c1 = _core(axis, d)
    below = np.concatenate(([0.0], np.cumsum(0.5 * np.diff(axis) * (d[:-1] + d[1:]))))
    tail = 0.5 * TAIL_MASS * below[-1]
    assert below[c0 + 1] <= tail < below[c0 + 2]  # the last node with at most tail before it
    assert below[-1] - below[c1 - 1] <= tail < below[-1] - below[c1 - 2]
    assert axis[c0] == pytest.approx(1.0 - 3.29 - 0.01, abs=0.011)  # its 0.0005 quantile, a node on
    assert axis[c1] == pytest.approx(1.0 + 3.29 + 0.01, abs=0.011)
    coarse = np.linspace(-1.0, 1.0, 11)  # each end cell holds more than the tail: all kept
    assert _core(coarse, np.ones(11)) == (0, 10)
    heavy_end = np.r_[np.linspace(0.0, 0.999, 1000), 2.0]  # the last cell holds half the mass
    assert _core(heavy_end, np.ones(1001))[1] == 1000


def test_refined_axis_resolves_a_narrow_peak_and_leaves_a_wide_one():
    axis = np.linspace(0.0, 1.0, 33)
    h = axis[1]
    wide = norm.logpdf(axis, 0.5, 5 * h)
    assert refined_axis(axis, wide, None, 1e-15) == (None, "resolved")
    narrow = norm.logpdf(axis, 0.4, 0.8 * h)
    finer, why = refined_axis(axis, narrow, None, 1e-15)
    assert why == "refine" and finer.size >= N_REFINE
    inside = finer[(finer > 0.3) & (finer < 0.5)]
    assert 0.8 * h >= RESOLVE_SD * np.diff(inside).max()  # now resolved
    f = norm.pdf(finer, 0.4, 0.8 * h)
    assert np.trapezoid(f, finer) == pytest.approx(1.0, rel=1e-6)  # the mass is all inside
    assert refined_axis(axis, narrow, None, 0.01) == (None, "float")
    two = np.log(norm.pdf(axis, 0.25, 5 * h) + norm.pdf(axis, 0.75, 5 * h))  # both resolved
    assert refined_axis(axis, two, None, 1e-15) == (None, "resolved")
