"""Laws of the grid refinement's helpers that mutation testing (session 86, part 6) found
unchecked: `tail_refined_axes` (which parameters it refines, the node count and spacing of a
refined core, a kept grid line displacing a core node, the bounds on ``res`` and ``below``, a core
spanning the whole axis) and the marginals under a constant added to the log density."""

from __future__ import annotations

import numpy as np
import pytest

from gpmsa.calibration.grid import (
    SAME_NODE,
    _core,
    _marginals,
    refined_axes,
    resolution,
    tail_refined_axes,
)

AXIS = np.linspace(0.0, 1.0, 101)


def student_t(axis: np.ndarray, centre: float, scale: float) -> np.ndarray:
    """Log density of a Student-t (3 dof): tails heavy enough that the core is narrower than the
    axis."""
    return -2.0 * np.log1p(((axis - centre) / scale) ** 2 / 3.0)


def two_param_logp(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """A heavy-tailed first parameter, a Gaussian (sd 0.1) second one: (G,), 'ij' order."""
    return (student_t(a, 0.4, 0.05)[:, None] - 0.5 * ((b[None, :] - 0.5) / 0.1) ** 2).ravel()


@pytest.mark.parametrize(("res", "n_core"), [(1.0, 361), (2.0, 181), (3.5, 129)])
def test_a_core_gets_resolve_sd_nodes_per_sd_at_least_n_refine(res, n_core):
    """The core (nodes 1..91 here) is replaced by equally spaced nodes, RESOLVE_SD / res times
    its cells (1.0: 4 x 90 cells; 2.0: 2 x 90) but at least REFINE_FACTORS[-1] times them and
    N_REFINE nodes (3.5: 1.25 x 90 + 1 = 114 < 129); the tails keep nodes of the old axis."""
    logp = student_t(AXIS, 0.4, 0.05)
    c0, c1 = _core(AXIS, _marginals([AXIS], logp)[0])
    assert (c0, c1) == (1, 91)
    (finer,) = tail_refined_axes([AXIS], logp, None, (res,), 4.0)
    inside = (finer >= AXIS[c0]) & (finer <= AXIS[c1])
    np.testing.assert_allclose(
        finer[inside], np.linspace(AXIS[c0], AXIS[c1], n_core), rtol=0, atol=1e-15
    )
    assert np.isin(finer[~inside], AXIS).all()
    assert finer[0] == 0.0 and finer[-1] == 1.0


@pytest.mark.parametrize("res", [0.0, 0.1])
def test_a_resolution_of_zero_counts_as_a_tenth(res):
    """`_resolution` gives 0 for a point mass: the core (nodes 35..45) gets RESOLVE_SD / 0.1 =
    40 times its cells, as at 0.1."""
    logp = student_t(AXIS, 0.4, 0.003)
    assert _core(AXIS, _marginals([AXIS], logp)[0]) == (35, 45)
    (finer,) = tail_refined_axes([AXIS], logp, None, (res,), 4.0)
    inside = finer[(finer >= AXIS[35]) & (finer <= AXIS[45])]
    np.testing.assert_allclose(inside, np.linspace(AXIS[35], AXIS[45], 401), rtol=0, atol=1e-15)


def test_a_symmetric_core_is_refined():
    """A peak in the middle of the axis: its core (nodes 5..95) is narrower than the axis."""
    logp = student_t(AXIS, 0.5, 0.05)
    assert _core(AXIS, _marginals([AXIS], logp)[0]) == (5, 95)
    (finer,) = tail_refined_axes([AXIS], logp, None, (1.0,), 4.0)
    assert finer.size > AXIS.size


def test_a_core_spanning_the_whole_axis_is_not_refined():
    assert tail_refined_axes([AXIS], np.zeros(AXIS.size), None, (1.0,), 4.0) is None


@pytest.mark.parametrize(
    ("res", "refined"),
    [((1.0, 4.0), (True, False)), ((1.0, 3.9), (True, True)), ((4.0, 1.0), (False, True))],
)
def test_only_parameters_under_resolve_sd_are_refined(res, refined):
    a, b = np.linspace(0.0, 1.0, 41), np.linspace(0.0, 1.0, 31)
    finer = tail_refined_axes([a, b], two_param_logp(a, b), None, res)
    assert len(finer) == 2
    for axis, new, ref in zip((a, b), finer, refined, strict=True):
        assert (new.size > axis.size) == ref
        if not ref:
            np.testing.assert_array_equal(new, axis)


@pytest.mark.parametrize(
    ("res", "below", "none"),
    [
        ((1.5, 10.0), 1.5, True),
        ((1.4999, 10.0), 1.5, False),
        ((4.0,), 4.0, True),
        ((3.999,), 4.0, False),
    ],
)
def test_nothing_is_refined_unless_some_resolution_is_under_below(res, below, none):
    """``below`` bounds the smallest resolution (a parameter at ``below`` or above is left)."""
    a = np.linspace(0.0, 1.0, 41)
    if len(res) == 2:
        b = np.linspace(0.0, 1.0, 31)
        got = tail_refined_axes([a, b], two_param_logp(a, b), None, res, below)
    else:
        got = tail_refined_axes([a], student_t(a, 0.4, 0.05), None, res, below)
    assert (got is None) == none


def test_a_kept_line_displaces_the_core_node_next_to_it():
    """A grid line 0.001 core spacings from a core node: the node gives way (SAME_NODE), the line
    stays, its neighbours are the core's next nodes a spacing away."""
    logp = student_t(AXIS, 0.4, 0.05)
    core = np.linspace(AXIS[1], AXIS[91], 361)
    step = core[1] - core[0]
    line = core[100] + 1e-3 * step
    (finer,) = tail_refined_axes([AXIS], logp, [np.array([line])], (1.0,), 4.0)
    assert line in finer
    gaps = np.sort(np.abs(finer - line))[1:3] / step
    assert gaps.min() > SAME_NODE
    np.testing.assert_allclose(gaps, [0.999, 1.001], rtol=1e-9)
    (finer,) = tail_refined_axes([AXIS], logp, [np.array([core[100] + 0.015 * step])], (1.0,), 4.0)
    assert core[100] in finer  # 0.015 spacings away: the node stays


def test_a_kept_line_in_a_tail_stays():
    """Grid lines beyond the core (nodes 1..91) are kept too, between the tails' nodes."""
    lines = np.array([0.0037, 0.955])
    (finer,) = tail_refined_axes([AXIS], student_t(AXIS, 0.4, 0.05), [lines], (1.0,), 4.0)
    assert np.isin(lines, finer).all()


@pytest.mark.parametrize("shift", [-800.0, 800.0])
def test_marginals_and_refinement_ignore_a_constant_in_the_log_density(shift):
    """The log density is unnormalised: adding +-800 (exp of which under/overflows) changes
    neither the marginals' resolution nor the refined grid."""
    a, b = np.linspace(0.0, 1.0, 41), np.linspace(0.0, 1.0, 31)
    x, y = np.meshgrid(a, b, indexing="ij")
    logp = (-0.5 * ((x - 0.4) / 0.01) ** 2 - 0.5 * ((y - 0.6) / 0.1) ** 2).ravel()
    np.testing.assert_allclose(
        resolution([a, b], logp + shift), resolution([a, b], logp), rtol=1e-12
    )
    for got, ref in zip(
        refined_axes([a, b], logp + shift, None), refined_axes([a, b], logp, None), strict=True
    ):
        np.testing.assert_array_equal(got, ref)
    one = student_t(AXIS, 0.4, 0.05)
    np.testing.assert_allclose(
        _marginals([AXIS], one + shift)[0], _marginals([AXIS], one)[0], rtol=1e-12
    )
