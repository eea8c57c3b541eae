"""Laws of gpmsa.calibration.grid that mutation testing (session 91, every second site) found
unchecked, each on a tiny grid with the expectation worked out by hand: the spread's sd where
it is below the IQR's, the local cubic on a grid of exactly STENCIL nodes, an all-zero table
interpolated at k points, the nearest node at a midpoint, the last cell for a uniform draw of
exactly 1, a valley before a peak on the run's last node, a mode's spacing and mass on a
non-uniform axis, a refined region leaving out the grid lines beyond it, the core of a
non-uniform axis, the conditional sds of a log density far from 0, a frozen ConstraintCut
compared by identity, and a refined step equal to ``min_step``."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from gpmsa.calibration.grid import (
    IQR_PER_SD,
    ConstraintCut,
    _core,
    _finer_axis,
    _mode_stats,
    _spread,
    _valleys,
    conditional_sds,
    draw_bilinear,
    interp_log,
    nearest,
    refined_axis,
    whole_refined_axis,
)


def test_the_spread_of_a_uniform_mass_is_its_sd():
    """Equal masses 1 at 0, 1, 2, 3 (total 4): mean 1.5, sd sqrt(1.25); the centred cdf
    (0.125, 0.375, 0.625, 0.875) puts the quartiles at 0.5 and 2.5, IQR / IQR_PER_SD = 1.483 >
    sd, so the spread is the sd."""
    spread = _spread(np.arange(4.0), np.ones(4))
    assert 2.0 / IQR_PER_SD > np.sqrt(1.25)
    assert spread == pytest.approx(np.sqrt(1.25), rel=1e-14)


def test_the_local_cubic_applies_on_a_grid_of_exactly_stencil_nodes():
    """log density -x^2 on 0, 1, 2, 3 (second differences -2, -2: smooth): the cubic through
    the four nodes is exact at 1.5 (-2.25) where linear interpolation gives -2.5."""
    axis = np.arange(4.0)
    out = interp_log(-(axis**2), axis, np.array([[1.5]]), smooth=True)
    np.testing.assert_allclose(out, [-2.25], rtol=1e-14)
    np.testing.assert_allclose(interp_log(-(axis**2), axis, np.array([[1.5]])), [-2.5])


def test_a_table_of_zero_density_gives_minus_inf_at_every_point():
    """Three points (3, 1) on an all -inf table: three values, all -inf."""
    axis = np.linspace(0.0, 1.0, 5)
    out = interp_log(np.full(5, -np.inf), axis, np.array([[0.1], [0.5], [0.9]]))
    assert out.shape == (3,)
    assert np.all(np.isneginf(out))


def test_a_value_midway_between_two_nodes_is_given_the_upper_node():
    """Nodes 0, 1, 2: 0.5 and 1.5 are as near either neighbour; the upper one is returned
    (0.4 and 1.6 are strictly nearer 0 and 2)."""
    out = nearest(np.array([0.0, 1.0, 2.0]), np.array([0.5, 1.5, 0.4, 1.6]))
    np.testing.assert_array_equal(out, [1, 2, 0, 2])


class _OnesRng:
    """A generator whose uniforms are all exactly 1.0, the closed end of [0, 1]."""

    def random(self, size: int) -> np.ndarray:
        return np.ones(size)


def test_a_uniform_draw_of_one_lands_in_the_last_cell():
    """Axes (0, 1, 2) and (0, 1), density 1 everywhere: the cells' cumulative masses are 4, 8; a
    uniform of 1.0 reaches 8, searchsorted's 'right' gives 2 (no such cell), held to the last
    cell (i, j) = (1, 0); s = t = 1 put the draw on its far corner (2, 1), node 2 * 2 + 1 = 5."""
    vals, node = draw_bilinear(
        [np.array([0.0, 1.0, 2.0]), np.array([0.0, 1.0])], np.ones((3, 2)), _OnesRng(), 2
    )
    np.testing.assert_array_equal(vals, [[2.0, 1.0], [2.0, 1.0]])
    np.testing.assert_array_equal(node, [5, 5])


def test_a_valley_before_a_peak_on_the_last_node_of_the_run_separates():
    """Density 1, 0.1, 1 on the run 0..2: the dip at node 1 is below 0.5 times the highest
    density on either side (1 left, 1 on the run's last node right)."""
    assert _valleys(np.array([1.0, 0.1, 1.0]), np.array([1]), 0, 2) == [1]


def test_a_mode_on_a_non_uniform_axis_has_the_spacing_of_its_region():
    """Axis 0, 1, 3, 6, density 0, 1, 1, 0: the mode on nodes 1..2 with one more each side spans
    0..6 over 3 cells (spacing 2), mass (1 + 1) * 2 = 4; its two unit masses at 1 and 3 have sd
    1 (IQR / IQR_PER_SD = 2 / 1.349 is larger)."""
    out = _mode_stats(np.array([0.0, 1.0, 3.0, 6.0]), np.array([0.0, 1.0, 1.0, 0.0]), 1, 2)
    np.testing.assert_allclose(out, (4.0, 1.0, 2.0), rtol=1e-14)


def test_a_refined_region_leaves_out_the_grid_lines_beyond_it():
    """One unresolved mode on nodes 4..6 of 0, 0.1, ..., 1 (region 0.3..0.7, 4 cells): 9 equally
    spaced nodes (n = 9 = 2 * 4 + 1); the grid line 0.05 lies outside the region and is not
    added."""
    axis = np.linspace(0.0, 1.0, 11)
    modes = (np.array([4]), np.array([6]), np.array([True]))
    out = _finer_axis(axis, modes, 9, np.array([0.05]), 2.0)
    np.testing.assert_array_equal(out, np.linspace(axis[3], axis[7], 9))


def test_the_core_of_a_non_uniform_axis_weighs_each_cell_by_its_width():
    """Axis 0, 1, 2, 3, 2003, density 0, 0, 1, 1, 1: cell masses 0, 0.5, 1, 2000 (total
    2001.5, half of TAIL_MASS of it 1.0008); the mass before node 2 (0.5) is within that, the
    mass before node 3 (1.5) is not, so the core starts at node 2, one node more: 1; it ends at
    the last node."""
    axis, density = np.array([0.0, 1.0, 2.0, 3.0, 2003.0]), np.array([0.0, 0.0, 1.0, 1.0, 1.0])
    assert _core(axis, density) == (1, 4)


@pytest.mark.parametrize("level", [0.0, 1000.0, -1000.0])
def test_conditional_sds_of_a_flat_density_at_any_level(level):
    """A flat log density (any constant) on the 3 x 3 grid 0, 1, 2: given either parameter the
    other has trapezoid masses 0.5, 1, 0.5 about mean 1, variance (0.5 + 0.5) / 2 = 0.5, in unit
    spacings: sqrt(0.5) each."""
    axes = [np.array([0.0, 1.0, 2.0]), np.array([0.0, 1.0, 2.0])]
    out = conditional_sds(axes, np.full(9, level))
    np.testing.assert_allclose(out, (np.sqrt(0.5), np.sqrt(0.5)), rtol=1e-14)


def test_a_constraint_cut_is_frozen_and_compared_by_identity():
    """The cut is shared by every update of a Calibrator: its fields cannot be rebound; it is
    hashable and equal only to itself (its fields are arrays, which have no single truth)."""
    axes = [np.linspace(0.0, 1.0, 3), np.linspace(0.0, 1.0, 3)]
    ok = np.ones(9, dtype=bool)
    cut = ConstraintCut.make(axes, ok, lambda p: np.ones(p.shape[0], dtype=bool))
    twin = ConstraintCut.make(axes, ok, lambda p: np.ones(p.shape[0], dtype=bool))
    assert len({cut, twin}) == 2
    assert cut == cut and cut != twin
    with pytest.raises(dataclasses.FrozenInstanceError):
        cut.allowed = np.zeros((3, 3), dtype=bool)


def test_a_refined_step_equal_to_the_smallest_step_is_refined():
    """A Student-t peak whose mode holds the whole 33-node axis: the refined axis is
    `whole_refined_axis`; with ``min_step`` equal to its smallest step (representable, not
    closer) it is kept ("refine"), a hair above it it is not ("float")."""
    axis = np.linspace(0.0, 1.0, 33)
    logp = -2.0 * np.log1p(((axis - 0.4) / 0.005) ** 2 / 3.0)
    finer = whole_refined_axis(axis)
    step = float(np.diff(finer).min())
    out, why = refined_axis(axis, logp, None, step)
    assert why == "refine"
    np.testing.assert_array_equal(out, finer)
    assert refined_axis(axis, logp, None, np.nextafter(step, 1.0)) == (None, "float")
