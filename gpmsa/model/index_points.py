"""An output index of several columns (SEPIA's ``y_ind_sim`` / ``y_ind_obs`` of shape (l, d),
d >= 2, e.g. (time, angle) pairs): its checks, and the piecewise-linear interpolation on the
Delaunay triangulation of the simulation's index points that maps the basis and the mean onto
the observations' points (as ``scipy.interpolate.LinearNDInterpolator``; exact on a
simulation point). A one-column index (l,) is interpolated along it by ``np.interp``
elsewhere."""

from __future__ import annotations

import numpy as np
from scipy.spatial import Delaunay, QhullError

from gpmsa.errors import GPMSAError, numbers_text


def is_points(grid: np.ndarray | None) -> bool:
    """Whether ``grid`` is an index of several columns (l, d) rather than one grid (l,)."""
    return grid is not None and np.ndim(grid) == 2


def n_points(grid: np.ndarray) -> int:
    """The number of output points of an index (l,) or (l, d)."""
    return int(np.shape(grid)[0])


def _point_text(row: np.ndarray) -> str:
    return "(" + ", ".join(numbers_text(*row)) + ")"


def check_points(points: np.ndarray, name: str) -> None:
    """GPMSAError unless the simulation index ``points`` (l, d), finite, holds no point twice and
    spans d dimensions (its points on no line or plane: the triangulation needs it)."""
    _, first, inverse = np.unique(points, axis=0, return_index=True, return_inverse=True)
    twice = np.flatnonzero(first[inverse.reshape(-1)] != np.arange(points.shape[0]))
    if twice.size:
        k = int(twice[0])
        j = int(first[inverse.reshape(-1)[k]])
        raise GPMSAError(
            f"{name} holds the point {_point_text(points[k])} twice (rows {j} and {k}): every "
            "simulation output point must be distinct"
        )
    _triangulation(points, name)


def _triangulation(points: np.ndarray, name: str) -> Delaunay:
    d = points.shape[1]
    try:
        if points.shape[0] <= d:
            raise QhullError("too few points")
        return Delaunay(points)
    except QhullError:
        raise GPMSAError(
            f"{name} of {points.shape[0]} points in {d} columns does not span {d} dimensions "
            f"(fewer than {d + 1} points, or all on a line or plane): the basis is interpolated "
            "on their triangulation"
        ) from None


def check_columns(points: np.ndarray, new: np.ndarray, what: str) -> None:
    """GPMSAError unless ``new`` is an index of as many columns as the simulation's ``points``
    (one column: 1-D)."""
    d = points.shape[1] if points.ndim == 2 else 1
    e = new.shape[1] if new.ndim == 2 else 1
    if d != e or new.ndim > 2:
        raise GPMSAError(
            f"{what} has shape {new.shape} but the simulation index has {d} column(s) "
            f"(shape {points.shape}): give the observations' points in the same columns"
        )


def weights(points: np.ndarray, new: np.ndarray, what: str) -> np.ndarray:
    """W (l_new, l_sim): values on the simulation ``points`` (l_sim, d) times W are their
    piecewise-linear interpolant (barycentric on the Delaunay triangulation) at ``new``
    (l_new, d); a row of W is one-hot where its point is a simulation point (exact there).
    GPMSAError naming ``what`` and the point where one lies outside the points' convex hull."""
    check_columns(points, new, what)
    W = np.zeros((new.shape[0], points.shape[0]))
    at = {row.tobytes(): i for i, row in enumerate(points + 0.0)}  # + 0.0: -0.0 is 0.0
    on = np.array([at.get(row.tobytes(), -1) for row in new + 0.0], dtype=np.intp)
    hit = on >= 0
    W[np.flatnonzero(hit), on[hit]] = 1.0
    rest = np.flatnonzero(~hit)
    if rest.size:
        tri = _triangulation(points, "the simulation index")
        s = tri.find_simplex(new[rest])
        if np.any(s < 0):
            k = int(rest[np.flatnonzero(s < 0)[0]])
            raise GPMSAError(
                f"{what} has the point {_point_text(new[k])} (row {k}) outside the convex hull "
                "of the simulation index's points; observations must lie within it"
            )
        d = points.shape[1]
        T = tri.transform[s]
        b = np.einsum("nij,nj->ni", T[:, :d], new[rest] - T[:, d])
        W[rest[:, None], tri.simplices[s]] = np.column_stack([b, 1.0 - b.sum(axis=1)])
    return W
