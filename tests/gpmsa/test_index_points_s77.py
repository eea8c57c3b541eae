"""An output index of several columns (SEPIA's y_ind_sim / y_ind_obs of (time, angle) pairs,
shape (l, d)): observations on simulation points fit and calibrate as the numbered-points
workaround to the bit, between points the basis and mean are piecewise linear on the points'
triangulation, outside their hull refused; the emulator file keeps the points; bad shapes are
refused naming the problem (the figures' maps: test_plots_maps_s77.py)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.cli.main import main
from gpmsa.model.basis import interpolate_basis
from gpmsa.model.transforms import Standardizer

TIME, ANGLE = np.linspace(0.0, 1.0, 4), np.linspace(0.0, 2.0, 5)
POINTS = np.column_stack([np.repeat(TIME, 5), np.tile(ANGLE, 4)])  # (20, 2), SEPIA's y_ind_sim
ROWS = (np.array([0, 3, 7, 12, 19]), np.array([2, 5, 11]))  # each experiment's points
X_OBS = np.array([0.3, 0.7])
pytestmark = pytest.mark.filterwarnings("ignore::gpmsa.ConvergenceWarning")


def _f(x: float, t: float, pts: np.ndarray) -> np.ndarray:
    return np.sin(np.pi * pts[:, 0] * (0.5 + x)) * (1 + t) + 0.3 * pts[:, 1] * t


def _sim(index) -> gpmsa.SimData:
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=12), rng.uniform(size=12)
    y = np.array([_f(a, b, POINTS) for a, b in zip(x, t, strict=True)])
    return gpmsa.SimData(x[:, None], t[:, None], y, index=index)


def _obs(index) -> gpmsa.ObsData:
    ys = [_f(x, 0.4, POINTS[r]) + 0.01 * np.cos(r) for x, r in zip(X_OBS, ROWS, strict=True)]
    return gpmsa.ObsData(X_OBS[:, None], ys, index=index)


def _kernels(rows: np.ndarray) -> np.ndarray:
    """A user's discrepancy basis at these points: two Gaussian kernels in (time, angle)."""
    p = POINTS[rows]
    centres = np.array([[0.2, 0.5], [0.8, 1.5]])
    return np.exp(-0.5 * np.sum((p[:, None, :] - centres[None]) ** 2, axis=2) / 0.25)


def test_points_on_simulation_points_fit_as_numbered_points_to_the_bit():
    disc = [_kernels(r) for r in ROWS]
    runs = {}
    for sim_index, obs_index in (
        (POINTS, [POINTS[r] for r in ROWS]),
        (np.arange(20.0), [r.astype(float) for r in ROWS]),  # the documented workaround
    ):
        sim, obs = _sim(sim_index), _obs(obs_index)
        emu = gpmsa.fit(sim, obs, n_iter=25, tune=False, seed=3, n_pc=2, discrepancy=disc)
        plain = gpmsa.fit(sim, n_iter=25, tune=False, seed=4, n_pc=2)
        post = gpmsa.calibrate(plain, obs, n_samples=60, n_burn=10, seed=2)
        full = gpmsa.full_prediction(emu, obs, [[0.4]], discrepancy=disc, experiment=1, seed=1)
        runs[sim_index.ndim] = (emu, post, full)
    (emu2, post2, full2), (emu1, post1, full1) = runs[2], runs[1]
    for k in emu1.draws:
        assert np.array_equal(emu2.draws[k], emu1.draws[k]), k
    for k in emu1.calibration:
        assert np.array_equal(emu2.calibration[k], emu1.calibration[k]), k
    assert np.array_equal(post2.samples["t0"], post1.samples["t0"])
    assert np.array_equal(full2.y, full1.y)


def test_between_points_the_basis_and_mean_are_linear_on_the_triangle():
    pts = np.array([[0.0, 0.0], [2.0, 0.0], [0.0, 2.0], [3.0, 3.0]])  # two triangles
    values = np.array([1.0, 5.0, 9.0, 100.0])
    at = np.array([[0.5, 0.5], [2.0, 0.0]])  # inside the first triangle; on a point
    # (0.5, 0.5) = 0.5 (0, 0) + 0.25 (2, 0) + 0.25 (0, 2): 0.5 * 1 + 0.25 * 5 + 0.25 * 9 = 4
    assert interpolate_basis(values[:, None], pts, at)[:, 0].tolist() == [4.0, 5.0]
    y = np.vstack([values + s for s in (-1.0, 0.0, 0.5, 0.5, 1.0)])  # mean: values + 0.2
    sim = gpmsa.SimData(np.linspace(0, 1, 5)[:, None], [[0.1], [0.9], [0.4], [0.6], [0.3]], y,
                        index=pts)  # fmt: skip
    assert np.allclose(Standardizer.from_sim(sim).mean_on(at), [4.2, 5.2], rtol=0, atol=1e-12)


def test_a_point_outside_the_hull_is_refused_naming_experiment_and_point():
    index = [POINTS[ROWS[0]], np.array([[0.5, 1.0], [1.2, 0.0], [0.1, 0.1]])]
    with pytest.raises(gpmsa.GPMSAError, match=r"experiment 1 has the point \(1.2, 0\) \(row 1"):
        gpmsa.fit(_sim(POINTS), _obs(index), n_iter=5, tune=False, n_pc=2)


def test_file_round_trip_and_info(tmp_path, capsys):
    sim = _sim(POINTS)
    between = np.array([[0.5, 1.0], [0.2, 0.3], [0.9, 1.9]])  # one (l, 2) index for all
    obs = gpmsa.ObsData(X_OBS[:, None], [_f(x, 0.4, between) for x in X_OBS], index=between)
    assert [g.shape for g in obs.grids] == [(3, 2), (3, 2)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = gpmsa.fit(sim, obs, n_iter=30, tune=False, seed=1, n_pc=2, discrepancy="constant")
    back = gpmsa.load(emu.save(tmp_path / "points.gpmsa"))
    assert np.array_equal(back.standardizer.grid, POINTS) and np.array_equal(back.index, POINTS)
    assert back.model_sha256 == emu.model_sha256
    fp = [gpmsa.full_prediction(e, obs, [[0.4]], discrepancy="constant", seed=1, grid=POINTS[:3])
          for e in (emu, back)]  # fmt: skip
    assert fp[0].y.shape[-1] == 3 and np.array_equal(fp[0].y, fp[1].y)
    assert main(["info", str(tmp_path / "points.gpmsa")]) == 0
    out = capsys.readouterr().out
    assert "output index:    20 points in 2 columns, [0, 1] x [0, 2]" in out


@pytest.mark.parametrize(
    ("sim_index", "obs_index", "message"),
    [
        (POINTS, [POINTS[ROWS[0]][:, [0, 1, 1]], POINTS[ROWS[1]][:, [0, 1, 1]]],
         r"index of experiment 0 has shape \(5, 3\).*2 column"),
        (POINTS, [r.astype(float) for r in ROWS], r"shape \(5,\).*2 column"),
        (np.arange(20.0), [POINTS[r] for r in ROWS], r"shape \(5, 2\).*1 column"),
    ],
)  # fmt: skip
def test_index_columns_differing_between_sim_and_obs_are_refused(sim_index, obs_index, message):
    with pytest.raises(gpmsa.GPMSAError, match=message):
        gpmsa.fit(_sim(sim_index), _obs(obs_index), n_iter=5, tune=False, n_pc=2)


def test_bad_index_points_are_refused():
    bad = POINTS.copy()
    bad[4, 1] = np.nan
    with pytest.raises(gpmsa.GPMSAError, match=r"index must be finite"):
        _sim(bad)
    bad = POINTS.copy()
    bad[9] = bad[2]
    with pytest.raises(gpmsa.GPMSAError, match=r"point \(0, 1\) twice \(rows 2 and 9\)"):
        _sim(bad)
    with pytest.raises(gpmsa.GPMSAError, match="does not span 2 dimensions"):
        _sim(np.column_stack([np.arange(20.0), 2 * np.arange(20.0)]))  # on a line
    with pytest.raises(gpmsa.GPMSAError, match="pass its transpose"):
        _sim(POINTS.T)
    with pytest.raises(gpmsa.GPMSAError, match=r"index\[1\] must be finite"):
        _obs([POINTS[ROWS[0]], np.where(ROWS[1][:, None] == 5, np.nan, POINTS[ROWS[1]])])
    with pytest.raises(gpmsa.GPMSAError, match=r"index\[1\] has shape \(3,\).*\(l_j, 2\)"):
        _obs([POINTS[ROWS[0]], ROWS[1].astype(float)])


def test_linear_discrepancy_is_refused_naming_the_alternative():
    sim, obs = _sim(POINTS), _obs([POINTS[r] for r in ROWS])
    with pytest.raises(gpmsa.GPMSAError, match=r"2 columns: pass the basis per experiment"):
        gpmsa.fit(sim, obs, n_iter=5, tune=False, n_pc=2, discrepancy="linear")


def test_grid_discrepancy_on_other_points():
    sim, obs = _sim(POINTS), _obs([POINTS[r] for r in ROWS])
    disc = [_kernels(r) for r in ROWS]
    emu = gpmsa.fit(sim, obs, n_iter=30, tune=False, seed=0, n_pc=2, discrepancy=disc)
    on = gpmsa.full_prediction(emu, obs, [[0.4]], discrepancy=disc, seed=1, grid=POINTS,
                               grid_discrepancy=_kernels(np.arange(20)))  # fmt: skip
    own = gpmsa.full_prediction(emu, obs, [[0.4]], discrepancy=disc, seed=1, experiment=1)
    assert on.delta.shape[-1] == 20
    assert np.allclose(on.mean("delta")[:, ROWS[1]], own.mean("delta"), rtol=0, atol=1e-12)
