"""The index figures over an output index of two columns (SEPIA's (time, angle) y_ind) draw
maps: each curve of the one-column figure becomes a panel over the points (Gouraud-shaded
triangles with a dot at each point, or coloured markers at an experiment's own points), panels
compared on one colour scale; three columns are refused naming the two-column case; the
one-column figures keep their lines; ``gpmsa info --json`` describes the output index."""

from __future__ import annotations

import dataclasses
import json
import warnings

import matplotlib
import numpy as np
import pytest

import gpmsa
from gpmsa.cli.main import main

matplotlib.use("Agg")

TIME, ANGLE = np.linspace(0.0, 1.0, 4), np.linspace(0.0, 2.0, 5)
POINTS = np.column_stack([np.repeat(TIME, 5), np.tile(ANGLE, 4)])  # (20, 2)
ROWS = (np.array([0, 3, 7, 12, 19]), np.array([2, 5, 11]))
X_OBS = np.array([0.3, 0.7])
PARAMS = {"betaU": [[1, 1, 1], [1, 1, 1]], "lamUz": [1, 1, 1], "lamWs": [1e3] * 3,
          "lamWOs": [1e3]}  # fmt: skip
LABELS = ("output index[:, 0]", "output index[:, 1]")
pytestmark = pytest.mark.filterwarnings("ignore::gpmsa.ConvergenceWarning")


def _f(x: float, t: float, pts: np.ndarray) -> np.ndarray:
    return np.sin(np.pi * pts[:, 0] * (0.5 + x)) * (1 + t) + 0.3 * pts[:, 1] * t


def _sim(index=POINTS) -> gpmsa.SimData:
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=12), rng.uniform(size=12)
    y = np.array([_f(a, b, POINTS) for a, b in zip(x, t, strict=True)])
    return gpmsa.SimData(x[:, None], t[:, None], y, index=index, t_names=["theta"])


def _obs() -> gpmsa.ObsData:
    ys = [_f(x, 0.4, POINTS[r]) for x, r in zip(X_OBS, ROWS, strict=True)]
    return gpmsa.ObsData(X_OBS[:, None], ys, index=[POINTS[r] for r in ROWS])


def _maps(fig) -> list:
    """The axes holding a map (a triangulated surface or markers at points)."""
    return [ax for ax in fig.axes if ax.get_xlabel() == LABELS[0]]


def _mesh(ax):
    (mesh,) = [c for c in ax.collections if type(c).__name__ == "TriMesh"]
    return mesh


def _dots(ax):
    (dots,) = [c for c in ax.collections if type(c).__name__ == "PathCollection"]
    return dots


@pytest.fixture(scope="module")
def emu() -> gpmsa.Emulator:
    return gpmsa.Emulator.from_params(_sim(), PARAMS)


@pytest.fixture(scope="module")
def post(emu) -> gpmsa.Posterior:
    return gpmsa.calibrate(emu, _obs(), n_samples=40, n_burn=5, seed=0)


@pytest.fixture(scope="module")
def pred(emu, post) -> gpmsa.FullPrediction:
    return gpmsa.full_prediction(emu, _obs(), X_OBS[:, None], posterior=post, seed=1, grid=POINTS)


def test_data_maps_four_runs_by_theta_and_each_experiment_on_one_scale():
    sim, obs = _sim(), _obs()
    fig = gpmsa.plots.data(sim, obs)
    maps = _maps(fig)
    assert len(maps) == 6 and len(fig.axes) == 7  # 4 runs, 2 experiments, one colour bar
    runs = [int(ax.get_title().split(":")[0].removeprefix("run ")) for ax in maps[:4]]
    order = np.argsort(sim.t[:, 0])
    assert runs[0] == order[0] and runs[-1] == order[-1]  # the lowest and highest theta
    for ax, i in zip(maps[:4], runs, strict=True):
        assert np.array_equal(_mesh(ax).get_array(), sim.y[i])
        assert np.array_equal(ax.lines[0].get_xdata(), POINTS[:, 0])  # a dot at each point
    for ax, r, e in zip(maps[4:], ROWS, obs.experiments, strict=True):
        assert np.array_equal(_dots(ax).get_offsets(), POINTS[r])
        assert np.array_equal(_dots(ax).get_array(), e)
    norms = {(m.norm.vmin, m.norm.vmax) for m in [_mesh(a) for a in maps[:4]]
             + [_dots(a) for a in maps[4:]]}  # fmt: skip
    low = min(sim.y[runs].min(), *(e.min() for e in obs.experiments))
    assert norms == {(low, max(sim.y[runs].max(), *(e.max() for e in obs.experiments)))}
    assert maps[0].get_ylabel() == LABELS[1]


def test_pc_basis_maps_each_vector_with_its_own_symmetric_scale(emu):
    fig = gpmsa.plots.pc_basis(emu)
    maps = _maps(fig)
    assert len(maps) == emu.p_u == 3 and len(fig.axes) == 3 * 3 + 3  # + a colour bar each
    for j, ax in enumerate(maps):
        mesh = _mesh(ax)
        vector = emu.standardizer.y_sd * emu.K[:, j]
        assert np.allclose(mesh.get_array(), vector)
        assert mesh.norm.vmin == -mesh.norm.vmax == -np.max(np.abs(vector))
        assert ax.get_title().startswith(f"PC {j + 1} (")


def test_emulator_fit_maps_mean_width_and_residual_per_run(emu):
    cv = gpmsa.cross_validate(emu, draws=False)
    fig = gpmsa.plots.emulator_fit(emu, cv, max_runs=2)
    maps = _maps(fig)
    assert len(maps) == 6 and len(fig.axes) == 1 + 6 + 3  # scatter, 2 runs x 3, 3 colour bars
    assert fig.axes[0].get_title().startswith("cross-validation: ")
    mean_0, width_0, resid_0 = maps[0], maps[2], maps[4]  # column by column
    assert mean_0.get_title() == "run 0: predicted mean"
    assert np.allclose(_mesh(mean_0).get_array(), cv.mean[0])
    assert width_0.get_title() == "run 0: width of the 90 % interval"
    assert np.allclose(_dots(resid_0).get_array(), cv.y[0] - cv.mean[0])
    for column in (maps[0:2], maps[2:4]):  # each column on one scale
        assert len({(_mesh(a).norm.vmin, _mesh(a).norm.vmax) for a in column}) == 1
    held = _sim(index=np.arange(20.0))  # the same runs on a one-column index: refused
    with pytest.raises(gpmsa.GPMSAError, match="another output grid"):
        gpmsa.plots.emulator_fit(emu, held, draws=False)


def test_obs_projection_maps_what_the_basis_misses(emu):
    obs = _obs()
    fig = gpmsa.plots.obs_projection(emu, obs)
    maps = _maps(fig)
    assert len(fig.axes) == 3 + 3 + 2 and len(maps) == 3  # histograms, maps, 2 colour bars
    assert maps[0].get_title().startswith("runs beyond 3 components: rms ")
    assert _mesh(maps[0]).get_array().shape == (20,) and _mesh(maps[0]).norm.vmin == 0.0
    for ax, r in zip(maps[1:], ROWS, strict=True):
        assert np.array_equal(_dots(ax).get_offsets(), POINTS[r])
    assert fig.axes[0].get_title().startswith("PC 1: ")


def test_prediction_bands_map_mean_width_delta_and_observed(emu, post, pred):
    observed = pred.mean("y") + 0.1
    fig = gpmsa.plots.prediction_bands(pred, observed)
    maps = _maps(fig)
    assert len(maps) == 2 * 4 and len(fig.axes) == 8 + 4  # 4 rows x 2 x, a colour bar a row
    assert maps[0].get_title() == "x0 = 0.3\nmean of y"
    assert np.allclose(_mesh(maps[0]).get_array(), pred.mean("y")[0])
    lo, hi = pred.interval("y", 0.9)
    assert np.allclose(_mesh(maps[2]).get_array(), (hi - lo)[0])
    assert np.allclose(_dots(maps[7]).get_array(), 0.1)
    assert np.array_equal(_dots(maps[7]).get_offsets(), POINTS)
    assert _mesh(maps[0]).norm.vmin == _mesh(maps[1]).norm.vmin  # a row: one scale
    few = gpmsa.full_prediction(emu, _obs(), [[0.5]], posterior=post, seed=1, grid=POINTS[:2])
    fig = gpmsa.plots.prediction_bands(few)  # two points span no triangle: markers
    assert np.array_equal(_dots(_maps(fig)[0]).get_offsets(), POINTS[:2])


def test_sensitivity_bars_map_main_and_total_effects(emu):
    sens = gpmsa.sensitivity(emu, draws=False)
    fig = gpmsa.plots.sensitivity_bars(sens)
    maps = _maps(fig)
    assert len(maps) == 4 and len(fig.axes) == 1 + 4 + 1
    assert [ax.get_title() for ax in maps] == [
        "main effect of x0",
        "main effect of theta",
        "total effect of x0",
        "total effect of theta",
    ]
    mesh = _mesh(maps[1])
    main = sens.main[0, :, 1]
    assert np.allclose(mesh.get_array()[np.isfinite(main)], main[np.isfinite(main)])
    assert (mesh.norm.vmin, mesh.norm.vmax) == (0.0, 1.0)
    assert len(fig.axes[0].patches) == 4  # the bars are the one-column figure's


def test_three_index_columns_are_refused_naming_the_two_column_case(pred):
    rng = np.random.default_rng(1)
    cube = rng.uniform(size=(20, 3))
    sim = _sim(index=cube)
    emu3 = gpmsa.Emulator.from_params(sim, PARAMS)
    message = r"maps over a two-column one; this one has 20 points in 3 columns"
    calls = [
        lambda: gpmsa.plots.data(sim),
        lambda: gpmsa.plots.pc_basis(emu3),
        lambda: gpmsa.plots.emulator_fit(emu3, gpmsa.cross_validate(emu3, draws=False)),
        lambda: gpmsa.plots.sensitivity_bars(gpmsa.sensitivity(emu3, draws=False)),
        lambda: gpmsa.plots.obs_projection(emu3, gpmsa.ObsData([[0.5]], [cube[:4, 0]],
                                                               index=[cube[:4]])),
        lambda: gpmsa.plots.prediction_bands(dataclasses.replace(pred, grid=cube)),
    ]  # fmt: skip
    for call in calls:
        with pytest.raises(gpmsa.GPMSAError, match=message):
            call()


def test_one_column_figures_keep_their_lines():
    s = np.linspace(0.0, 1.0, 8)
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(12, 1)), rng.uniform(size=(12, 1))
    sim = gpmsa.SimData(x=x, t=t, y=np.outer(x, s) + np.outer(t, s**2), index=s)
    obs = gpmsa.ObsData(x=[[0.5]], y=[0.5 * s + s**2])
    emu = gpmsa.Emulator.from_params(sim, {"betaU": [[1, 1], [1, 1]], "lamUz": [1, 1],
                                           "lamWs": [1e3, 1e3], "lamWOs": [1e3]})  # fmt: skip
    fig = gpmsa.plots.data(sim, obs)
    lines = fig.axes[0].lines
    assert len(fig.axes) == 2 and len(lines) == 12 + 1
    assert np.array_equal(lines[3].get_ydata(), sim.y[3])
    assert np.array_equal(lines[3].get_xdata(), s)
    fig = gpmsa.plots.pc_basis(emu)
    assert len(fig.axes) == 6 and not fig.axes[0].collections
    assert np.allclose(fig.axes[0].lines[0].get_ydata(), emu.standardizer.y_sd * emu.K[:, 0])
    fig = gpmsa.plots.emulator_fit(emu, gpmsa.cross_validate(emu, draws=False), max_runs=3)
    assert len(fig.axes) == 2 and len(fig.axes[1].lines) == 2 * 3
    assert fig.axes[1].get_xlabel() == "output index"
    fig = gpmsa.plots.obs_projection(emu, obs)
    assert len(fig.axes) == 3 and len(fig.axes[2].lines) == 12 + 1 + 1  # runs, obs, zero
    fig = gpmsa.plots.sensitivity_bars(gpmsa.sensitivity(emu, draws=False))
    assert len(fig.axes) == 2 and len(fig.axes[1].lines) == 2 * 2  # main and total per input


@pytest.mark.parametrize(
    ("index", "expected"),
    [
        (POINTS, {"points": 20, "columns": 2, "ranges": [[0.0, 1.0], [0.0, 2.0]],
                  "names": None, "units": None}),
        (np.linspace(2.0, 5.0, 20), {"points": 20, "columns": 1, "ranges": [[2.0, 5.0]],
                                     "names": None, "units": None}),
    ],
)  # fmt: skip
def test_info_json_describes_the_output_index(tmp_path, capsys, index, expected):
    gpmsa.Emulator.from_params(_sim(index), PARAMS).save(tmp_path / "e.gpmsa")
    assert main(["info", str(tmp_path / "e.gpmsa"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["output_index"] == expected
    assert out["info_format"] == "gpmsa-info/1" and out["model"]["l_sim"] == 20
    assert {"output_scale", "basis", "separable", "posterior"} <= set(out)


def test_info_json_output_index_of_a_scalar_output_is_null(tmp_path, capsys):
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(10, 1)), rng.uniform(size=(10, 1))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = gpmsa.Emulator.from_params(gpmsa.SimData(x=x, t=t, y=x + t), {
            "betaU": [[1], [1]], "lamUz": [1], "lamWs": [1e3], "lamWOs": [1e3]})  # fmt: skip
    emu.save(tmp_path / "s.gpmsa")
    assert main(["info", str(tmp_path / "s.gpmsa"), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["output_index"] is None
