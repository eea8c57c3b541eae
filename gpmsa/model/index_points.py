"""An output index of several columns (SEPIA's ``y_ind_sim`` / ``y_ind_obs`` of shape (l, d),
d >= 2, e.g. (time, angle) pairs): its checks, and the piecewise-linear interpolation on the
Delaunay triangulation of the simulation's index points that maps the basis and the mean onto
the observations' points (as ``scipy.interpolate.LinearNDInterpolator``; exact on a
simulation point). A one-column index (l,) is interpolated along it by ``np.interp``
elsewhere; `within` is its range check, with the same rounding tolerance."""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np
from scipy import sparse
from scipy.spatial import Delaunay, QhullError

from gpmsa import limits
from gpmsa.errors import GPMSAError, ResourceLimitError, numbers_text

HULL_TOL = 1e-9
"""A point outside the simulation points' convex hull (or a one-column grid's ends) by at most
this fraction of each index column's span (of its simplex, for a slanted edge) is rounding (0.1
+ 0.2 for 0.3): taken onto the edge, exactly the edge point's values there."""

TIE_TOL = 1e-10
"""A located point this close (barycentric) to a face of its simplex is on a face the neighbour
shares: it is looked up by brute force, the lowest-numbered simplex holding it, so that its
weights do not depend on where scipy's walk started (the batch's previous point)."""


def is_points(grid: np.ndarray | None) -> bool:
    """Whether ``grid`` is an index of several columns (l, d) rather than one grid (l,)."""
    return grid is not None and np.ndim(grid) == 2


def n_points(grid: np.ndarray) -> int:
    """The number of output points of an index (l,) or (l, d)."""
    return int(np.shape(grid)[0])


def _point_text(row: np.ndarray, names: tuple[str, ...] | None = None) -> str:
    """``row`` as "(0.3, 1.2)", or with the index columns' ``names`` "(time 0.3, angle 1.2)"."""
    values = numbers_text(*row)
    if names is not None and len(names) == len(values):
        values = [f"{n} {v}" for n, v in zip(names, values, strict=True)]
    return "(" + ", ".join(values) + ")"


def named(what: str, names: tuple[str, ...] | None) -> str:
    """``what`` (a one-column index, e.g. "grid") followed by its column's name where given:
    "grid (time)"."""
    return what if names is None or len(names) != 1 else f"{what} ({names[0]})"


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
    _triangulation(points, name, complete=False)


def within(values: np.ndarray, lo: float, hi: float) -> bool:
    """Whether the one-column index ``values`` lies in [lo, hi] up to rounding (`HULL_TOL` of
    hi - lo; ``np.interp`` takes a value beyond an end as the end)."""
    slack = HULL_TOL * hi - HULL_TOL * lo  # (hi - lo may overflow)
    return bool(values.min() >= lo - slack and values.max() <= hi + slack)


def _triangulation(points: np.ndarray, name: str, complete: bool = True) -> Triangulation:
    """The triangulation of the simulation index ``points`` (l, d) (`_delaunay`); GPMSAError
    where they span no simplex and, with ``complete``, where Qhull leaves some of them out
    (within rounding of others: interpolation between points would not see their values;
    without it, as `check_points` asks, such an index is taken: values on its points need no
    triangles)."""
    l, d = points.shape
    if d > 2 and l ** math.ceil(d / 2) > limits.MAX_INDEX_SIMPLICES:
        raise ResourceLimitError(
            f"{name} of {l} points in {d} columns may triangulate into up to {l}^"
            f"{math.ceil(d / 2)} simplices, over gpmsa.limits.MAX_INDEX_SIMPLICES = "
            f"{limits.MAX_INDEX_SIMPLICES:,} (the basis is interpolated on the points' Delaunay "
            "triangulation, whose size can grow as l^(d/2); a regular grid's stays ~6 l in 3 "
            "columns): raise that limit for such a grid, or give fewer points or columns "
            "(2 columns: any number of points)"
        )
    try:
        if l <= d:
            raise QhullError("too few points")
        found = _delaunay(points.shape, np.ascontiguousarray(points).tobytes())
    except QhullError:
        spans = _spans(points)
        apart = (f", or columns whose spans are too far apart for float64: "
                 f"{', '.join(numbers_text(*spans, digits=3))}"
                 if np.all(spans > 0) and np.max(spans) > 1e6 * np.min(spans) else "")  # fmt: skip
        raise GPMSAError(
            f"{name} of {points.shape[0]} points in {d} columns does not span {d} dimensions "
            f"(fewer than {d + 1} points, or all on a line or plane{apart}): the basis is "
            "interpolated on their triangulation"
        ) from None
    lost = found.tri.coplanar
    if complete and lost.shape[0]:
        row, near = int(lost[0, 0]), int(lost[0, 2])
        spans = numbers_text(*_spans(points), digits=3)
        both = numbers_text(*points[row], *points[near])  # distinct where they differ
        first, second = (f"({', '.join(both[k * d : k * d + d])})" for k in (0, 1))
        raise GPMSAError(
            f"{name}: {lost.shape[0]} of its {l} points fall out of their triangulation in "
            f"float64, the first {first} (row {row}) within rounding of {second} (row {near}), "
            "so values between points cannot be "
            f"interpolated there (the index columns span {', '.join(spans)}: a column about "
            "1e6 times narrower than another, or points nearly repeated, do that); rescale "
            "the index columns to comparable spans, or merge the nearly repeated points"
        )
    return found


def _spans(points: np.ndarray) -> np.ndarray:
    """Each column's span (d,), inf where it overflows float64 (beyond ~1.8e308)."""
    with np.errstate(over="ignore"):
        return np.max(points, axis=0) - np.min(points, axis=0)


def triangles(points: np.ndarray, name: str) -> np.ndarray:
    """The triangles (k, d + 1) of row indices on which the index ``points`` (l, d) are
    interpolated (the figures draw maps on them; a copy); GPMSAError where they span no
    triangle or leave points out."""
    return _triangulation(points, name).tri.simplices.copy()


class Triangulation(NamedTuple):
    """The Delaunay triangulation ``tri`` of the simulation's index points, made in their own
    units or, where float64 cannot hold it there, in the ``frame`` (scale, origin (d,), width)
    that maps them onto [0, 1] by one width (`local`: divided by a power of two, exactly,
    shifted and divided by the width): points located in it are first mapped by `local`.
    Where the points are in general position the triangles are the same in both; a regular
    grid's cells (four points on a circle) may be split either way."""

    tri: Delaunay
    frame: tuple[float, np.ndarray, float] | None

    def local(self, q: np.ndarray) -> np.ndarray:
        """Points ``q`` (n, d) in the triangulation's coordinates."""
        if self.frame is None:
            return q
        scale, origin, width = self.frame
        return (q / scale - origin) / width


@functools.lru_cache(maxsize=4)
def _delaunay(shape: tuple[int, int], data: bytes) -> Triangulation:
    """The triangulation of the points (``shape``, float64 bytes), kept for the next call: a fit
    or a prediction interpolates the basis, the mean and the sd on the same points. Made in the
    points' own units; where Qhull fails there or leaves points out (``coplanar``: an offset
    far beyond the points' span, e.g. 1e7 + [0, 1], or a span near float64's ends), again in
    `Triangulation`'s frame (a column far narrower than another still leaves points out:
    `_triangulation` refuses it). QhullError where they span no simplex in either."""
    points = np.frombuffer(data).reshape(shape)
    try:
        tri = Delaunay(points)
        if not tri.coplanar.shape[0]:
            return Triangulation(tri, None)
    except QhullError:
        pass
    scale = math.ldexp(1.0, math.frexp(float(np.max(np.abs(points))))[1] - 1)  # |unit| < 2
    unit = points / scale
    origin = unit.min(axis=0)
    width = float(np.max(unit.max(axis=0) - origin))
    if not width > 0.0:  # one point repeated
        raise QhullError("the points coincide")
    origin.flags.writeable = False
    return Triangulation(Delaunay((unit - origin) / width), (scale, origin, width))


def check_columns(points: np.ndarray, new: np.ndarray, what: str) -> None:
    """GPMSAError unless ``new`` is an index of as many columns as the simulation's ``points``
    (one column: 1-D)."""
    d = points.shape[1] if points.ndim == 2 else 1
    e = new.shape[1] if new.ndim == 2 else 1
    if d != e or new.ndim > 2:
        raise GPMSAError(
            f"{what} has shape {new.shape} but the simulation index has {d} column(s) "
            f"(shape {points.shape}): give its points in the same columns"
        )


def weights(
    points: np.ndarray, new: np.ndarray, what: str, names: tuple[str, ...] | None = None
) -> sparse.csr_array:
    """W (l_new, l_sim), sparse: values on the simulation ``points`` (l_sim, d) times W are
    their piecewise-linear interpolant (barycentric on the Delaunay triangulation) at ``new``
    (l_new, d), at most d + 1 entries a row; a row is one-hot where its point is a simulation
    point (exact there). A point outside the points' convex hull by rounding (`HULL_TOL`) is
    taken onto it; one beyond: GPMSAError naming ``what`` and the point (by the index columns'
    ``names`` where given). A row depends on its point alone (not on the other points of
    ``new``)."""
    check_columns(points, new, what)
    given = new
    new = _onto_box(points, new + 0.0)  # + 0.0: -0.0 is 0.0
    at = {row.tobytes(): i for i, row in enumerate(points + 0.0)}
    on = np.array([at.get(row.tobytes(), -1) for row in new], dtype=np.intp)
    hit, rest = np.flatnonzero(on >= 0), np.flatnonzero(on < 0)
    rows, cols, vals = [hit], [on[hit]], [np.ones(hit.size)]
    if rest.size:
        found = _triangulation(points, f"the simulation index (interpolated onto {what})")
        tri, q = found.tri, found.local(new[rest])
        s = _locate(tri, q)
        if np.any(s < 0):
            k = int(rest[np.flatnonzero(s < 0)[0]])
            raise GPMSAError(
                f"{what} has the point {_point_text(given[k], names)} (row {k}) outside the "
                "convex hull of the simulation index's points, on which the basis is "
                "interpolated: give points within it"
            )
        b = _barycentric(tri, s, q)
        rows.append(np.repeat(rest, b.shape[1]))
        cols.append(tri.simplices[s].reshape(-1))
        vals.append(b.reshape(-1))
    shape = (new.shape[0], points.shape[0])
    coo = (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols)))
    return sparse.csr_array(coo, shape=shape)


def _onto_box(points: np.ndarray, new: np.ndarray) -> np.ndarray:
    """``new`` with each coordinate beyond the points' range by rounding (`HULL_TOL` of the
    column's span) set to the range's end (+0.0 for an end -0.0: the simulation point there is
    found as one, `weights`)."""
    lo, hi = points.min(axis=0) + 0.0, points.max(axis=0) + 0.0
    slack = HULL_TOL * hi - HULL_TOL * lo  # (hi - lo may overflow)
    low = (new < lo) & (new >= lo - slack)
    high = (new > hi) & (new <= hi + slack)
    return np.where(low, lo, np.where(high, hi, new))


def _locate(tri: Delaunay, q: np.ndarray) -> np.ndarray:
    """Each point's simplex (-1: outside the hull beyond rounding): scipy's walk, then by brute
    force (the lowest-numbered simplex holding it, whatever the walk's start) for a point on a
    face (`TIE_TOL`) and, within `HULL_TOL` of its simplex, for one outside a slanted edge."""
    s = tri.find_simplex(q)
    found = np.flatnonzero(s >= 0)
    tie = found[_barycentric(tri, s[found], q[found]).min(axis=1) <= TIE_TOL]
    s[tie] = tri.find_simplex(q[tie], bruteforce=True)
    out = np.flatnonzero(s < 0)
    s[out] = tri.find_simplex(q[out], bruteforce=True, tol=HULL_TOL)
    return s


def _barycentric(tri: Delaunay, s: np.ndarray, q: np.ndarray) -> np.ndarray:
    """The barycentric coordinates (n, d + 1) of the points ``q`` in their simplices ``s``."""
    d = q.shape[1]
    T = tri.transform[s]
    b = np.einsum("nij,nj->ni", T[:, :d], q - T[:, d])
    return np.column_stack([b, 1.0 - b.sum(axis=1)])
