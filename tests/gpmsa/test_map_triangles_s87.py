"""The maps over a two-column output index are drawn on the triangles gpmsa interpolates on
(matplotlib's own triangulation split 4 of a regular 4 x 5 grid's 24 triangles the other way,
so the figure showed another interpolation than the fit's), also far from the origin."""

from __future__ import annotations

import matplotlib
import numpy as np
import pytest
from scipy.spatial import Delaunay

import gpmsa
from gpmsa.model.index_points import triangles

matplotlib.use("Agg")

TIME, ANGLE = np.linspace(0.0, 1.0, 4), np.linspace(0.0, 2.0, 5)
POINTS = np.column_stack([np.repeat(TIME, 5), np.tile(ANGLE, 4)])  # (20, 2)


def _as_set(tri: np.ndarray) -> set:
    return {tuple(sorted(int(i) for i in row)) for row in tri}


def _drawn(fig, points: np.ndarray) -> set:
    """The triangles of the first map's mesh, as rows of ``points``."""
    mesh = next(c for ax in fig.axes for c in ax.collections if type(c).__name__ == "TriMesh")
    row = {tuple(p): k for k, p in enumerate(points.tolist())}
    return {tuple(sorted(row[tuple(v)] for v in path.vertices[:3].tolist()))
            for path in mesh.get_paths()}  # fmt: skip


@pytest.mark.parametrize("offset", [0.0, 1.7e9])
def test_the_data_maps_are_drawn_on_the_interpolations_triangles(offset):
    points = POINTS + np.array([offset, 0.0])
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=6), rng.uniform(size=6)
    y = np.sin(3 * POINTS[None, :, 0] * (0.5 + x[:, None])) + t[:, None] * POINTS[None, :, 1]
    sim = gpmsa.SimData(x[:, None], t[:, None], y, index=points)
    fig = gpmsa.plots.data(sim)
    want = _as_set(triangles(points, "index"))
    assert _drawn(fig, points) == want
    if offset == 0.0:  # scipy's Delaunay: the fit's interpolation (index_points.weights)
        assert want == _as_set(Delaunay(POINTS).simplices)


def test_the_triangles_given_out_are_a_copy_of_the_cached_ones():
    """A caller writing into the triangles it got must not change later interpolations."""
    points = POINTS + 0.0
    first = triangles(points, "index")
    first[:] = 0
    assert _as_set(triangles(points, "index")) == _as_set(Delaunay(POINTS).simplices)
