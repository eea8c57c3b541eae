"""Metamorphic tests under a change of units: the same problem stated with x, t, y and the
output index mapped by affine maps (a scale c and a shift b) gives the same answer mapped
through the same maps, to round-off (relative to eps times the shift over the span). Found by
session 87's sweep: a two-column output index offset far beyond its span (epoch seconds, a
map's eastings) or scaled near float64's ends lost points from, or failed, its triangulation;
columns of spans ~1e6 apart are refused. The linear discrepancy basis is in the index's own
units by design (docs/calibration.md): [1, unit index] given as an array is invariant."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.model import index_points

pytestmark = pytest.mark.filterwarnings("ignore::gpmsa.ConvergenceWarning")

EPS = np.finfo(float).eps


def _scattered_points() -> np.ndarray:
    """20 index points in [0, 1]^2: the corners and scattered ones (no four on a circle, so
    that the Delaunay triangulation is unique and unit-free maps keep it exactly)."""
    rng = np.random.default_rng(11)
    corners = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    return np.vstack([corners, rng.uniform(0.05, 0.95, size=(16, 2))])


NEW = np.array([[0.1, 0.2], [0.55, 0.4], [0.9, 0.85], [0.3, 0.7], [0.62, 0.13]])


@pytest.mark.parametrize("shift", [1e4, 1e7, 1.7e9])
def test_index_points_far_from_the_origin_interpolate_as_at_it(shift):
    points = _scattered_points()
    w0 = index_points.weights(points, NEW, "o").toarray()
    w = index_points.weights(points + shift, NEW + shift, "o").toarray()
    # the points themselves are rounded to eps * shift: the weights move by that over the span
    assert np.abs(w - w0).max() <= 100 * EPS * shift


@pytest.mark.parametrize("scale", [1e-200, 1e-9, 1e9, 1e100])
def test_index_points_at_any_scale_interpolate_as_at_one(scale):
    points = _scattered_points()
    w0 = index_points.weights(points, NEW, "o").toarray()
    w = index_points.weights(points * scale, NEW * scale, "o").toarray()
    np.testing.assert_allclose(w, w0, rtol=0, atol=1e-12)


def test_index_columns_of_very_different_spans_are_refused_not_interpolated_wrongly():
    a, b = np.meshgrid(np.linspace(0, 1, 5), np.linspace(0, 1e8, 4), indexing="ij")
    points = np.column_stack([a.ravel(), b.ravel()])  # Qhull left 12 of 20 out: say so
    with pytest.raises(gpmsa.GPMSAError, match="fall out of their triangulation.*comparable"):
        index_points.weights(points, NEW * [1.0, 1e8], "o")
    # taken where no value between points is asked for: the runs, and observations on them
    gpmsa.SimData(t=np.arange(3.0), y=np.ones((3, 20)) * [[0], [1], [3]], index=points)
    on = index_points.weights(points, points[[3, 7]], "o").toarray()
    assert np.array_equal(on, np.eye(20)[[3, 7]])


def _two_column_case(shift: float, scale: float):
    """A small fit and its calibration grid's log-likelihood with the 2-column index mapped by
    ``scale * index + shift``."""
    rng = np.random.default_rng(5)
    x, t = rng.uniform(size=(16, 1)), rng.uniform(size=(16, 1))
    pts = _scattered_points()
    y = np.sin(3 * x + 2 * pts[:, 0]) + t * pts[:, 1] + 0.3 * x
    xo = np.array([[0.3], [0.7]])
    yo = np.sin(3 * xo + 2 * NEW[:, 0]) + 0.4 * NEW[:, 1] + 0.3 * xo + 0.05
    sim = gpmsa.SimData(x=x, t=t, y=y, index=pts * scale + shift)
    obs = gpmsa.ObsData(x=xo, y=yo, index=NEW * scale + shift)
    emu = gpmsa.fit(sim, n_iter=40, tune=False, seed=0)
    return gpmsa.Calibrator(emu, n_grid=17).log_likelihood_grid(obs)[1]


@pytest.mark.parametrize(("shift", "scale"), [(1e7, 1.0), (0.0, 1e-200)])
def test_calibration_on_a_two_column_index_does_not_depend_on_its_units(shift, scale):
    ll0 = _two_column_case(0.0, 1.0)
    ll = _two_column_case(shift, scale)  # before: 0.58 of |loglik| off at 1e7, refused at 1e-200
    assert np.abs(ll - ll0).max() <= 1e-6 * np.abs(ll0).max()


# --- the invariant paths, pinned (the sweep found them invariant at 1e-9 .. 1e9) -------------


def _scalar_case(c: float, b: float):
    """Fit, grid and MCMC calibration and a prediction with x, t and y all mapped by c v + b;
    returned in the unit / standardised scale (the default units' answer at c = 1, b = 0)."""
    rng = np.random.default_rng(3)
    x, t = rng.uniform(size=(20, 1)), rng.uniform(size=(20, 1))
    y = np.sin(3 * x) + t + 0.5 * x * t
    xo = np.array([[0.3], [0.7]])
    yo = np.sin(3 * xo) + 0.4 + 0.2 * xo + 0.01
    sim = gpmsa.SimData(x=c * x + b, t=c * t + b, y=c * y + b, x_names=["x"], t_names=["t"])
    emu = gpmsa.fit(sim, n_iter=60, tune=False, seed=0)
    params = np.concatenate([np.ravel(v) for v in emu.params.values()])
    ll = gpmsa.Calibrator(emu, n_grid=17).log_likelihood_grid(c * xo + b, c * yo + b)[1]
    post = gpmsa.calibrate(emu, c * xo + b, c * yo + b, n_samples=150, n_burn=20, tune=False,
                           seed=1, fixed={"lamOs": 5.0})  # fmt: skip
    theta = (np.asarray(post.samples["t"]) - b) / c
    mean, var = emu.predict(c * xo + b, [[0.5 * c + b]])
    return params, ll, theta, (mean - b) / c, var / c**2


@pytest.mark.parametrize(("c", "b"), [(1e-9, 0.0), (1e9, 0.0), (1.0, 273.15), (1e3, -1e6)])
def test_scalar_problem_in_other_units_gives_the_same_answer(c, b):
    ref = _scalar_case(1.0, 0.0)
    got = _scalar_case(c, b)
    tol = 1e-12 + 1e3 * EPS * abs(b) / min(c, 1.0)  # a shift's rounding relative to the span
    np.testing.assert_array_equal(got[0], ref[0])  # same accept decisions: the same draws
    for a, r in zip(got[1:], ref[1:], strict=True):
        assert np.abs(a - r).max() <= tol * max(np.abs(r).max(), 1.0)


def _linear_unit_discrepancy(scale: float, shift: float) -> np.ndarray:
    """Draws of theta with a linear discrepancy given as [1, unit index] (the index mapped by
    ``scale * g + shift``)."""
    rng = np.random.default_rng(4)
    x, t, g = rng.uniform(size=(20, 1)), rng.uniform(size=(20, 1)), np.linspace(0, 1, 10)
    y = np.sin(3 * x + 2 * g) + t * g + 0.3 * x
    go = np.array([0.05, 0.33, 0.5, 0.71, 0.95])
    xo = np.array([[0.3], [0.7]])
    yo = np.sin(3 * xo + 2 * go) + 0.4 * go + 0.3 * xo + 0.05 + 0.02 * go
    index, obs_index = scale * g + shift, scale * go + shift
    unit = (obs_index - index.min()) / (index.max() - index.min())
    emu = gpmsa.fit(gpmsa.SimData(x=x, t=t, y=y, index=index), n_iter=40, tune=False, seed=0)
    obs = gpmsa.ObsData(x=xo, y=yo, index=obs_index)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.AtBoundWarning)
        post = gpmsa.calibrate(emu, obs, n_samples=150, n_burn=20, tune=False, seed=1,
                               discrepancy=np.column_stack([np.ones(5), unit]))  # fmt: skip
    return np.asarray(post.samples["t0"])


def test_a_linear_discrepancy_on_the_unit_index_does_not_depend_on_its_units():
    ref = _linear_unit_discrepancy(1.0, 0.0)
    for scale, shift in ((1e3, 273.15), (1e-6, 0.0)):
        got = _linear_unit_discrepancy(scale, shift)
        assert np.abs(got - ref).max() <= 1e-9


def test_an_index_spanning_float64s_range_is_refused_by_gpmsa_not_numpy():
    """The rescaled frame divides by a power of two before shifting: a span of 2e308 (which
    overflows as a difference) gave scipy's "Points cannot contain NaN"."""
    points = np.array([[1e308, 0.0], [-1e308, 0.0], [0.0, 1.0], [0.0, -1.0]])
    with pytest.raises(gpmsa.GPMSAError, match="does not span 2 dimensions.*spans are too far"):
        gpmsa.SimData(t=np.arange(4.0), y=np.arange(16.0).reshape(4, 4) ** 2, index=points)
    wide = np.array([[1e308, 0.0], [-1e308, 0.0], [0.0, 1e308], [0.0, -1e308]])
    assert index_points.triangles(wide, "index").shape == (2, 3)


def test_nearly_repeated_points_are_taken_until_a_value_between_them_is_asked_for():
    """Observations on the simulation points (SEPIA's y_ind_obs = y_ind_sim) need no
    triangles; interpolating between points names the points Qhull left out."""
    grid = np.column_stack([np.repeat(np.linspace(0, 1, 4), 5), np.tile(np.linspace(0, 1, 5), 4)])
    points = np.vstack([grid, [[0.1 + 0.2, 0.5], [0.3, 0.5]]])
    gpmsa.SimData(t=np.arange(3.0), y=np.ones((3, 22)) * [[0], [1], [3]], index=points)
    on = index_points.weights(points, points[[20, 21]], "o").toarray()
    assert np.array_equal(on, np.eye(22)[[20, 21]])
    with pytest.raises(
        gpmsa.GPMSAError, match=r"\(row 2[01]\) within rounding of .* \(row 2[01]\)"
    ):
        index_points.weights(points, np.array([[0.5, 0.55]]), "o")


def test_a_point_far_outside_an_index_spanning_float64s_range_is_refused():
    """The hull's rounding slack, HULL_TOL x (hi - lo), overflowed to inf for a column spanning
    more than float64 holds: a point 0.7e308 beyond it was snapped onto its end, one-hot."""
    wide = np.array([[1e308, 0], [-1e308, 0], [0, 1e308], [0, -1e308], [0.2e308, 0.1e308]])
    with pytest.raises(gpmsa.GPMSAError, match="outside the convex hull"):
        index_points.weights(wide, np.array([[-1.7e308, 0.0]]), "q")
    inside = index_points.weights(wide, np.array([[0.0, 0.0]]), "q").toarray()
    assert inside.sum() == pytest.approx(1.0) and np.all(inside >= 0)


def test_the_points_left_out_are_shown_apart():
    grid = np.column_stack([np.repeat(np.linspace(0, 1, 4), 5), np.tile(np.linspace(0, 1, 5), 4)])
    points = np.vstack([grid, [[0.1 + 0.2, 0.5], [0.3, 0.5]]])
    with pytest.raises(gpmsa.GPMSAError) as err:
        index_points.weights(points, np.array([[0.5, 0.55]]), "o")
    first, second = re.findall(r"\(([^()]*)\) \(row 2[01]\)", str(err.value))
    assert first != second
