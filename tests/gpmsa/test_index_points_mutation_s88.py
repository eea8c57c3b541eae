"""The output-index interpolation (``gpmsa.model.index_points``) pinned against barycentric
coordinates solved by hand, and its checks at their exact edges (the mutation testing of
session 88): the rounding slack on each side of each column, the simplex-count limit, the
fewest points that span, repeated points, and the messages' point texts."""

from __future__ import annotations

import numpy as np
import pytest

import gpmsa
from gpmsa.model import index_points
from gpmsa.model.index_points import HULL_TOL

RNG = np.random.default_rng(11)
PTS2 = np.vstack(
    [[0.0, 0.0], [4.0, 0.0], [0.0, 2.0], [4.0, 2.0], RNG.uniform([0, 0], [4, 2], (9, 2))]
)


def _by_hand(points: np.ndarray, simplices: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Dense weights (l_new, l_sim): for each point, the barycentric coordinates lam solving
    [p_0 .. p_d; 1 .. 1] lam = [q; 1] in the first simplex where all are >= 0."""
    d = points.shape[1]
    W = np.zeros((q.shape[0], points.shape[0]))
    for i, x in enumerate(q):
        for simplex in simplices:
            A = np.vstack([points[simplex].T, np.ones(d + 1)])
            lam = np.linalg.solve(A, np.append(x, 1.0))
            if lam.min() >= -1e-12:
                W[i, simplex] = lam
                break
        else:
            raise AssertionError(f"{x} is in no simplex")
    return W


@pytest.mark.parametrize("d", [2, 3])
def test_weights_are_the_barycentric_coordinates_in_the_points_simplex(d):
    points = PTS2 if d == 2 else np.vstack([np.eye(3), np.zeros(3), RNG.uniform(0, 0.3, (6, 3))])
    lo, hi = points.min(axis=0), points.max(axis=0)
    q = RNG.uniform(lo, hi, (40, d))
    q = q[[bool(index_points._triangulation(points, "p").tri.find_simplex(x) >= 0) for x in q]]
    tri = index_points._triangulation(points, "p").tri
    W = index_points.weights(points, q, "q")
    assert W.shape == (q.shape[0], points.shape[0])
    np.testing.assert_allclose(W.toarray(), _by_hand(points, tri.simplices, q), rtol=0, atol=1e-12)
    assert np.all(np.diff(W.indptr) == d + 1)  # d + 1 entries a row
    # an affine function is reproduced exactly, in any triangulation
    f = points @ np.arange(1.0, d + 1) + 0.5
    np.testing.assert_allclose(W @ f, q @ np.arange(1.0, d + 1) + 0.5, rtol=1e-13, atol=1e-13)


def test_a_simulation_point_is_one_hot_and_minus_zero_is_zero():
    q = np.array([[4.0, 2.0], [-0.0, 0.0], [0.0, -0.0], [2.0, 1.0]])
    W = index_points.weights(PTS2, q, "q").toarray()
    np.testing.assert_array_equal(W[:3], np.eye(PTS2.shape[0])[[3, 0, 0]])
    assert np.count_nonzero(W[3]) >= 2 and W[3].sum() == pytest.approx(1.0)
    # found as a simulation point (one stored entry), not located in a triangle
    assert np.diff(index_points.weights(PTS2, q, "q").indptr)[:3].tolist() == [1, 1, 1]
    flipped = PTS2 * [-1.0, 1.0]  # its first column's 0.0 is -0.0 now
    W = index_points.weights(flipped, np.array([[0.0, 0.0], [-0.0, 2.0]]), "q")
    assert np.diff(W.indptr).tolist() == [1, 1] and W.indices.tolist() == [0, 2]


@pytest.mark.parametrize("col", [0, 1])
@pytest.mark.parametrize("side", ["low", "high"])
def test_the_rounding_slack_is_hull_tol_of_each_columns_span(col, side):
    span = np.ptp(PTS2, axis=0)[col]  # 4 and 2: a slack of its own per column
    edge = np.array([[1.0, 1.0]])
    edge[0, col] = PTS2[:, col].min() if side == "low" else PTS2[:, col].max()
    sign = -1.0 if side == "low" else 1.0
    inside = edge.copy()
    inside[0, col] += sign * 0.9 * HULL_TOL * span  # by rounding: the edge's values
    W_edge = index_points.weights(PTS2, edge, "q").toarray()
    np.testing.assert_array_equal(index_points.weights(PTS2, inside, "q").toarray(), W_edge)
    lo, hi = PTS2[:, col].min(), PTS2[:, col].max()
    at_slack = edge.copy()
    at_slack[0, col] += sign * (HULL_TOL * hi - HULL_TOL * lo)  # the slack itself: taken too
    np.testing.assert_array_equal(index_points.weights(PTS2, at_slack, "q").toarray(), W_edge)
    beyond = edge.copy()
    beyond[0, col] += sign * 1.5 * HULL_TOL * span  # beyond the slack (of the wider column too)
    with pytest.raises(gpmsa.GPMSAError, match=r"has the point \(.*\) \(row 1\) outside"):
        index_points.weights(PTS2, np.vstack([edge, beyond]), "q")


def test_a_point_beyond_a_slanted_edge_by_rounding_is_taken_in_its_triangle():
    tri = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    on = np.array([[0.25, 0.75]])  # on the hypotenuse
    out = on + 1e-13  # beyond it, within HULL_TOL of the triangle
    W_on = index_points.weights(tri, on, "q").toarray()
    np.testing.assert_allclose(W_on, [[0.0, 0.25, 0.75]], rtol=0, atol=1e-15)
    np.testing.assert_allclose(index_points.weights(tri, out, "q").toarray(), W_on, atol=1e-12)
    with pytest.raises(gpmsa.GPMSAError, match="outside the convex hull"):
        index_points.weights(tri, on + 1e-6, "q")


def test_within_is_the_range_up_to_its_rounding_slack():
    lo, hi = 2.0, 6.0
    slack = HULL_TOL * 4.0
    assert index_points.within(np.array([lo, hi]), lo, hi)
    assert index_points.within(np.array([lo - 0.9 * slack, hi + 0.9 * slack]), lo, hi)
    assert not index_points.within(np.array([lo - 1.5 * slack, 3.0]), lo, hi)
    assert not index_points.within(np.array([3.0, hi + 1.5 * slack]), lo, hi)


def test_outside_the_hull_names_the_row_and_the_columns():
    q = np.array([[1.0, 1.0], [2.0, 1.0], [5.0, 0.5]])
    with pytest.raises(
        gpmsa.GPMSAError, match=r"grid has the point \(time 5, angle 0.5\) \(row 2\)"
    ):
        index_points.weights(PTS2, q, "grid", ("time", "angle"))
    with pytest.raises(gpmsa.GPMSAError, match=r"grid has the point \(5, 0.5\) \(row 2\)"):
        index_points.weights(PTS2, q, "grid", ("time",))  # names that do not fit: none


def test_named_and_the_shape_helpers():
    assert index_points.named("grid", ("time",)) == "grid (time)"
    assert index_points.named("grid", ("time", "angle")) == "grid"
    assert index_points.named("grid", None) == "grid"
    assert index_points.is_points(PTS2) and not index_points.is_points(PTS2[:, 0])
    assert not index_points.is_points(None)
    assert index_points.n_points(PTS2) == 13 and index_points.n_points(PTS2[:, 0]) == 13
    index_points.check_columns(PTS2, PTS2[:2], "q")
    index_points.check_columns(PTS2[:, 0], PTS2[:2, 0], "q")
    for new in (PTS2[:2, 0], np.ones((2, 3)), np.ones((2, 2, 1))):
        with pytest.raises(gpmsa.GPMSAError, match=r"q has shape .* 2 column\(s\)"):
            index_points.check_columns(PTS2, new, "q")
    with pytest.raises(gpmsa.GPMSAError, match=r"q has shape \(2, 1, 1\) .* 1 column\(s\)"):
        index_points.check_columns(PTS2[:, 0], np.ones((2, 1, 1)), "q")


def test_the_fewest_points_that_span_and_one_fewer():
    one_triangle = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    index_points.check_points(one_triangle, "index")
    W = index_points.weights(one_triangle, np.array([[0.25, 0.5]]), "q").toarray()
    np.testing.assert_allclose(W, [[0.25, 0.25, 0.5]], rtol=0, atol=1e-15)
    with pytest.raises(gpmsa.GPMSAError, match="index of 2 points in 2 columns does not span"):
        index_points.check_points(one_triangle[:2], "index")


def test_a_repeated_point_names_both_rows():
    pts = PTS2.copy()
    pts[7] = pts[11]  # the first of the two is row 7
    with pytest.raises(gpmsa.GPMSAError, match=r"twice \(rows 7 and 11\)"):
        index_points.check_points(pts, "index")


def test_the_simplex_limit_is_l_to_the_half_d_and_not_above(monkeypatch):
    cube = np.array([[i, j, k] for i in (0.0, 1.0) for j in (0.0, 1.0) for k in (0.0, 1.0)])
    cube = np.vstack([cube, [[0.5, 0.4, 0.3]]])  # l = 9, d = 3: up to 9^2 = 81 simplices
    monkeypatch.setattr(gpmsa.limits, "MAX_INDEX_SIMPLICES", 81)
    index_points.check_points(cube, "index")
    monkeypatch.setattr(gpmsa.limits, "MAX_INDEX_SIMPLICES", 80)
    with pytest.raises(gpmsa.ResourceLimitError, match=r"9 points in 3 columns .* up to 9\^2"):
        index_points.check_points(cube, "index")
    monkeypatch.setattr(gpmsa.limits, "MAX_INDEX_SIMPLICES", 1)  # two columns: any number
    index_points.check_points(PTS2, "index")


def test_columns_too_far_apart_are_named_in_the_message():
    line = np.column_stack([np.arange(5.0), 1e-16 * np.arange(5.0) ** 2])  # spans 4, 1.6e-15
    with pytest.raises(gpmsa.GPMSAError, match=r"too far apart for float64: 4, 1.6e-15\)"):
        index_points.check_points(line, "index")
    with pytest.raises(gpmsa.GPMSAError, match=r"plane\): the basis") as err:
        index_points.check_points(np.column_stack([np.arange(5.0), np.zeros(5)]), "index")
    assert "apart" not in str(err.value)  # a zero span: on a line, not far apart


def test_a_far_offset_index_interpolates_in_its_frame():
    pts = PTS2 + np.array([1.7e9, -3e8])  # Qhull fails or drops points in these units
    found = index_points._triangulation(pts, "index")
    assert found.frame is not None
    scale, origin, width = found.frame
    assert scale == 2.0**30  # a power of two: |points| / scale in [1, 2)
    np.testing.assert_array_equal(found.local(pts).min(axis=0), [0.0, 0.0])
    assert found.local(pts).max() == 1.0  # the widest column spans [0, 1]
    q = pts[:4].mean(axis=0, keepdims=True) + np.array([[0.3, -0.2]])
    W = index_points.weights(pts, q, "q")
    f = PTS2 @ np.array([1.0, 3.0])
    np.testing.assert_allclose(W @ f, (q - [1.7e9, -3e8]) @ np.array([1.0, 3.0]), atol=1e-5)


def test_points_left_out_are_named_by_the_first_one_and_its_neighbour():
    grid = np.column_stack(
        [np.repeat(np.linspace(0, 1, 4), 5), np.tile(np.linspace(0, 2.123456, 5), 4)]
    )
    near = [[0.1 + 0.2, 0.5], [0.3, 0.5], [0.6, 1.2], [0.6 + 2**-53, 1.2]]  # two pairs
    points = np.vstack([grid, near])
    with pytest.raises(gpmsa.GPMSAError) as err:
        index_points.weights(points, np.array([[0.5, 0.55]]), "o")
    assert (
        "2 of its 24 points fall out of their triangulation in float64, the first "
        "(0.29999999999999999, 0.5) (row 21) within rounding of (0.30000000000000004, 0.5) "
        "(row 20), so values" in str(err.value)
    )
    assert "(the index columns span 1, 2.12: a column" in str(err.value)
    index_points.check_points(points, "index")  # taken where no triangles are needed


@pytest.mark.parametrize("ratio", [1e6, 2.0])
def test_points_on_a_slanted_line_are_not_called_far_apart(ratio):
    """Spans 1e6 apart (not beyond) or comparable, all on one line: the message says line."""
    line = np.column_stack([ratio * np.arange(5.0), np.arange(5.0)])
    with pytest.raises(gpmsa.GPMSAError, match=r"on a line or plane\): the basis") as err:
        index_points.check_points(line, "index")
    assert "apart" not in str(err.value)


def test_a_minus_zero_corner_reached_by_rounding_is_exactly_that_point():
    """A column whose end is -0.0 (e.g. -np.linspace(0, 1, 5)): a point beyond it by rounding
    is that simulation point, one-hot (it was located in a triangle instead, its value
    leaking ~1e-16 to the neighbours), and a refused point is shown as given, not snapped
    to -0."""
    rng = np.random.default_rng(161)
    pts = -rng.uniform(0, 3, (10, 2))
    pts[0] = [-0.0, rng.uniform(-2.5, -0.5)]  # the first column's max: -0.0
    for q in ([1e-13, pts[0, 1]], [0.0, pts[0, 1]], [-0.0, pts[0, 1]]):
        W = index_points.weights(pts, np.array([q]), "q")
        assert W.indices.tolist() == [0] and W.data.tolist() == [1.0], q
    flipped = PTS2 * [-1.0, 1.0]
    with pytest.raises(gpmsa.GPMSAError, match=r"point \(1e-12, -2\) \(row 0\) outside"):
        index_points.weights(flipped, np.array([[1e-12, -2.0]]), "q")
