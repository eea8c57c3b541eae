"""Maps over an output index of two columns (SEPIA's (time, angle) y_ind, shape (l, 2)): the
values at the points coloured piecewise-linearly over their Delaunay triangles (gpmsa's own
interpolation between points, ``gpmsa.model.index_points``), markers at the points, and the
colour scales panels share."""

from __future__ import annotations

import numpy as np

from gpmsa.errors import GPMSAError
from gpmsa.model.index_points import triangles

VALUES, SIGNED, SPREAD = "viridis", "RdBu_r", "magma"  # colour maps: values, signed, widths


def value_norm(*arrays: np.ndarray):
    """A Normalize over the finite values of ``arrays`` (one colour scale for the panels that
    show them); a range of width 1 about a constant."""
    from matplotlib.colors import Normalize

    finite = np.concatenate([np.ravel(a)[np.isfinite(np.ravel(a))] for a in arrays])
    low, high = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 0.0)
    return Normalize(low - 0.5, high + 0.5) if low == high else Normalize(low, high)


def signed_norm(*arrays: np.ndarray):
    """A Normalize symmetric about 0 covering the finite values of ``arrays`` (residuals, basis
    vectors, discrepancies: white is zero); [-1, 1] where all are 0."""
    from matplotlib.colors import Normalize

    finite = np.concatenate([np.ravel(a)[np.isfinite(np.ravel(a))] for a in arrays])
    top = float(np.max(np.abs(finite))) if finite.size else 0.0
    return Normalize(-top, top) if top > 0 else Normalize(-1.0, 1.0)


def surface(ax, points: np.ndarray, values: np.ndarray, norm, cmap: str, labels) -> object:
    """``values`` (l,) at ``points`` (l, 2) on ``ax``: colour linear on each of the triangles
    gpmsa interpolates on (`gpmsa.model.index_points.triangles`; ``tripcolor`` with Gouraud
    shading; a triangle with a non-finite corner is left blank) and a small black marker at
    each point; points that span no triangle (fewer than 3, on one line, or within rounding of
    each other) get coloured markers instead (``markers``). ``labels``: the axes' (the index
    columns', ``_figure.index_labels``). Returns the mappable for a colour bar."""
    from matplotlib.tri import Triangulation

    try:  # gpmsa's own triangles: matplotlib's split a regular grid's cells otherwise
        simplices = triangles(np.asarray(points, dtype=np.float64), "the map's points")
    except GPMSAError:  # fewer than 3 points, on one line, or points within rounding
        return markers(ax, points, values, norm, cmap, labels=labels)
    tri = Triangulation(points[:, 0], points[:, 1], triangles=simplices)
    finite = np.isfinite(values)
    tri.set_mask(~np.all(finite[tri.triangles], axis=1))
    mesh = ax.tripcolor(tri, np.where(finite, values, 0.0), shading="gouraud", norm=norm,
                        cmap=cmap)  # fmt: skip
    ax.plot(points[:, 0], points[:, 1], ".", ms=2, color="k")
    _labels(ax, labels)
    return mesh


def markers(ax, points: np.ndarray, values: np.ndarray, norm, cmap: str, *, labels,
            background=None) -> object:  # fmt: skip
    """``values`` (l,) at ``points`` (l, 2) as markers coloured by value (observations at their
    own points), over the grey dots of ``background`` (l_sim, 2), e.g. the simulation points;
    ``labels``: the axes' (as ``surface``'s). Returns the mappable for a colour bar."""
    if background is not None:
        ax.plot(background[:, 0], background[:, 1], ".", ms=2, color="0.7")
    dots = ax.scatter(points[:, 0], points[:, 1], c=values, norm=norm, cmap=cmap, s=36,
                      edgecolors="k", linewidths=0.6)  # fmt: skip
    _labels(ax, labels)
    return dots


def colour_bar(fig, mappable, axes, label: str) -> None:
    """One colour bar, labelled ``label``, for the panels ``axes`` sharing ``mappable``'s scale."""
    fig.colorbar(mappable, ax=axes, shrink=0.9).set_label(label)


def _labels(ax, labels) -> None:
    ax.set_xlabel(labels[0])
    ax.set_ylabel(labels[1])
