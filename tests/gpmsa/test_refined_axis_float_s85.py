"""`grid.refined_axis` says "float" whenever the axis it would give spaces some nodes closer than
``min_step`` (float64's resolution of the parameter), on its two paths that mutation testing
(session 85, part 5) found unchecked: a refined axis whose spacing is not even (an unresolved
narrow peak beside a resolved broad one: its largest step is the broad one's), and the heavy-tail
path (no refinement factor fits the node budget: the core refined, `tail_refined_axes`)."""

from __future__ import annotations

import numpy as np

from gpmsa.calibration.grid import refined_axis


def test_an_uneven_refined_axis_is_judged_by_its_smallest_step():
    axis = np.linspace(0.0, 1.0, 129)
    narrow = np.exp(-0.5 * ((axis - 0.3) / 1e-3) ** 2) / 1e-3  # refined: 2e-4 steps
    broad = np.exp(-0.5 * ((axis - 0.8) / 0.035) ** 2) / 0.035  # resolved: kept at 1/128
    logp = np.log(narrow + broad)
    finer, why = refined_axis(axis, logp, None, 1e-15)
    steps = np.diff(finer)
    assert why == "refine" and steps.min() < 1e-3 < steps.max()
    assert refined_axis(axis, logp, None, 1e-3) == (None, "float")


def test_the_heavy_tail_path_says_float_below_the_smallest_step():
    """A Student-t (3 dof) peak of scale 2e-4 on 513 nodes: its tails hold the whole axis above
    MASS_CUTOFF, so no refinement factor fits and the core is refined (steps of about 7e-5)."""
    axis = np.linspace(0.0, 1.0, 513)
    logp = -2.0 * np.log1p(((axis - 0.4) / 2e-4) ** 2 / 3.0)
    finer, why = refined_axis(axis, logp, None, 1e-15)
    assert why == "tails" and finer is not None
    smallest = np.diff(finer).min()
    assert smallest < 1e-4
    assert refined_axis(axis, logp, None, 2.0 * smallest) == (None, "float")
    again, why = refined_axis(axis, logp, None, 0.5 * smallest)
    assert why == "tails"
    np.testing.assert_array_equal(again, finer)
