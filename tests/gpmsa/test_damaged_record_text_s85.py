"""Text in a file's numeric record is named a damaged record, not a CSV table (session 85).

``as_float``'s message for text advises on a table read from a CSV file ("Read the file with
pd.read_csv(..., na_values=[...])", "df.apply(pd.to_numeric)"). The emulator file's checks of
its hot copies' record (settings "hot_states", "hot_step_widths") and of settings.fixed passed
that advice on for text in the file's JSON, where no CSV table is involved: a file damaged or
edited by hand. They now name the field and say the record is damaged; a user's own data keeps
the advice. A study file's hot record read numeric text ("0.5") and bools as numbers and let
an integer beyond float64 escape as an OverflowError; it now refuses them as the emulator
file's check does (test_hot_record_checks_s85).
"""

import copy

import numpy as np
import pytest
from test_hotcont_s76 import _source as _tempered_fit
from test_studyhot_s76 import _damaged as _damaged_study

import gpmsa
from gpmsa.errors import GPMSAError
from gpmsa.model.data import as_float
from tests.gpmsa.test_file_hostile import read_members, write_members

ADVICE = ("pd.read_csv", "df.apply", "to_numeric", "na_values", "decimal=", "not converted")
TEXT = [("abc", "str 'abc'"), ([["0.5", "0.25"]], "str '0.5'"), (["1,5", 2.0], "str '1,5'"),
        ([[True]], "bool True")]  # fmt: skip


@pytest.fixture(scope="module")
def fit_file(tmp_path_factory):
    """A tempered fit's file (2 chains, 2 hot copies) as its manifest and arrays."""
    path = _tempered_fit().save(tmp_path_factory.mktemp("fit") / "t.gpmsa")
    return read_members(path)


def _refusal(path) -> str:
    with pytest.raises(gpmsa.EmulatorFileError) as info:
        gpmsa.load(path)
    return str(info.value)


@pytest.mark.parametrize(("value", "shown"), TEXT, ids=["word", "numeric-2d", "comma", "bool"])
@pytest.mark.parametrize("key", ["hot_states", "hot_step_widths"])
def test_text_in_a_fits_hot_record_is_a_damaged_record(tmp_path, fit_file, key, value, shown):
    manifest, arrays = copy.deepcopy(fit_file)
    manifest["settings"][key]["theta"] = value
    msg = _refusal(write_members(tmp_path / "bad.gpmsa", manifest, arrays))
    assert f"settings.{key}['theta'] must be a numeric array, got {shown}" in msg, msg
    assert "(a damaged record: gpmsa writes numbers there)" in msg, msg
    assert not any(a in msg for a in ADVICE), msg


def test_text_in_settings_fixed_is_a_damaged_record(tmp_path):
    rng = np.random.default_rng(0)
    sim = gpmsa.SimData(x=rng.random((8, 1)), t=rng.random((8, 1)), y=rng.random((8, 1)))
    emu = gpmsa.Emulator.from_params(sim, {"betaU": np.ones((2, 1)), "lamUz": [1.0],
                                           "lamWs": [1e4], "lamWOs": [1e4]})  # fmt: skip
    manifest, arrays = read_members(emu.save(tmp_path / "e.gpmsa"))
    manifest["settings"]["fixed"] = {"lamUz": ["n/a"]}
    msg = _refusal(write_members(tmp_path / "bad.gpmsa", manifest, arrays))
    assert "settings.fixed['lamUz'] must be a numeric array, got str 'n/a' (a damaged record" in msg
    assert not any(a in msg for a in ADVICE), msg


@pytest.mark.parametrize(("value", "shown"), TEXT[1:], ids=["numeric-2d", "comma", "bool"])
def test_text_in_a_studys_hot_record_is_a_damaged_record(tmp_path, value, shown):
    def edit(settings):
        settings["hot_states"]["theta"] = value

    with pytest.raises(gpmsa.EmulatorFileError) as info:
        gpmsa.load_study(_damaged_study(tmp_path, edit))
    msg = str(info.value)
    assert f"settings.hot_states.theta must be a numeric array, got {shown} (a damaged" in msg
    assert not any(a in msg for a in ADVICE), msg


def test_a_users_own_text_keeps_its_advice():
    with pytest.raises(GPMSAError, match=r"decimal=','"):
        as_float([["1,5"]], "x")
    with pytest.raises(GPMSAError, match=r"df\.apply\(pd\.to_numeric\)"):
        as_float([["0.5"]], "x")
    with pytest.raises(GPMSAError, match=r"^x must be a numeric array, got str '1,5'$"):
        as_float([["1,5"]], "x", advice=False)
