"""Laws of gpmsa.calibration.grid that mutation testing (session 92, the odd half of the sites)
found unchecked, each on a small case with the expectation fixed by hand: the tail refinement's
schedule of shares (the first of 1.0, 0.7, 0.5, 0.35, 0.25, 0.18, 0.12 whose grid fits the node
budget) and its default threshold, UNRESOLVED_SD = 1.5 node spacings per sd; the number of
rounds of redrawing a constraint's rejections; a one-node peak holding exactly MODE_MASS of the
mass; the quick peak test's False; the second refinement factor (1.5) and the fewest nodes
of a refined mode beyond REFINE_MODES (9); the nodes of a refined mode with two parameters
(49); node budgets met exactly (516 nodes for one parameter, 9604 for two, a tail step equal
to ``min_step``); which small narrow peaks a mode count refines (MODE_MASS of the peaks' mass
or more); the core's ends where the mass before a node is exactly half of TAIL_MASS; a new node
on the last grid line of a cell no boundary crosses; a peak whose spread is exactly RESOLVE_SD
node spacings; the local spacing at an axis' first node."""

from __future__ import annotations

import numpy as np
import pytest

from gpmsa.calibration.grid import (
    MAX_REFINED,
    MODE_MASS,
    N_REFINE,
    RESOLVE_SD,
    ConstraintCut,
    _core,
    _finer_axis,
    _mode_stats,
    _modes,
    _one_resolved_peak,
    _resolution,
    _with_core,
    conditional_sds,
    draw_allowed,
    mesh,
    refined_axes,
    refined_axis,
    tail_refined_axes,
    trapezoid_weights,
)
from gpmsa.errors import GPMSAError


def narrow_normal(n: int) -> tuple[np.ndarray, np.ndarray]:
    """An n-node unit axis and a normal log density at 0.5 with an sd of 3 node spacings: its
    core (`_core`) is 24 nodes, the rest of the axis is tails."""
    axis = np.linspace(0.0, 1.0, n)
    return axis, -0.5 * ((axis - 0.5) / (3.0 / (n - 1))) ** 2


@pytest.mark.parametrize(
    ("n", "share", "size", "looser", "looser_size"),
    [
        (100, 1.0, 177, None, None),
        (870, 0.7, 439, 1.0, 521),
        (1120, 0.5, 435, 0.7, 517),
        (1450, 0.35, 427, 0.5, 517),
        (1940, 0.25, 429, 0.35, 517),
        (2570, 0.18, 429, 0.25, 517),
        (3420, 0.12, 409, 0.18, 517),
    ],
)
def test_the_tails_keep_the_first_share_of_the_schedule_that_fits(
    n, share, size, looser, looser_size
):
    """One parameter (budget MAX_REFINED * N_REFINE = 516 nodes): the core of 24 nodes (23 cells,
    4 * 23 + 1 = 93 < N_REFINE) becomes N_REFINE equally spaced nodes; each tail of about
    n / 2 nodes keeps ``share`` of them, the first share of the schedule whose grid holds at
    most 516 nodes (``size``); the share before it in the schedule (``looser``) gives
    ``looser_size`` > 516."""
    axis, logp = narrow_normal(n)
    (finer,) = tail_refined_axes([axis], logp, None, (1.0,), RESOLVE_SD)
    c0, c1 = _core(axis, np.exp(logp - logp.max()))
    assert c1 - c0 == 23
    core = np.linspace(axis[c0], axis[c1], N_REFINE)
    np.testing.assert_array_equal(finer, _with_core(axis, core, c0, c1, share, None, 0))
    assert finer.size == size <= MAX_REFINED * N_REFINE
    if looser is not None:
        wider = _with_core(axis, core, c0, c1, looser, None, 0)
        assert wider.size == looser_size > MAX_REFINED * N_REFINE


def test_the_tail_refinement_runs_below_one_and_a_half_spacings_per_sd_by_default():
    """A resolution of 1.6 spacings per sd (under RESOLVE_SD = 4, over UNRESOLVED_SD = 1.5):
    by default no last pass (None); with the threshold at RESOLVE_SD it refines the core. At
    1.4 the default threshold refines it too, to the same axis."""
    axis, logp = narrow_normal(870)
    assert tail_refined_axes([axis], logp, None, (1.6,)) is None
    (refined,) = tail_refined_axes([axis], logp, None, (1.6,), RESOLVE_SD)
    (default,) = tail_refined_axes([axis], logp, None, (1.4,))
    assert refined.size < axis.size
    # a core of 23 cells: ceil(4 / 1.4 * 23) + 1 = 67 and ceil(4 / 1.6 * 23) + 1 = 59 nodes, both
    # fewer than N_REFINE, so both cores get N_REFINE nodes
    np.testing.assert_array_equal(default, refined)


def test_a_constraint_that_rejects_everything_is_redrawn_one_hundred_rounds():
    """Nothing allowed: each round redraws all 3 draws (no acceptance seen), 100 rounds of 3,
    then the refusal counts 300 rejected of 300."""
    calls = []

    def nothing(p: np.ndarray) -> np.ndarray:
        calls.append(p.shape[0])
        return np.zeros(p.shape[0], dtype=bool)

    axes = [np.array([0.0, 1.0]), np.array([0.0, 1.0])]
    rng = np.random.default_rng(0)
    with pytest.raises(GPMSAError, match=r"the constraint rejected 300 of 300 draws"):
        draw_allowed(axes, np.ones((2, 2)), rng, 3, nothing)
    assert calls == [3] * 100


def test_a_one_node_peak_holding_exactly_mode_mass_leaves_the_grid_unresolved():
    """A bump 1, 2, 3, 3, 2, 1 on nodes 0..5 of 0, 1, ..., 9 (trapezoid mass 11.5) and a peak on
    node 8 alone of density 1.15000000115e-8, exactly MODE_MASS of the total in float64: "that
    much or more" reads the grid as unresolved (0.0); one float64 step less and the peak is
    left out, the resolution that of the bump alone."""
    axis = np.arange(10.0)
    density = np.array([1.0, 2.0, 3.0, 3.0, 2.0, 1.0, 0.0, 0.0, 1.15000000115e-08, 0.0])
    assert density[8] == MODE_MASS * (density @ trapezoid_weights(axis))
    assert _resolution(axis, density) == 0.0
    bump = np.where(np.arange(10) == 8, 0.0, density)
    less = np.where(np.arange(10) == 8, np.nextafter(density[8], 0.0), density)
    assert _resolution(axis, less) == _resolution(axis, bump) > 1.0


def test_the_quick_peak_test_answers_false_for_a_valley():
    """Density 1, 0, 1 on 0, 1, 2: after its highest node (the first) it falls and rises again,
    not one peak: False (a bool, as for a resolved peak)."""
    assert _one_resolved_peak(np.arange(3.0), np.array([1.0, 0.0, 1.0])) is False


def test_a_mode_too_wide_to_double_is_refined_one_and_a_half_times():
    """A Student-t peak whose mode holds the whole 301-node axis (300 cells): doubled, 601
    nodes exceed the budget MAX_REFINED * N_REFINE = 516; the next factor, 1.5, gives 451
    equally spaced nodes, which fit."""
    axis = np.linspace(0.0, 1.0, 301)
    logp = -2.0 * np.log1p(((axis - 0.4) / 0.005) ** 2 / 3.0)
    finer, why = refined_axis(axis, logp, None, 0.0)
    assert why == "refine"
    np.testing.assert_allclose(finer, np.linspace(0.0, 1.0, 451), rtol=0.0, atol=1e-15)


def test_many_modes_get_nine_nodes_each_at_least():
    """Four unresolved modes (nodes 2-4, 12-14, 22-24, 32-34 of 41) sharing n = 10: 2 * 10 // 4
    = 5 nodes each is under the least, 9, and 1.25 times their 4 cells (6 nodes) too: 4 x 9."""
    axis = np.linspace(0.0, 1.0, 41)
    first, last = np.array([2, 12, 22, 32]), np.array([4, 14, 24, 34])
    few = _finer_axis(axis, (first, last, np.ones(4, bool)), 10, None, 1.25)
    assert few.size == 36
    np.testing.assert_allclose(few[:9], np.linspace(axis[1], axis[5], 9), rtol=0.0, atol=1e-15)


def test_a_narrow_peak_of_two_parameters_is_refined_on_49_nodes_each():
    """A normal peak at (0.5, 0.5) with an sd of one node spacing on the 41 x 41 unit grid: its
    mode (density above MASS_CUTOFF = 1e-14 of the peak, within 8 sds) holds nodes 12..28; with
    one more each side, 11..29 (18 cells, doubled: 37 nodes) gets 49 equally spaced nodes per
    parameter, and nothing beyond it is kept."""
    axis = np.linspace(0.0, 1.0, 41)
    z = (axis - 0.5) / axis[1]
    logp = (-0.5 * z[:, None] ** 2 - 0.5 * z[None, :] ** 2).ravel()
    finer = refined_axes([axis, axis], logp, None)
    for out in finer:
        np.testing.assert_allclose(out, np.linspace(axis[11], axis[29], 49), rtol=0.0, atol=1e-15)


def student_t(axis: np.ndarray, centre: float, scale: float) -> np.ndarray:
    """Log density of a Student-t (3 dof): a narrow peak whose tails reach the axis' ends."""
    return -2.0 * np.log1p(((axis - centre) / scale) ** 2 / 3.0)


def test_a_refined_axis_of_exactly_the_budget_fits():
    """A mode holding the whole 344-node axis (343 cells): doubled 687 nodes, 1.5 times
    ceil(514.5) + 1 = 516 = MAX_REFINED * N_REFINE, which fits (not 1.25 times: 430)."""
    axis = np.linspace(0.0, 1.0, 344)
    finer, why = refined_axis(axis, student_t(axis, 0.4, 0.005), None, 0.0)
    assert why == "refine"
    np.testing.assert_allclose(finer, np.linspace(0.0, 1.0, 516), rtol=0.0, atol=1e-15)


def test_a_two_parameter_grid_of_exactly_the_budget_fits():
    """A mode holding the whole 131-node first axis (130 cells) and a wide, resolved normal on
    the 49-node second: doubled, 261 x 49 nodes; 1.5 times, 196 x 49 = 9604 = MAX_REFINED *
    N_REFINE_2D**2, which fits (not 1.25 times: 164 x 49)."""
    a, b = np.linspace(0.0, 1.0, 131), np.linspace(0.0, 1.0, 49)
    logp = (student_t(a, 0.4, 0.005)[:, None] - 0.5 * ((b[None, :] - 0.6) / 0.2) ** 2).ravel()
    finer = refined_axes([a, b], logp, None)
    np.testing.assert_allclose(finer[0], np.linspace(0.0, 1.0, 196), rtol=0.0, atol=1e-15)
    np.testing.assert_array_equal(finer[1], b)


def test_a_tail_refinement_of_exactly_the_budget_keeps_every_share():
    """A normal at 0.45 with an sd of 3 spacings on 860 nodes: its core (nodes 375..398) on
    N_REFINE nodes and share 1.0 of its tails give 516 nodes, exactly the budget: kept."""
    axis = np.linspace(0.0, 1.0, 860)
    logp = -0.5 * ((axis - 0.45) / (3.0 / 859)) ** 2
    (finer,) = tail_refined_axes([axis], logp, None, (1.0,), RESOLVE_SD)
    c0, c1 = _core(axis, np.exp(logp - logp.max()))
    assert (c0, c1) == (375, 398)
    core = np.linspace(axis[c0], axis[c1], N_REFINE)
    np.testing.assert_array_equal(finer, _with_core(axis, core, c0, c1, 1.0, None, 0))
    assert finer.size == MAX_REFINED * N_REFINE == 516


def test_a_tail_refined_step_equal_to_the_smallest_step_is_kept():
    """A Student-t peak on 600 nodes (no refinement factor fits): the tail-refined axis; with
    ``min_step`` equal to its smallest step it is kept ("tails"), a hair above it it is not
    ("float")."""
    axis = np.linspace(0.0, 1.0, 600)
    logp = student_t(axis, 0.4, 0.002)
    finer, why = refined_axis(axis, logp, None, 0.0)
    assert why == "tails" and finer.size == 402
    step = float(np.diff(finer).min())
    out, why = refined_axis(axis, logp, None, step)
    assert why == "tails"
    np.testing.assert_array_equal(out, finer)
    assert refined_axis(axis, logp, None, np.nextafter(step, 1.0)) == (None, "float")


def two_peaks(small: float) -> tuple[np.ndarray, np.ndarray]:
    """On 0, 0.005, ..., 1: a normal at 0.3 with an sd of 10 spacings (peak 1, cut to 0 below
    1e-14; mass 0.1253) and a one-node peak of density ``small`` at node 150."""
    axis = np.linspace(0.0, 1.0, 201)
    density = np.exp(-0.5 * ((axis - 0.3) / 0.05) ** 2)
    density[density < 1e-14] = 0.0
    density[150] = small
    return axis, density


def test_a_narrow_peak_holding_a_billionth_of_the_mass_is_refined():
    """The one-node peak of density 2e-7 over a spacing of 0.005 holds 1e-9 in all, 8e-9 of
    the peaks' mass 0.1253: at least MODE_MASS of it, so it is refined, the wide one not."""
    axis, density = two_peaks(2e-7)
    first, last, unresolved = _modes(axis, density)
    np.testing.assert_array_equal(first, [0, 150])
    np.testing.assert_array_equal(last, [140, 150])
    np.testing.assert_array_equal(unresolved, [False, True])
    assert _mode_stats(axis, density, 150, 150)[0] == pytest.approx(1e-9, rel=1e-12)


def test_a_narrow_peak_holding_exactly_mode_mass_is_refined():
    """The one-node peak's density 2.5066282753503825e-8 gives it exactly MODE_MASS of the
    peaks' mass in float64: refined ("or more"); a billionth less and it is not."""
    axis, density = two_peaks(2.5066282753503825e-8)
    masses = [_mode_stats(axis, density, i0, i1)[0] for i0, i1 in ((0, 140), (150, 150))]
    assert masses[1] == MODE_MASS * np.sum(masses)
    np.testing.assert_array_equal(_modes(axis, density)[2], [False, True])
    axis, density = two_peaks(2.5066282753503825e-8 * (1.0 - 1e-9))
    np.testing.assert_array_equal(_modes(axis, density)[2], [False, False])


def test_the_core_starts_at_a_node_with_exactly_half_the_tail_mass_before_it():
    """Axis 0, 1, 2, 1001.5, density 0, 0, 2, 2: cell masses 0, 1, 1999 (total 2000, half of
    TAIL_MASS of it 1.0); the mass before node 2 is exactly 1.0, within the tail, so the core
    starts at node 2, one node more: 1; it ends at the last node."""
    assert _core(np.array([0.0, 1.0, 2.0, 1001.5]), np.array([0.0, 0.0, 2.0, 2.0])) == (1, 3)


def test_the_core_ends_at_a_node_with_exactly_half_the_tail_mass_after_it():
    """The mirror image: axis 0, 999.5, 1000.5, 1001.5, density 2, 2, 0, 0: the mass before node
    1 is 1999 = 2000 - 1.0, so the core ends at node 1, one node more: 2."""
    assert _core(np.array([0.0, 999.5, 1000.5, 1001.5]), np.array([2.0, 2.0, 0.0, 0.0])) == (0, 2)


def test_a_new_node_on_the_last_grid_line_takes_the_verdict_of_its_uncrossed_cell():
    """Grid 0, 1/3, 2/3, 1 per parameter; the constraint forbids the strip 0.3 < x < 0.4 (so
    every cell left of x = 2/3 is crossed and split) and a sliver 0.45 < y < 0.55 on x > 0.99,
    between the grid's nodes. The new node (1, 0.5) lies only in the last column's cell, which
    no boundary crosses: it takes that cell's verdict, allowed (its neighbour to the left is
    crossed, but does not touch x = 1)."""
    a = np.linspace(0.0, 1.0, 4)

    def allows(p: np.ndarray) -> np.ndarray:
        x, y = p[:, 0], p[:, 1]
        return ~(((x > 0.3) & (x < 0.4)) | ((x > 0.99) & (y > 0.45) & (y < 0.55)))

    cut = ConstraintCut.make([a, a], allows(mesh([a, a])), allows)
    f0, f1 = cut.axes
    assert f0[-1] == 1.0 and f1[6] == pytest.approx(0.5, abs=1e-15)
    assert not allows(np.array([[1.0, f1[6]]]))[0]
    assert cut.allowed[-1, 6]


def test_one_peak_spread_over_exactly_resolve_sd_spacings_is_resolved():
    """Density 1 on the nodes -7..7 of the unit-spaced axis -8..8 and 3.5 at 0 (one peak, no
    dip): variance 280 / 17.5 = 16, an sd of exactly RESOLVE_SD = 4 spacings (its IQR / 1.349
    is wider), which resolves it."""
    axis = np.arange(-8.0, 9.0)
    density = np.concatenate(([0.0], np.ones(7), [3.5], np.ones(7), [0.0]))
    first, last, unresolved = _modes(axis, density)
    assert (first.tolist(), last.tolist()) == ([1], [15])
    np.testing.assert_array_equal(unresolved, [False])


def test_the_local_spacing_at_the_first_node_is_its_one_interval():
    """Axis 0, 2, 3 (intervals 2, 1): local spacings 2, max(2, 1) = 2, 1. A flat density has
    trapezoid masses 1, 1.5, 0.5 (mean 1.5, variance 3.75 / 3 = 1.25) and mean squared local
    spacing (4 + 6 + 0.5) / 3 = 3.5: sqrt(1.25 / 3.5) = sqrt(5 / 14) spacings per sd, for the
    resolution and, given a second parameter on 0, 1, 2, the conditional sd (the second's:
    sqrt(0.5), as on a uniform grid)."""
    a, b = np.array([0.0, 2.0, 3.0]), np.array([0.0, 1.0, 2.0])
    assert _resolution(a, np.ones(3)) == pytest.approx(np.sqrt(5.0 / 14.0), rel=1e-14)
    sds = conditional_sds([a, b], np.zeros(9))
    np.testing.assert_allclose(sds, (np.sqrt(5.0 / 14.0), np.sqrt(0.5)), rtol=1e-14)
