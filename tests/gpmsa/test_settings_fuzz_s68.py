"""Findings of the s68 settings fuzz (/tmp/settingsfuzz-scratch/fuzz_emu.py, fuzz_study.py): the
sweep counts and acceptance rates a continuation reads back from a file (an appended fit's
appended_to, appended_after, pooled_sweeps, sweeps_run; n_iter, n_burn; diagnostics' "accept";
a study's accept_rate) loaded whatever they held, and ``fit(..., init=emu, append=True)`` then
raised TypeError / ValueError / OverflowError inside numpy or recorded garbage (a negative
pooled_sweeps, an acceptance rate of 7.5). Each is now refused on loading, EmulatorFileError
naming the field; ``gpmsa info`` refuses it in one line."""

import contextlib
import functools
import io
import warnings

import pytest

import gpmsa
from gpmsa.cli.main import main
from gpmsa.io.container import ENVELOPE, STUDY_FORMAT, read_raw, write_raw
from tests.gpmsa._continue_cases import continue_data, continue_fit
from tests.gpmsa.test_file_hostile import read_members, write_members
from tests.gpmsa.test_study_append_s67 import _calibrate


@functools.cache
def _appended() -> gpmsa.Emulator:
    """A 2-chain joint fit (thin 2) and 5 more draws a chain appended to it."""
    data, obs = continue_data()
    first = continue_fit(n_iter=20, tune=False, n_keep=20)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        return gpmsa.fit(data, obs, seed=1, n_chains=2, init=first, n_iter=10, append=True)


def _edited(tmp_path, edit):
    manifest, arrays = read_members(_appended().save(tmp_path / "e.gpmsa"))
    edit(manifest)
    return write_members(tmp_path / "edit.gpmsa", manifest, arrays)


def _refused(path, field: str, load=gpmsa.load) -> None:
    with pytest.raises(gpmsa.EmulatorFileError, match=field):
        load(path)
    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        rc = main(["info", str(path)])
    assert rc == 2 and err.getvalue().count("\n") == 1 and "unexpected" not in err.getvalue()


def _set(key, value):
    return lambda m: m["settings"].update({key: value})


@pytest.mark.parametrize(
    ("edit", "field"),
    [
        (_set("sweeps_run", 0), "settings.sweeps_run"),  # accept weighed by 0 sweeps
        (_set("sweeps_run", 10**400), "settings.sweeps_run"),  # OverflowError in pool_accept
        (_set("sweeps_run", "x"), "settings.sweeps_run"),
        (_set("pooled_sweeps", 2**70), "settings.pooled_sweeps"),
        (_set("pooled_sweeps", 10**6), "settings.pooled_sweeps"),  # more than sweeps_run
        (_set("appended_after", 10**6), "settings.appended_after"),
        (_set("appended_after", [1]), "settings.appended_after"),
        (_set("appended_to", 7), "settings.appended_to"),
        (lambda m: m["settings"].pop("sweeps_run"), "settings.sweeps_run"),
        (_set("n_iter", -1), "settings.n_iter"),
        (_set("n_burn", 10**6), "settings.n_burn"),  # a negative pooled_sweeps next
        (lambda m: m["diagnostics"]["lamWOs"].update(accept=1), r"diagnostics\['lamWOs'\]\.accept"),
        (lambda m: m["diagnostics"]["lamWOs"].update(accept=["x"]), r"\['lamWOs'\]\.accept\[0\]"),
        (lambda m: m["diagnostics"]["lamWOs"].update(accept=[7.5]), r"\['lamWOs'\]\.accept\[0\]"),
    ],
)
def test_an_appended_record_a_continuation_cannot_use_is_refused(tmp_path, edit, field):
    """These loaded; appending to them raised TypeError ('int' object is not iterable),
    ValueError or OverflowError from numpy, or recorded wrong counts and rates."""
    _refused(_edited(tmp_path, edit), field)


def test_a_valid_appended_file_loads_as_saved(tmp_path):
    emu = _appended()
    back = gpmsa.load(emu.save(tmp_path / "e.gpmsa"))
    assert back.settings == emu.settings and back.diagnostics == emu.diagnostics
    assert back.model_sha256 == emu.model_sha256


@functools.cache
def _study():
    source = _calibrate(30, 1, n_burn=10, tune=False)
    return _calibrate(6, 2, init=source, append=True, tune=False)


@pytest.mark.parametrize(
    ("key", "value", "field"),
    [
        ("accept_rate", "rates", "settings.accept_rate"),
        ("accept_rate", 7.5, "settings.accept_rate"),  # pooled as 7.5 * sweeps_run + ...
        ("pooled_sweeps", 0, "settings.pooled_sweeps"),
        ("sweeps_run", 10**400, "settings.sweeps_run"),
        ("appended_to", "x", "settings.appended_to"),
    ],
)
def test_a_study_record_an_appended_study_cannot_use_is_refused(tmp_path, key, value, field):
    path = _study().save(tmp_path / "run.gpmsa")
    manifest, arrays = read_raw(path, formats=(STUDY_FORMAT,))
    manifest = {k: v for k, v in manifest.items() if k not in ENVELOPE}
    rates = manifest["settings"]["accept_rate"]
    manifest["settings"][key] = {k: value for k in rates} if value == 7.5 else value
    write_raw(path, manifest, arrays, fmt=STUDY_FORMAT)
    _refused(path, field, gpmsa.load_study)


def test_a_valid_appended_study_loads_as_saved(tmp_path):
    study = _study()
    assert study.settings["appended_to"] is None  # never saved: no digest
    back = gpmsa.load_study(study.save(tmp_path / "run.gpmsa"))
    assert back.settings == study.settings
