"""Guards of fit and save: observations with too few x columns (gpmsa.fit broadcast them), saves
over files that are not gpmsa files, files holding zero draws, a generator given as shared, and
a study file name that could not name its model files."""

from __future__ import annotations

import io
import json
import zipfile

import numpy as np
import pytest

import gpmsa
from gpmsa.errors import EmulatorFileError, GPMSAError
from gpmsa.io.container import content_hash
from tests.gpmsa import _study_cases as sc
from tests.gpmsa._emulator_edit import replaced


def _read(path):
    with zipfile.ZipFile(path) as z:
        manifest = json.loads(z.read("manifest.json"))
        arrays = {n[len("arrays/") : -4]: np.load(io.BytesIO(z.read(n)))
                  for n in z.namelist() if n.startswith("arrays/")}  # fmt: skip
    return manifest, arrays


def _write_resealed(path, manifest, arrays) -> None:
    """Write (manifest, arrays) as a gpmsa file whose envelope and hash match the arrays."""
    manifest = {k: v for k, v in manifest.items() if k != "content_sha256"}
    manifest["arrays"] = {k: {"shape": list(v.shape), "dtype": v.dtype.str}
                          for k, v in arrays.items()}  # fmt: skip
    manifest["content_sha256"] = content_hash(arrays, manifest)
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as z:
        z.writestr("manifest.json", json.dumps(manifest))
        for k, v in arrays.items():
            buf = io.BytesIO()
            np.save(buf, v, allow_pickle=False)
            z.writestr(f"arrays/{k}.npy", buf.getvalue())


def _sim_two_inputs() -> gpmsa.SimData:
    rng = np.random.default_rng(3)
    x, t = rng.uniform(size=(16, 2)), rng.uniform(size=(16, 1))
    return gpmsa.SimData(x=x, t=t, y=x[:, :1] + 2.0 * t, t_names=["t"])


@pytest.fixture(scope="module")
def study():
    rng = np.random.default_rng(0)
    x, y = sc.observations(0.5, 4, 0.05, rng)
    emu = sc.emulator()
    return gpmsa.calibrate_study([emu, emu], [x, x], [y, y], shared=["t"], n_samples=120,
                                 n_burn=30, seed=1, tune_rounds=2)  # fmt: skip


def _files(folder) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in folder.iterdir()}


# 1 -----------------------------------------------------------------------------------------------
def test_fit_refuses_x_obs_with_too_few_columns():
    """gpmsa.fit broadcast a one-column x_obs over a model's two inputs ([0.5] -> [0.5, 0.5])
    and ran; gpmsa.calibrate refused the same observations."""
    obs = gpmsa.ObsData(x=[[0.5]], y=[[1.5]])
    with pytest.raises(GPMSAError, match=r"x_obs must have shape \(n, 2\), got \(1, 1\)"):
        gpmsa.fit(_sim_two_inputs(), obs, n_iter=50, seed=1)
    with pytest.raises(GPMSAError, match=r"x_obs must have shape \(n, 2\), got \(1, 1\)"):
        gpmsa.fit_study([_sim_two_inputs()] * 2, [obs, obs], shared=["t"], n_iter=50, seed=1)


# 2 -----------------------------------------------------------------------------------------------
def test_emulator_save_refuses_a_file_that_is_not_a_gpmsa_file(tmp_path):
    """Emulator.save replaced a user's notes.txt (not a gpmsa file) without a word."""
    emu = sc.emulator()
    notes = tmp_path / "notes.txt"
    notes.write_text("my precious notes\n")
    with pytest.raises(GPMSAError, match=r"refusing to write .*notes\.txt: it holds a file that "
                                         r"is not a gpmsa file \(18 bytes\), which an emulator "
                                         r"file would replace"):  # fmt: skip
        emu.save(notes)
    archive = tmp_path / "data.zip"  # a zip, but not laid out as a gpmsa file
    with zipfile.ZipFile(archive, "w") as z:
        z.writestr("table.csv", "a,b\n1,2\n")
    before = archive.read_bytes()
    with pytest.raises(GPMSAError, match="not a gpmsa file"):
        emu.save(archive)
    assert notes.read_text() == "my precious notes\n" and archive.read_bytes() == before
    empty = tmp_path / "empty.gpmsa"  # an empty file holds nothing to lose
    empty.touch()
    emu.save(empty)
    emu.save(empty)  # an emulator file is replaced, as documented
    assert gpmsa.load(empty).m == emu.m


def test_study_save_refuses_files_that_are_not_gpmsa_files(study, tmp_path):
    """Study.save replaced a user's data.csv, and a user's text file where a member goes."""
    csv = tmp_path / "data.csv"
    csv.write_text("a,b\n1,2\n")
    with pytest.raises(GPMSAError, match=r"refusing to write .*data\.csv: it holds a file that "
                                         r"is not a gpmsa file \(8 bytes\), which a study file "
                                         r"would replace"):  # fmt: skip
        study.save(csv)
    member = tmp_path / "beam.model0.gpmsa"
    member.write_text("user text\n")
    before = _files(tmp_path)
    with pytest.raises(GPMSAError, match=r"refusing to write .*beam\.model0\.gpmsa: it holds a "
                                         r"file that is not a gpmsa file"):  # fmt: skip
        study.save(tmp_path / "beam.gpmsa")
    assert _files(tmp_path) == before  # nothing written, nothing replaced
    member.unlink()
    study.save(tmp_path / "beam.gpmsa")
    study.save(tmp_path / "beam.gpmsa")  # a study replaces its own files
    assert gpmsa.load_study(tmp_path / "beam.gpmsa").labels == study.labels


# 3 -----------------------------------------------------------------------------------------------
@pytest.mark.parametrize("cut", ["draws", "chains"])
def test_a_study_file_with_zero_draws_is_refused(study, tmp_path, cut):
    """A study file whose arrays held zero draws (hash matching) crashed load_study with
    "ValueError: cannot reshape array of size 0"."""
    path = study.save(tmp_path / "s.gpmsa")
    manifest, arrays = _read(path)
    arrays = {k: (v[:, :0] if cut == "draws" else v[:0]) for k, v in arrays.items()}
    _write_resealed(path, manifest, arrays)
    what = "draw" if cut == "draws" else "chain"
    with pytest.raises(EmulatorFileError, match=rf"s\.gpmsa: arrays/log_post: needs >= 1 {what}"):
        gpmsa.load_study(path)


def _with_draws(n: int) -> gpmsa.Emulator:
    emu = gpmsa.Emulator.from_params(sc.sim_data(), sc.PARAMS)
    draws = {k: np.repeat(np.asarray(v)[None], n, axis=0) for k, v in emu.params.items()}
    return replaced(emu, draws=draws, log_post=np.zeros(n))


def test_an_emulator_file_with_zero_draws_is_refused(tmp_path):
    """An emulator file whose draw_ arrays held zero draws loaded, and predict(draws=True) then
    averaged nothing into NaN."""
    path = _with_draws(3).save(tmp_path / "e.gpmsa")
    manifest, arrays = _read(path)
    arrays = {k: v[:0] if k == "log_post" or k.startswith("draw_") else v
              for k, v in arrays.items()}  # fmt: skip
    _write_resealed(path, manifest, arrays)
    with pytest.raises(EmulatorFileError, match=r"arrays/draw_\w+: needs >= 1 draw"):
        gpmsa.load(path)
    with pytest.raises(GPMSAError, match=r"refusing to write .*needs >= 1 draw"):
        _with_draws(0).save(tmp_path / "zero.gpmsa")  # the writer refuses what the reader would
    plain = gpmsa.Emulator.from_params(sc.sim_data(), sc.PARAMS)  # no draws at all: as before
    assert gpmsa.load(plain.save(tmp_path / "plain.gpmsa")).n_draws == 0


# 4 -----------------------------------------------------------------------------------------------
def test_fit_study_records_shared_names_given_as_a_generator():
    """fit_study read shared= once to build the layout; a generator then recorded [] in each
    member's settings."""
    rng = np.random.default_rng(0)
    obs = [gpmsa.ObsData(*sc.observations(0.5, 3, 0.05, rng)) for _ in range(2)]
    study = gpmsa.fit_study([sc.sim_data()] * 2, obs, shared=(n for n in ["t"]), n_iter=60,
                            seed=2, tune_rounds=1)  # fmt: skip
    assert [m.settings["study"]["shared"] for m in study.members] == [["t"], ["t"]]
    assert [m.settings["study"]["hierarchical"] for m in study.members] == [[], []]


# 5 -----------------------------------------------------------------------------------------------
def test_study_save_names_the_rule_for_its_file_name(study, tmp_path):
    """study.save("my study.gpmsa") failed naming an internal field (study.models[0].file)."""
    for name in ("my study.gpmsa", "é.gpmsa", ".hidden.gpmsa", "x" * 145 + ".gpmsa"):
        with pytest.raises(GPMSAError, match=rf"path: the study file's name '{name}' may use only "
                                             r"ASCII letters, digits, '_', '-' and '\.', not "
                                             r"start with '\.', and have a stem of at most 144 "
                                             r"characters"):  # fmt: skip
            study.save(tmp_path / name)
    assert list(tmp_path.iterdir()) == []
    longest = tmp_path / ("x" * 144 + ".gpmsa")  # model0: x*144.model0.gpmsa, 157 characters
    study.save(longest)
    assert gpmsa.load_study(longest).labels == study.labels


class _Checked(Exception):
    """Carries the bytes that fit's memory check was asked about."""


@pytest.mark.parametrize(("p", "q", "n_pc"), [(1, 1, 1), (1, 1, 3), (2, 2, 2), (0, 1, 2)])
def test_a_planned_simulation_fit_needs_the_bytes_fit_checks(monkeypatch, p, q, n_pc):
    """simulation_fit_nbytes, which a caller uses before its runs exist (train_emulator.py's
    preflight), gives the figure fit checks for the prepared problem."""
    from gpmsa.fitting import fit as fit_module

    def record(nbytes, what):
        raise _Checked(nbytes)

    rng = np.random.default_rng(3)
    m = 12
    x, t = rng.uniform(size=(m, p)), rng.uniform(size=(m, q))
    y = np.sin(np.arange(1, 5) * (t.sum(axis=1, keepdims=True) + x.sum(axis=1, keepdims=True)))
    monkeypatch.setattr(fit_module, "check_memory", record)
    with pytest.raises(_Checked) as checked:
        gpmsa.fit(gpmsa.SimData(x=x, t=t, y=y), n_iter=700, n_chains=2, n_pc=n_pc, seed=0)
    planned = fit_module.simulation_fit_nbytes(m, p, q, n_pc, n_iter=700, n_chains=2)
    assert checked.value.args[0] == planned
