"""``SimData(index_names=, index_units=)``: labels of the output index's columns, checked on
construction, kept in the emulator file only where given (a file without them is written as
before, and the labels are no part of ``model_sha256``), checked on loading, carried by fits
and continuations, and used by the figures' axes and ``gpmsa info``."""

from __future__ import annotations

import json
import pickle

import matplotlib
import numpy as np
import pandas as pd
import pytest

import gpmsa
from gpmsa.cli.main import main
from gpmsa.io.container import ENVELOPE, read_raw, write_raw

matplotlib.use("Agg")
pytestmark = pytest.mark.filterwarnings("ignore::gpmsa.ConvergenceWarning")

GRID = np.linspace(0.0, 1.0, 8)
TIME, ANGLE = np.linspace(0.0, 1.0, 4), np.linspace(0.0, 2.0, 5)
POINTS = np.column_stack([np.repeat(TIME, 5), np.tile(ANGLE, 4)])  # (20, 2)
PARAMS = {"betaU": [[1, 1], [1, 1]], "lamUz": [1, 1], "lamWs": [1e3] * 2, "lamWOs": [1e3]}


def _runs(index):
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(12, 1)), rng.uniform(size=(12, 1))
    cols = np.asarray(index).reshape(len(index), -1)
    y = np.sin(np.pi * x * cols[:, 0]) * (1 + t) + t * cols[:, -1] ** 2
    return x, t, y


def _sim(index=GRID, **kw) -> gpmsa.SimData:
    x, t, y = _runs(index)
    return gpmsa.SimData(x=x, t=t, y=y, index=index, **kw)


def _emu(index=GRID, **kw) -> gpmsa.Emulator:
    return gpmsa.Emulator.from_params(_sim(index, **kw), PARAMS, n_pc=2)


@pytest.mark.parametrize(
    ("index", "kw", "names", "units"),
    [
        (GRID, {}, None, None),
        (GRID, {"index_names": "time", "index_units": "s"}, ("time",), ("s",)),
        (GRID, {"index_names": ["time"]}, ("time",), None),
        (None, {"index_units": ("s",)}, None, ("s",)),
        (POINTS, {"index_names": ("time", "angle"), "index_units": ["s", ""]},
         ("time", "angle"), ("s", "")),
        (POINTS, {"index_names": (n for n in ("time", "angle"))}, ("time", "angle"), None),
        (pd.DataFrame(POINTS, columns=["time", "angle"]), {}, ("time", "angle"), None),
        (pd.DataFrame(POINTS), {}, None, None),  # a frame's default labels 0, 1: no names
        (pd.Series(GRID, name="time"), {}, ("time",), None),
    ],
)  # fmt: skip
def test_index_labels_are_taken_as_given(index, kw, names, units):
    x, t, y = _runs(GRID if index is None else np.asarray(index))
    sim = gpmsa.SimData(x=x, t=t, y=y, index=index, **kw)
    assert sim.index_names == names and sim.index_units == units


def test_a_table_index_is_read_by_the_given_names():
    table = pd.DataFrame(POINTS[:, ::-1], columns=["angle", "time"])
    sim = _sim(table, index_names=["time", "angle"])
    assert np.array_equal(sim.index, POINTS) and sim.index_names == ("time", "angle")
    with pytest.raises(gpmsa.GPMSAError, match=r"index has the columns \['angle', 'time'\]"):
        _sim(table, index_names=["time", "phi"])


@pytest.mark.parametrize(
    ("index", "kw", "match"),
    [
        (POINTS, {"index_names": "time"}, r"index_names must be a list of 2 names, one per "
         r"column of the output index \(20, 2\), got the string 'time'"),
        (GRID, {"index_names": ["time", "angle"]}, r"index_names must have 1 entries, one per "
         r"column of the output index \(8,\), got 2"),
        (POINTS, {"index_units": ["s"]}, "index_units must have 2 entries"),
        (POINTS, {"index_names": ["time", "time"]}, "index_names must be unique"),
        (POINTS, {"index_names": ["time", " "]}, r"index_names\[1\] must be a non-empty name"),
        (GRID, {"index_names": [""]}, r"index_names\[0\] must be a non-empty name"),
        (POINTS, {"index_names": ["time", 2]}, r"index_names\[1\] must be a string, got int 2"),
        (GRID, {"index_units": [None]}, r"index_units\[0\] must be a string, got NoneType"),
        (GRID, {"index_names": {"time"}}, "index_names must be a list of names, one per column "
         "in order, got set"),
        (GRID, {"index_units": 1.0}, "index_units must be a list of units, one per column in "
         "order, got float"),
    ],
)  # fmt: skip
def test_bad_index_labels_are_refused(index, kw, match):
    with pytest.raises(gpmsa.GPMSAError, match=match):
        _sim(index, **kw)


def test_a_scalar_output_takes_no_index_labels():
    x, t, _ = _runs(GRID)
    with pytest.raises(gpmsa.GPMSAError, match="index_names labels the output index, but y has "
                                               "one column"):  # fmt: skip
        gpmsa.SimData(x=x, t=t, y=x[:, 0] + t[:, 0], index_names="time")


def test_file_keeps_the_labels_only_where_given(tmp_path):
    plain, named = _emu(), _emu(index_names="time", index_units="s")
    assert plain.model_sha256 == named.model_sha256  # labels: no part of the model
    m_plain, a_plain = plain.to_record()
    m_named, a_named = named.to_record()
    assert "index_names" not in m_plain["model"] and "index_units" not in m_plain["model"]
    assert m_named["model"].pop("index_names") == ["time"]
    assert m_named["model"].pop("index_units") == ["s"]
    assert m_named == m_plain and a_named.keys() == a_plain.keys()
    back = gpmsa.load(named.save(tmp_path / "n.gpmsa"))
    assert (back.index_names, back.index_units) == (("time",), ("s",))
    assert back.model_sha256 == named.model_sha256
    back = gpmsa.load(plain.save(tmp_path / "p.gpmsa"))
    assert back.index_names is None and back.index_units is None
    copy = pickle.loads(pickle.dumps(named))
    assert copy.index_names == ("time",)


def test_units_alone_and_two_columns_round_trip(tmp_path):
    emu = _emu(POINTS, index_units=["s", "rad"])
    back = gpmsa.load(emu.save(tmp_path / "u.gpmsa"))
    assert back.index_names is None and back.index_units == ("s", "rad")


def _rewrite(src, dst, edit):
    manifest, arrays = read_raw(src)
    manifest = {k: v for k, v in manifest.items() if k not in ENVELOPE}
    edit(manifest["model"])
    return write_raw(dst, manifest, arrays)


@pytest.mark.parametrize(
    ("edit", "match"),
    [
        (lambda m: m.update(index_names="time"), "model.index_names: must be a list of strings"),
        (lambda m: m.update(index_names=["time", "x"]), "model.index_names: must have 1 entries"),
        (lambda m: m.update(index_names=[3]), "model.index_names: must be a list of strings"),
        (lambda m: m.update(index_names=[""]), "model.index_names: names must be non-empty"),
        (lambda m: m.update(index_units=None), "model.index_units: must be a list of strings"),
        (lambda m: m.update(index_units=[["s"]]), "model.index_units: must be a list of strings"),
    ],
)
def test_damaged_labels_are_refused_on_loading(tmp_path, edit, match):
    src = _emu(index_names="time").save(tmp_path / "n.gpmsa")
    path = _rewrite(src, tmp_path / "bad.gpmsa", edit)
    with pytest.raises(gpmsa.EmulatorFileError, match=match):
        gpmsa.load(path)


def test_damaged_labels_of_two_columns_and_of_a_scalar_output_are_refused(tmp_path):
    src = _emu(POINTS, index_names=["time", "angle"]).save(tmp_path / "n.gpmsa")
    path = _rewrite(src, tmp_path / "dup.gpmsa", lambda m: m.update(index_names=["a", "a"]))
    with pytest.raises(gpmsa.EmulatorFileError, match="model.index_names: names must be unique"):
        gpmsa.load(path)
    x, t, _ = _runs(GRID)
    scalar = gpmsa.Emulator.from_params(gpmsa.SimData(x=x, t=t, y=np.sin(3 * x) + t), {
        "betaU": [[1], [1]], "lamUz": [1], "lamWs": [1e3], "lamWOs": [1e3]})  # fmt: skip
    src = scalar.save(tmp_path / "s.gpmsa")
    path = _rewrite(src, tmp_path / "sbad.gpmsa", lambda m: m.update(index_units=["s"]))
    with pytest.raises(gpmsa.EmulatorFileError, match="model.index_units: a scalar output"):
        gpmsa.load(path)


def test_fit_and_its_continuation_carry_the_labels():
    sim = _sim(index_names="time", index_units="s")
    emu = gpmsa.fit(sim, n_iter=20, tune=False, seed=0)
    assert (emu.index_names, emu.index_units) == (("time",), ("s",))
    more = gpmsa.fit(sim, n_iter=20, tune=False, seed=1, init=emu)
    assert (more.index_names, more.index_units) == (("time",), ("s",))


def test_one_column_figures_label_the_index(tmp_path):
    sim = _sim(index_names="time", index_units="s")
    emu = gpmsa.Emulator.from_params(sim, PARAMS)
    obs = gpmsa.ObsData(x=[[0.5]], y=[sim.y[0] + 0.01])
    label = "time (s)"
    assert gpmsa.plots.data(sim, obs).axes[0].get_xlabel() == label
    assert gpmsa.plots.pc_basis(emu).axes[0].get_xlabel() == label
    fig = gpmsa.plots.emulator_fit(emu, gpmsa.cross_validate(emu, draws=False))
    assert fig.axes[1].get_xlabel() == label
    assert gpmsa.plots.obs_projection(emu, obs).axes[2].get_xlabel() == label
    sens = gpmsa.sensitivity(emu, draws=False)
    assert gpmsa.plots.sensitivity_bars(sens).axes[1].get_xlabel() == label
    plain = _emu()
    assert gpmsa.plots.pc_basis(plain).axes[0].get_xlabel() == "output index"


def test_two_column_maps_label_their_axes():
    sim = _sim(POINTS, index_names=["time", "angle"], index_units=["s", ""])
    emu = gpmsa.Emulator.from_params(sim, PARAMS, n_pc=2)
    figures = [gpmsa.plots.data(sim), gpmsa.plots.pc_basis(emu),
               gpmsa.plots.sensitivity_bars(gpmsa.sensitivity(emu, draws=False))]  # fmt: skip
    for fig in figures:
        maps = [ax for ax in fig.axes if ax.get_xlabel() == "time (s)"]
        assert maps and all(ax.get_ylabel() == "angle" for ax in maps)
    fig = gpmsa.plots.pc_basis(_emu(POINTS, index_units=["s", "rad"]))
    assert (fig.axes[0].get_xlabel(), fig.axes[0].get_ylabel()) == (
        "output index[:, 0] (s)", "output index[:, 1] (rad)")  # fmt: skip


def test_prediction_bands_label_the_index():
    x, t, y = _runs(GRID)
    sim = gpmsa.SimData(x=x, t=t, y=y, index=GRID, index_names="time", index_units="s")
    obs = gpmsa.ObsData(x=[[0.5]], y=[y[0]])
    emu = gpmsa.fit(sim, obs, n_iter=20, tune=False, seed=0, discrepancy="constant")
    pred = gpmsa.full_prediction(emu, obs, [[0.5]], seed=1, n_draws=3, n_rlz=10)
    assert pred.index_names == ("time",)
    assert gpmsa.plots.prediction_bands(pred).axes[1].get_xlabel() == "time (s)"


def test_info_prints_the_labels(tmp_path, capsys):
    path = _emu(POINTS, index_names=["time", "angle"], index_units=["s", ""]).save(
        tmp_path / "e.gpmsa"
    )
    assert main(["info", str(path)]) == 0
    assert "output index:    20 points in 2 columns (time [s], angle), [0, 1] x [0, 2]" in (
        capsys.readouterr().out
    )
    assert main(["info", str(path), "--json"]) == 0
    index = json.loads(capsys.readouterr().out)["output_index"]
    assert index["names"] == ["time", "angle"] and index["units"] == ["s", ""]
    path = _emu(index_names="time").save(tmp_path / "one.gpmsa")
    assert main(["info", str(path)]) == 0
    assert "output index:    8 points (time), [0, 1]\n" in capsys.readouterr().out
    path = _emu().save(tmp_path / "plain.gpmsa")
    assert main(["info", str(path)]) == 0
    assert "output index" not in capsys.readouterr().out  # one column, no labels: as before
    assert main(["info", str(path), "--json"]) == 0
    index = json.loads(capsys.readouterr().out)["output_index"]
    assert index["names"] is None and index["units"] is None


def test_older_files_load_without_labels():
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    emu = gpmsa.load(root / "control" / "emulators" / "jackal_A.gpmsa")
    assert emu.index_names is None and emu.index_units is None


def test_a_study_keeps_its_members_labels(tmp_path):
    t = np.linspace(0.1, 0.9, 12)[:, None]
    x = np.tile([[0.0], [1.0]], (6, 1))
    s = np.linspace(0.0, 1.0, 4)
    sim = gpmsa.SimData(x=x, t=t, y=x + 2 * t * s, t_names=["E"], index=s, index_names="time",
                        index_units="s")  # fmt: skip
    obs = [gpmsa.ObsData(x=[[0.5]], y=[0.5 + 0.6 * s]), gpmsa.ObsData(x=[[0.2]], y=[0.2 + 0.8 * s])]
    study = gpmsa.fit_study([sim, sim], obs, shared=["E"], n_iter=60, seed=2, tune_rounds=2)
    study.save(tmp_path / "st.gpmsa")
    back = gpmsa.load_study(tmp_path / "st.gpmsa")
    for member in (*study.members, *back.members):
        assert (member.index_names, member.index_units) == (("time",), ("s",))
