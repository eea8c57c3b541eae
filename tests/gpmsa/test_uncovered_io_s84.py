"""File and ``gpmsa info`` paths that no test ran before session 84 (a branch-coverage run of
the whole suite): the text and JSON summaries of a joint fit, and hand-edited emulator and study
files refused with EmulatorFileError naming the field. One was a defect: a study file whose
settings.n_chains is 0 was refused as "must be an integer, got 0" (0 is an integer; the rule is
>= 1)."""

import contextlib
import io
import json
import re
import warnings
from functools import cache

import numpy as np
import pytest

import gpmsa
from gpmsa.cli.main import main
from gpmsa.io.container import ENVELOPE, STUDY_FORMAT, read_raw, write_raw
from tests.gpmsa._study_cases import emulator, observations
from tests.gpmsa.test_discrepancy_groups_s61 import BASIS, _data
from tests.gpmsa.test_file_hostile import read_members, write_members


def _quiet(fn, *args, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the toys' short chains are not converged
        return fn(*args, **kw)


@cache
def _joint(per_experiment: bool) -> gpmsa.Emulator:
    """A short joint fit of the s61 toy (five experiments), its discrepancy one basis or one per
    experiment."""
    data, obs = _data()
    disc = [BASIS] * 5 if per_experiment else BASIS
    return _quiet(gpmsa.fit, data, obs, n_iter=6, tune=False, seed=0, discrepancy=disc)


def _info(*args) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        rc = main(["info", *map(str, args)])
    return rc, out.getvalue(), err.getvalue()


# --- gpmsa info of a joint fit --------------------------------------------------------------------
def test_info_describes_per_experiment_discrepancy_bases(tmp_path):
    path = _joint(True).save(tmp_path / "list.gpmsa")
    rc, out, err = _info(path)
    assert rc == 0, err
    line = next(s for s in out.splitlines() if s.startswith("discrepancy:"))
    assert "list (one basis per experiment: 5 experiments x 3 vectors, in the file)" in line


def test_info_json_gives_theta_means_in_native_units(tmp_path):
    emu = _joint(False)
    rc, out, err = _info("--json", emu.save(tmp_path / "joint.gpmsa"))
    assert rc == 0, err
    theta = json.loads(out)["posterior"]["theta"]
    (unit,) = theta["mean"]
    native = emu.standardizer.t_from_unit(np.array([[unit]]))[0, 0]
    assert theta["mean_native"] == {"t": pytest.approx(native, rel=1e-12)}
    lo, hi = emu.domain["t"]
    assert lo <= theta["mean_native"]["t"] <= hi


# --- hand-edited emulator files -------------------------------------------------------------------
def _set(path: tuple, value):
    def edit(m):
        for key in path[:-1]:
            m = m[key]
        m[path[-1]] = value

    return edit


@pytest.mark.parametrize(
    ("edit", "field"),
    [
        (
            _set(("priors", "rho_cap"), 1.5),
            r"priors.rho_cap: 1.5 is out of range: allowed \(0, 1\)",
        ),
        (
            _set(("priors", "rho_a"), -1.0),
            r"priors.rho_a: -1.0 is out of range: allowed \(0, inf\)",
        ),
        (_set(("priors", "corrected"), 1), "priors.corrected: must be true or false, got 1"),
        (_set(("convergence",), 5), "convergence: must be an object, got 5"),
        (_set(("model", "categorical"), []), "model.categorical: must be an object name -> levels"),
        (_set(("model", "categorical"), {"zz": [0, 1]}), "model.categorical.zz: is not an input"),
        (_set(("model", "mean_basis"), "cubic"), "model.mean_basis"),
    ],
)
def test_a_hand_edited_emulator_file_is_refused_naming_the_field(tmp_path, edit, field):
    manifest, arrays = read_members(emulator().save(tmp_path / "e.gpmsa"))
    edit(manifest)
    _refused(write_members(tmp_path / "edit.gpmsa", manifest, arrays), field)


def test_a_file_naming_two_outputs_alike_is_refused(tmp_path):
    manifest, arrays = read_members(_joint(False).save(tmp_path / "e.gpmsa"))
    manifest["names"]["y"] = ["y"] * len(manifest["names"]["y"])
    path = write_members(tmp_path / "edit.gpmsa", manifest, arrays)
    _refused(path, "names.y: output names must be unique")


def _refused(path, field: str) -> None:
    """gpmsa.load raises EmulatorFileError matching ``field``; gpmsa info refuses in one line."""
    with pytest.raises(gpmsa.EmulatorFileError, match=field):
        gpmsa.load(path)
    rc, _, err = _info(path)
    assert rc == 2 and err.count("\n") == 1 and "unexpected" not in err, err


@pytest.mark.parametrize(("key", "value"), [("settings", []), ("metadata", 5)])
def test_from_record_refuses_a_manifest_field_that_is_not_an_object(key, value):
    """A file's reader refuses these first (the container's own check of the manifest);
    ``Emulator.from_record`` of a record built in memory reaches the field check."""
    manifest, arrays = emulator().to_record()
    manifest = {**manifest, key: value}
    with pytest.raises(
        gpmsa.EmulatorFileError, match=re.escape(f"{key}: must be an object, got {value}")
    ):
        gpmsa.Emulator.from_record(manifest, arrays)


# --- hand-edited study files ----------------------------------------------------------------------
@cache
def _study() -> gpmsa.Study:
    rng = np.random.default_rng(4)
    data = [observations(th, 3, 0.03, rng) for th in (0.35, 0.5)]
    return _quiet(gpmsa.calibrate_study, [emulator(None)] * 2, [d[0] for d in data],
                  [d[1] for d in data], labels=["a", "b"], n_samples=20, n_burn=5, seed=5,
                  tune=False)  # fmt: skip


@pytest.mark.parametrize(
    ("key", "value", "match"),
    [
        ("n_chains", 0, r"settings.n_chains: must be an integer >= 1, got 0"),
        ("n_burn", -1, r"settings.n_burn: must be an integer >= 0, got -1"),
        ("thin", 1.5, r"settings.thin: must be an integer >= 1, got 1.5"),
    ],
)
def test_a_study_file_with_a_bad_count_names_its_rule(tmp_path, key, value, match):
    """Before: "must be an integer, got 0" for n_chains 0, which is an integer."""
    path = _study().save(tmp_path / "run.gpmsa")
    manifest, arrays = read_raw(path, formats=(STUDY_FORMAT,))
    manifest = {k: v for k, v in manifest.items() if k not in ENVELOPE}
    manifest["settings"][key] = value
    write_raw(path, manifest, arrays, fmt=STUDY_FORMAT)
    with pytest.raises(gpmsa.EmulatorFileError, match=match):
        gpmsa.load_study(path)
