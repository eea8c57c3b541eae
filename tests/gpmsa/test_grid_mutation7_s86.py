"""Laws of the grid refinement and the constraint cut that mutation testing (session 86, part 7)
found unchecked: `whole_refined_axis` against `refined_axis`, `_with_core`'s kept grid lines on
a trimmed axis and its tail count at small shares, `refined_axes`'s budget on axes of unequal
size, and `ConstraintCut.make`'s verdict at new nodes on the edge a crossed cell shares with an
uncrossed one; `_cell_inverse` held to [0, 1] where rounding puts the root above 1; the size of each
round of `draw_allowed`'s redraws."""

from __future__ import annotations

import numpy as np
import pytest

from gpmsa.calibration.grid import (
    MAX_REFINED,
    N_REFINE,
    N_REFINE_2D,
    REFINE_FACTORS,
    TAIL_SHARES,
    ConstraintCut,
    _cell_inverse,
    _with_core,
    draw_allowed,
    refined_axes,
    refined_axis,
    tail_refined_axes,
    whole_refined_axis,
)


def student_t(axis: np.ndarray, centre: float, scale: float) -> np.ndarray:
    """Log density of a Student-t (3 dof): a narrow peak whose tails reach the axis' ends."""
    return -2.0 * np.log1p(((axis - centre) / scale) ** 2 / 3.0)


@pytest.mark.parametrize("n", [33, 101])
def test_the_whole_refined_axis_is_the_refinement_of_a_peak_with_heavy_tails(n):
    """One unresolved mode holding the whole axis: `refined_axis` gives equally spaced nodes
    over it, REFINE_FACTORS[0] times its cells but at least N_REFINE (33: 129; 101: 201), the
    axis that a Calibrator prepares its predictors for."""
    axis = np.linspace(0.0, 1.0, n)
    finer, why = refined_axis(axis, student_t(axis, 0.4, 0.005), None, 0.0)
    assert why == "refine"
    expected = np.linspace(0.0, 1.0, max(N_REFINE, int(REFINE_FACTORS[0] * (n - 1)) + 1))
    np.testing.assert_allclose(whole_refined_axis(axis), expected, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(whole_refined_axis(axis), finer)


def test_kept_lines_beyond_a_trimmed_axis_are_left_out_and_those_inside_kept():
    """A refined axis trimmed to [0.2, 0.8] and the base grid's lines over [0, 1] (a gridded
    prior's zero edges): the tail refinement keeps the lines inside (in the first and last
    cells too) and adds none beyond the axis' ends."""
    axis = np.linspace(0.2, 0.8, 61)
    lines = np.array([0.0, 0.1, 0.203, 0.6, 0.797, 0.9, 1.0])
    (finer,) = tail_refined_axes([axis], student_t(axis, 0.45, 0.02), [lines], (1.0,), 4.0)
    assert finer[0] == axis[0] and finer[-1] == axis[-1]
    assert np.isin(lines[2:5], finer).all()


@pytest.mark.parametrize("share", TAIL_SHARES)
@pytest.mark.parametrize("span", [3, 10, 40])
def test_each_tail_keeps_a_share_of_its_nodes_and_at_least_two(share, span):
    """``span`` nodes beyond the core on each side: ceil(share * span) of them are kept, but at
    least two (the nearest and the end node), and never more."""
    axis = np.linspace(0.0, 1.0, 2 * span + 21)
    c0, c1 = span, span + 20
    core = np.linspace(axis[c0], axis[c1], 81)
    out = _with_core(axis, core, c0, c1, share, None, 0)
    count = max(int(np.ceil(share * span)), 2)
    for tail in (out[out < axis[c0]], out[out > axis[c1]]):
        assert 2 <= tail.size <= count
        assert np.isin(tail, axis).all()
    assert {axis[0], axis[c0 - 1], axis[c1 + 1], axis[-1]} <= set(out)


def test_the_node_budget_counts_both_axes_of_unequal_size():
    """A heavy-tailed first parameter (its mode holds the whole 101-node axis, refined
    REFINE_FACTORS[0] times: 201 nodes) and a resolved second one (41 nodes kept): 201 x 41 =
    8241 nodes fit MAX_REFINED * N_REFINE_2D**2 = 9604 (201**2 would not)."""
    a, b = np.linspace(0.0, 1.0, 101), np.linspace(0.0, 1.0, 41)
    logp = (student_t(a, 0.4, 0.01)[:, None] - 0.5 * ((b[None, :] - 0.6) / 0.2) ** 2).ravel()
    finer = refined_axes([a, b], logp, None)
    assert finer is not None
    assert (finer[0].size, finer[1].size) == (201, 41)
    assert finer[0].size * finer[1].size <= MAX_REFINED * N_REFINE_2D**2 < finer[0].size ** 2
    np.testing.assert_array_equal(finer[1], b)


def test_new_nodes_on_the_edge_of_a_crossed_cell_get_the_constraints_verdict():
    """A forbidden disk reaching across the edge x = 0.4 between a crossed cell and an uncrossed
    one (both of that edge's corners allowed): the split nodes on that edge, and every split node
    of a crossed cell, get the constraint's own verdict, so the cut density is zero there."""
    a = np.linspace(0.0, 1.0, 6)

    def allows(p: np.ndarray) -> np.ndarray:
        return np.hypot(p[:, 0] - 0.25, p[:, 1] - 0.5) > 0.16

    x, y = np.meshgrid(a, a, indexing="ij")
    ok = allows(np.column_stack([x.ravel(), y.ravel()]))
    cut = ConstraintCut.make([a, a], ok, allows)
    grid_ok = ok.reshape(6, 6)
    corners = np.stack([grid_ok[:-1, :-1], grid_ok[1:, :-1], grid_ok[:-1, 1:], grid_ok[1:, 1:]])
    crossed = corners.any(axis=0) & ~corners.all(axis=0)
    assert not crossed[2, 2] and crossed[1, 2]  # the edge x = 0.4, 0.4 <= y <= 0.6 between
    f0, f1 = cut.axes
    fx, fy = np.meshgrid(f0, f1, indexing="ij")
    verdict = allows(np.column_stack([fx.ravel(), fy.ravel()])).reshape(fx.shape)
    cells = [[np.flatnonzero((a[:-1] <= v) & (v <= a[1:])) for v in f] for f in (f0, f1)]
    in_crossed = np.array([[crossed[np.ix_(ci, cj)].any() for cj in cells[1]] for ci in cells[0]])
    np.testing.assert_array_equal(cut.allowed[in_crossed], verdict[in_crossed])
    edge = (f0 == a[2])[:, None] & (f1 > 0.4)[None, :] & (f1 < 0.6)[None, :]
    assert edge.sum() == 3 and not verdict[edge].any()
    assert not cut.density(np.ones((6, 6)))[edge].any()


def test_the_cell_inverse_stays_in_the_cell_where_rounding_puts_the_root_above_one():
    """At probability 1 the quadratic's root is 1, computed up to 7e-16 above it for a falling
    density (g0 = 1, g1 = 0.1, among others): the position in the cell is held to [0, 1], so no
    draw leaves its cell (nor the grid)."""
    g0, g1 = np.meshgrid(np.arange(1, 51) / 10, np.arange(1, 51) / 10)
    g0, g1 = g0.ravel(), g1.ravel()
    s = _cell_inverse(g0, g1, np.ones(g0.size))
    assert np.all((s >= 0.0) & (s <= 1.0))
    np.testing.assert_allclose(s, 1.0, rtol=0, atol=1e-13)
    target = 0.5 * (g0 + g1)  # the unclipped root, as computed, rounds above 1
    root = 2.0 * target / (g0 + np.sqrt(g0 * g0 + 2.0 * (g1 - g0) * target))
    assert (root > 1.0).sum() > 100


@pytest.mark.parametrize(("width", "seed"), [(0.5, 1), (0.004, 2), (0.004, 5)])
def test_each_round_draws_the_remainder_over_the_acceptance_seen_so_far(width, seed):
    """A uniform density, a constraint allowing x < ``width`` (acceptance 50% and 0.4%): the
    first round draws ``size``, each later one the remainder over the acceptance so far (at most
    100 times the remainder: the 0.4% case's second round), until all are drawn; the constraint
    is never asked about no points."""
    axes = [np.linspace(0.0, 1.0, 11), np.linspace(0.0, 1.0, 11)]
    sizes, hits = [], []

    def allows(p: np.ndarray) -> np.ndarray:
        sizes.append(p.shape[0])
        hits.append(int((p[:, 0] < width).sum()))
        return p[:, 0] < width

    size = 200
    vals = draw_allowed(axes, np.ones((11, 11)), np.random.default_rng(seed), size, allows)
    assert vals.shape == (size, 2) and (vals[:, 0] < width).all()
    expected, drawn, accepted = [size], 0, 0
    for n, hit in zip(sizes[:-1], hits[:-1], strict=True):
        drawn, accepted = drawn + n, accepted + hit
        need = size - accepted
        ratio = int(np.ceil(need * drawn / accepted)) if accepted else need
        expected.append(min(ratio, 100 * need))
    assert sizes == expected
    assert sum(hits[:-1]) < size <= sum(hits)
    if width < 0.01:
        assert 100 * (size - hits[0]) in sizes  # the cap was reached


@pytest.mark.parametrize(("wall", "edge"), [(0.05, 1), (0.25, 2)])
def test_a_bump_across_the_edge_of_a_crossed_cell_is_seen_wherever_the_edge_is(wall, edge):
    """Forbidden left of a wall with a bump (x < wall + 0.16 exp(-((y - 0.5) / 0.05)^2)) whose
    tip crosses the grid line x = a[edge] between a crossed cell and an allowed one (0.25: the
    cells left of it all forbidden, none crossed): the split node at the tip is forbidden."""
    a = np.linspace(0.0, 1.0, 6)

    def allows(p: np.ndarray) -> np.ndarray:
        return p[:, 0] > wall + 0.16 * np.exp(-(((p[:, 1] - 0.5) / 0.05) ** 2))

    x, y = np.meshgrid(a, a, indexing="ij")
    cut = ConstraintCut.make([a, a], allows(np.column_stack([x.ravel(), y.ravel()])), allows)
    tip = (cut.axes[0] == a[edge])[:, None] & (cut.axes[1] == 0.5)[None, :]
    assert tip.sum() == 1 and not cut.allowed[tip].any()
    fx, fy = np.meshgrid(*cut.axes, indexing="ij")
    verdict = allows(np.column_stack([fx.ravel(), fy.ravel()])).reshape(fx.shape)
    np.testing.assert_array_equal(cut.allowed, verdict)


def test_a_forbidden_island_inside_an_uncrossed_cell_keeps_the_corners_verdict():
    """A cell whose corners are all allowed keeps that verdict at its split nodes (split by
    crossed cells in its row and column) even where a small forbidden island holds one: only
    crossed cells are cut."""
    a = np.linspace(0.0, 1.0, 6)

    def allows(p: np.ndarray) -> np.ndarray:
        island = np.hypot(p[:, 0] - 0.5, p[:, 1] - 0.5) < 0.03
        return (p[:, 0] < 0.9) & (p[:, 1] < 0.9) & ~island

    x, y = np.meshgrid(a, a, indexing="ij")
    cut = ConstraintCut.make([a, a], allows(np.column_stack([x.ravel(), y.ravel()])), allows)
    centre = (cut.axes[0] == 0.5)[:, None] & (cut.axes[1] == 0.5)[None, :]
    assert centre.sum() == 1 and cut.allowed[centre].all()


def test_the_cut_density_is_the_bilinear_interpolant_at_the_allowed_split_nodes():
    """A linear free density 1 + 2x + 3y is reproduced by the bilinear interpolant: the cut
    density equals it at every allowed node of the split grid (the first row and column
    included) and is zero at the forbidden ones."""
    a = np.linspace(0.0, 1.0, 6)

    def allows(p: np.ndarray) -> np.ndarray:
        return p.sum(axis=1) > 0.3

    x, y = np.meshgrid(a, a, indexing="ij")
    cut = ConstraintCut.make([a, a], allows(np.column_stack([x.ravel(), y.ravel()])), allows)
    fx, fy = np.meshgrid(*cut.axes, indexing="ij")
    assert cut.axes[0].size > a.size
    got = cut.density(1.0 + 2.0 * x + 3.0 * y)
    expected = np.where(cut.allowed, 1.0 + 2.0 * fx + 3.0 * fy, 0.0)
    np.testing.assert_allclose(got, expected, rtol=1e-13, atol=0)
