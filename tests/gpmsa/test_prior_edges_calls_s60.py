"""A callable prior that is zero somewhere, on the one-parameter grid: its zero region's edges are
located by bisection between nodes. The prior was called at the nodes three times per update and
once per bisection step and edge (~50 single-point calls per edge: 2.0 ms per road-case update
against 0.76 ms without it); it is now called at the nodes once and at several steps' points of
all edges at a time, the edges unchanged (bit for bit against the one-point bisection)."""

import numpy as np
import pytest
from _calib_cases import road_emulator, road_obs

from gpmsa import Calibrator
from gpmsa.calibration.calibrator import BISECT_STEPS, PRIOR_BISECT_LEVELS

CUTS = [(380.0, 600.0), (410.0, 470.0), (426.6, 600.0), (300.0, 426.6)]


class Counting:
    """A zero-outside-[low, high] log prior of native GD that counts its calls and points."""

    def __init__(self, low: float, high: float):
        self.low, self.high, self.calls, self.shapes = low, high, 0, set()

    def __call__(self, gd: np.ndarray) -> np.ndarray:
        self.calls += 1
        self.shapes.add(np.shape(gd)[1:])
        return np.where((gd >= self.low) & (gd <= self.high), -0.5 * ((gd - 430.0) / 25.0) ** 2,
                        -np.inf)  # fmt: skip


def one_point_bisection(cal, nodes, ok, allows) -> tuple[np.ndarray, ...]:
    """The edges as located one point at a time (``allows``: unit-scale (1,) -> bool)."""
    std = cal.emulator.standardizer
    span, low = std.t_max[0] - std.t_min[0], std.t_min[0]
    cells = np.flatnonzero(ok[:-1] != ok[1:])
    first, second = nodes[cells].copy(), nodes[cells + 1].copy()
    for j, i in enumerate(cells):
        a, b = first[j], second[j]
        for _ in range(BISECT_STEPS):
            mid = 0.5 * (a + b)
            if not a < mid < b:
                break
            a, b = (mid, b) if allows(np.array([mid])) == ok[i] else (a, mid)
        a = nodes[i] if a * span + low == nodes[i] * span + low else a
        b = nodes[i + 1] if b * span + low == nodes[i + 1] * span + low else b
        first[j], second[j] = a, b
    return cells, first, second


@pytest.mark.parametrize(("low", "high"), CUTS)
def test_the_prior_is_called_a_few_times_per_update(low, high):
    """One or two edges: the prior is called at the nodes, then once per PRIOR_BISECT_LEVELS
    steps of every edge at once (16 calls, was 50 and 96), and at the inserted points."""
    x, y = road_obs()
    prior = Counting(low, high)
    cal = Calibrator(road_emulator())
    post = cal.update(x, y, prior=prior)
    most = 2 + 2 + -(-BISECT_STEPS // PRIOR_BISECT_LEVELS)  # nodes, inserted points, steps
    assert 1 < prior.calls <= most < 50
    assert prior.shapes == {()}  # always (k,) arrays of native GD
    assert post.grids["GD"].ppf(0.0) == pytest.approx(low, abs=1e-9)


@pytest.mark.parametrize(("low", "high"), CUTS)
def test_the_edges_are_the_one_point_bisections(low, high):
    """The edges located for a prior (and for a constraint) are those of the one-point bisection,
    to the last bit."""
    cal = Calibrator(road_emulator())
    axis = cal._axes[0]
    std = cal.emulator.standardizer
    native = axis * (std.t_max[0] - std.t_min[0]) + std.t_min[0]

    def verdict(unit: np.ndarray) -> np.ndarray:
        gd = unit * (std.t_max[0] - std.t_min[0]) + std.t_min[0]
        return (gd >= low) & (gd <= high)

    ok = verdict(axis)
    expected = one_point_bisection(cal, axis, ok, lambda u: bool(verdict(u)[0]))
    got = cal._constraint_edges(axis, ok, verdict)
    for e, g in zip(expected, got, strict=True):
        np.testing.assert_array_equal(g, e)
    assert expected[0].size == int(low > native[0]) + int(high < native[-1])
    constrained = Calibrator(road_emulator(), constraint=lambda th: low <= th[0] <= high)
    for e, g in zip(expected, constrained._base_cut, strict=True):
        np.testing.assert_array_equal(g, e)


def test_a_constraint_is_still_called_one_point_at_a_time():
    """A constraint's function takes native theta (1,) and is called at most once per bisection
    step and edge, besides the nodes."""
    shapes, calls = set(), [0]

    def constraint(th):
        shapes.add(th.shape)
        calls[0] += 1
        return 380.0 <= th[0] <= 470.0

    cal = Calibrator(road_emulator(), constraint=constraint)
    assert shapes == {(1,)}
    assert calls[0] <= cal._axes[0].size + 2 * BISECT_STEPS
