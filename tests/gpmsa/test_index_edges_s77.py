"""An output index at its edges and at scale: a point outside the simulation points' hull (or a
1-D grid's ends) by rounding only (0.1 + 0.2 on a point 0.3) is taken on the edge, exactly the
point's values; a point on a shared edge of a co-circular grid interpolates the same bits in
any batch; the weights are sparse; an index whose triangulation could be huge is refused,
in a file too."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest
from scipy import sparse

import gpmsa
from gpmsa.io.container import ENVELOPE, read_raw, write_raw
from gpmsa.model import index_points
from gpmsa.model.basis import interpolate_basis

T, A = np.array([0.0, 0.1, 0.2, 0.3]), np.array([0.0, 0.5, 1.0])
P = np.column_stack([np.repeat(T, 3), np.tile(A, 4)])  # (12, 2), a rectangular grid
K = np.random.default_rng(0).normal(size=(12, 2))


@pytest.mark.parametrize("scale", [1.0, 1e4])  # time in s, or in units of 1e-4 s
def test_a_point_outside_by_rounding_is_the_edge_point(scale):
    pts = P * [scale, 1.0]
    edge = np.array([[0.3 * scale, 0.5], [0.15 * scale, 1.0]])
    nudged = np.array([[(0.1 + 0.2) * scale, 0.5], [0.15 * scale, 1.0 + 1e-15]])
    assert not np.array_equal(nudged, edge)  # one ulp or so beyond the hull
    on_edge = interpolate_basis(K, pts, edge)
    np.testing.assert_array_equal(interpolate_basis(K, pts, nudged), on_edge)
    with pytest.raises(gpmsa.GPMSAError, match=r"outside the convex hull"):
        interpolate_basis(K, pts, np.array([[0.3 * scale * (1 + 1e-6), 0.5]]))


def test_a_one_column_grid_end_reached_by_rounding_is_its_end():
    at = interpolate_basis(K[:4], T, np.array([0.1 + 0.2]))
    np.testing.assert_array_equal(at, K[3:4])
    with pytest.raises(gpmsa.GPMSAError, match="within the simulation grid"):
        interpolate_basis(K[:4], T, np.array([0.3 + 1e-6]))
    rng = np.random.default_rng(3)
    x, t = rng.uniform(size=6), rng.uniform(size=6)
    sim = gpmsa.SimData(x[:, None], t[:, None], np.sin(np.outer(1 + x + t, T)), index=T)
    obs = gpmsa.ObsData([[0.5]], [np.array([0.1, 0.2])], index=[np.array([0.1, 0.1 + 0.2])])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = gpmsa.fit(sim, obs, n_iter=5, tune=False, n_pc=2, seed=0)  # refused before
        pred = gpmsa.full_prediction(emu, obs, [[0.4]], grid=[0.0, 0.1 + 0.2], seed=1)
    assert pred.y.shape[-1] == 2


def test_points_on_shared_edges_interpolate_the_same_bits_in_any_batch():
    t, a = np.linspace(0, 1, 11), np.linspace(0, 2, 9)  # co-circular cells: ties in the walk
    pts = np.column_stack([np.repeat(t, 9), np.tile(a, 11)])
    mid_t, mid_a = (t[:-1] + t[1:]) / 2, (a[:-1] + a[1:]) / 2
    q = np.vstack([np.column_stack([np.repeat(mid_t, 8), np.tile(mid_a, 10)]),  # diagonals
                   np.column_stack([np.repeat(mid_t, 9), np.tile(a, 10)]),  # cell edges
                   np.column_stack([np.repeat(t, 8), np.tile(mid_a, 11)])])  # fmt: skip
    values = np.sin(3 * pts[:, 0]) + pts[:, 1] ** 2
    batch = index_points.weights(pts, q, "q") @ values
    perm = np.random.default_rng(1).permutation(len(q))
    np.testing.assert_array_equal((index_points.weights(pts, q[perm], "q") @ values), batch[perm])
    one = np.concatenate([index_points.weights(pts, q[k : k + 1], "q") @ values
                          for k in range(0, len(q), 7)])  # fmt: skip
    np.testing.assert_array_equal(one, batch[::7])


def test_the_weights_are_sparse_and_the_points_triangulated_once():
    n = 71  # 5,041 simulation points, 5,000 prediction points: dense W 200 MB, 0.7 s a call
    g = np.linspace(0, 1, n)
    pts = np.column_stack([np.repeat(g, n), np.tile(2 * g, n)])
    q = np.random.default_rng(0).uniform([0, 0], [1, 2], size=(5000, 2))
    before = index_points._delaunay.cache_info().misses
    for _ in range(4):  # a prediction asks for the basis, the mean, the sd, and checks the grid
        W = index_points.weights(pts, q, "grid")
    assert index_points._delaunay.cache_info().misses - before == 1
    assert sparse.issparse(W) and W.shape == (5000, 5041) and W.nnz <= 3 * 5000
    values = np.sin(3 * pts[:, 0]) * pts[:, 1]
    np.testing.assert_allclose(W @ values, np.sin(3 * q[:, 0]) * q[:, 1], atol=2e-3)


def test_an_index_whose_triangulation_could_be_huge_is_refused(tmp_path):
    rng = np.random.default_rng(0)
    many = rng.uniform(size=(80, 10))  # Delaunay: 1.2 million simplices, 50 s, 1 GB
    with pytest.raises(gpmsa.GPMSAError, match=r"80 points in 10 columns"):
        gpmsa.SimData(rng.uniform(size=(5, 1)), rng.uniform(size=(5, 1)),
                      rng.uniform(size=(5, 80)), index=many)  # fmt: skip
    grid = np.column_stack([np.repeat(np.arange(8.0), 5), np.tile(np.arange(5.0), 8)])
    x, t = rng.uniform(size=8), rng.uniform(size=8)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = gpmsa.fit(gpmsa.SimData(x[:, None], t[:, None], rng.normal(size=(8, 40)),
                                      index=grid), n_iter=5, tune=False, n_pc=2)  # fmt: skip
    path = emu.save(tmp_path / "e.gpmsa")
    manifest, arrays = read_raw(path)
    manifest = {k: v for k, v in manifest.items() if k not in ENVELOPE}
    hostile = rng.uniform(size=(40, 10))  # 1.7 s and 0.2 GB; 80 such points: 50 s, 1 GB
    write_raw(path, manifest, dict(arrays, grid=hostile, index=hostile))
    with pytest.raises(gpmsa.EmulatorFileError, match=r"arrays/grid of 40 points in 10 columns"):
        gpmsa.load(path)  # (refused before triangulating: the message is the limit's)


def test_info_json_names_the_output_index_points(tmp_path, capsys):
    from gpmsa.cli.main import main

    rng = np.random.default_rng(2)
    x, t = rng.uniform(size=6), rng.uniform(size=6)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = gpmsa.fit(gpmsa.SimData(x[:, None], t[:, None], rng.normal(size=(6, 12)), index=P),
                        n_iter=5, tune=False, n_pc=2)  # fmt: skip
    path = str(emu.save(tmp_path / "e.gpmsa"))
    assert main(["info", "--json", path]) == 0
    record = json.loads(capsys.readouterr().out)
    ranges = [[0.0, 0.3], [0.0, 1.0]]
    assert record["output_index"] == {"points": 12, "columns": 2, "ranges": ranges,
                                      "names": None, "units": None}  # fmt: skip


def test_the_simplex_limit_is_a_resource_limit_a_user_may_raise(monkeypatch):
    """A regular 13^3 grid (2,197 points) triangulates into ~6 l simplices, but the worst-case
    bound l^2 exceeds the default limit: refused as a ResourceLimitError naming the limit,
    taken once ``gpmsa.limits.MAX_INDEX_SIMPLICES`` is raised."""
    axis = np.linspace(0.0, 1.0, 13)
    cube = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), axis=-1).reshape(-1, 3)
    rng = np.random.default_rng(1)
    x, t, y = rng.uniform(size=(5, 1)), rng.uniform(size=(5, 1)), rng.normal(size=(5, 2197))
    with pytest.raises(gpmsa.ResourceLimitError, match="MAX_INDEX_SIMPLICES"):
        gpmsa.SimData(x, t, y, index=cube)
    monkeypatch.setattr(gpmsa.limits, "MAX_INDEX_SIMPLICES", 2197**2)
    assert gpmsa.SimData(x, t, y, index=cube).index.shape == (2197, 3)
