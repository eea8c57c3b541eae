"""The bilinear draws against exact answers (mutation testing, session 86: the statistical tests
of the draws did not see a wrong coefficient in `_cell_inverse`'s quadratic, a NaN at probability
0, nor a cell's corner taken from the neighbouring cell): `_cell_inverse` against the closed-form
inverse CDF of a linear density, `draw_bilinear`'s moments against the interpolant's."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.interpolate import RegularGridInterpolator

from gpmsa.calibration.grid import ConstraintCut, _cell_inverse, draw_bilinear


@pytest.mark.parametrize(("g0", "g1"), [(1.0, 3.0), (3.0, 1.0), (0.0, 2.0), (2.0, 0.0), (1.0, 1.0)])
def test_the_cell_inverse_is_the_linear_densitys_quantile(g0, g1):
    """Density (1 - s) g0 + s g1: its CDF g0 s + (g1 - g0) s^2 / 2 over (g0 + g1) / 2 is r at the
    returned s, for r from 0 to 1 (the ends included)."""
    r = np.linspace(0.0, 1.0, 11)
    s = _cell_inverse(np.full(r.size, g0), np.full(r.size, g1), r)
    assert np.all((s >= 0.0) & (s <= 1.0))
    cdf = (g0 * s + 0.5 * (g1 - g0) * s**2) / (0.5 * (g0 + g1))
    np.testing.assert_allclose(cdf, r, rtol=0, atol=1e-12)
    assert s[0] == 0.0 and s[-1] == pytest.approx(1.0, abs=1e-12)


def test_bilinear_draws_have_the_interpolants_means_and_covariance():
    """An uneven 4 x 3 grid whose corners differ widely (one zero): 400,000 seeded draws' means
    and covariance match those of the bilinear interpolant (trapezoid sums on a 301 x 301
    mesh) within about 4 standard errors (a corner read from the neighbouring cell moves one of
    them by 0.006-0.06)."""
    axes = [np.array([0.0, 0.3, 0.5, 1.0]), np.array([-1.0, 0.0, 2.0])]
    dens = np.array([[1.0, 4.0, 0.5], [0.2, 3.0, 2.0], [5.0, 0.0, 1.0], [0.5, 2.0, 3.0]])
    u, v = np.linspace(0.0, 1.0, 301), np.linspace(-1.0, 2.0, 301)  # the nodes on mesh lines
    f = RegularGridInterpolator(axes, dens)(np.stack(np.meshgrid(u, v, indexing="ij"), axis=-1))
    fu, fv = np.trapezoid(f, v, axis=1), np.trapezoid(f, u, axis=0)
    z = np.trapezoid(fu, u)
    m0, m1 = np.trapezoid(fu * u, u) / z, np.trapezoid(fv * v, v) / z
    cov = np.trapezoid(np.trapezoid(f * v, v, axis=1) * u, u) / z - m0 * m1
    x, _ = draw_bilinear(axes, dens, np.random.default_rng(3), 400_000)
    assert x[:, 0].mean() == pytest.approx(m0, abs=2e-3)
    assert x[:, 1].mean() == pytest.approx(m1, abs=5e-3)
    assert np.cov(x.T)[0, 1] == pytest.approx(cov, abs=1.5e-3)


def test_each_draws_node_is_its_nearest_on_a_non_square_grid():
    axes = [np.linspace(0.0, 1.0, 5), np.linspace(0.0, 1.0, 3)]
    dens = np.arange(1.0, 16.0).reshape(5, 3)
    x, node = draw_bilinear(axes, dens, np.random.default_rng(0), 2000)
    near = [np.abs(x[:, k, None] - axes[k][None, :]).argmin(axis=1) for k in (0, 1)]
    np.testing.assert_array_equal(node, near[0] * 3 + near[1])


def test_a_constraint_cut_keeps_the_free_density_at_every_corner_of_a_crossed_cell():
    """``live``: the allowed nodes and all four corners of each cell the boundary crosses (the
    cut density interpolates towards a forbidden corner's free density inside such a cell)."""
    a = np.linspace(0.0, 1.0, 6)
    g0, g1 = np.meshgrid(a, a, indexing="ij")
    ok = (g0 + g1 <= 0.9).ravel()
    cut = ConstraintCut.make([a, a], ok, lambda p: p.sum(axis=1) <= 0.9)
    grid_ok = ok.reshape(6, 6)
    expected = grid_ok.copy()
    for i in range(5):
        for j in range(5):
            corners = grid_ok[i : i + 2, j : j + 2]
            if corners.any() and not corners.all():
                expected[i : i + 2, j : j + 2] = True
    np.testing.assert_array_equal(cut.live, expected)
    assert (expected & ~grid_ok).sum() > 5
