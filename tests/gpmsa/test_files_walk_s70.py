"""A user sharing emulator files (session 70 walkthrough): a save whose permissions cannot be
copied leaves nothing behind, a file cut short says so, and a study file given where an
emulator file is expected (and the reverse) is named for what it is."""

import os

import numpy as np
import pytest

import gpmsa
from gpmsa.errors import EmulatorFileError, GPMSAError
from gpmsa.io import atomic
from tests.gpmsa._study_cases import two_model_study


def _small() -> gpmsa.Emulator:
    rng = np.random.default_rng(1)
    x, t = rng.random((8, 1)), rng.random((8, 1))
    sim = gpmsa.SimData(x=x, t=t, y=np.sin(3 * x) + t, x_names=["v"], t_names=["GD"])
    params = {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [5000.0], "lamWOs": [5000.0]}
    return gpmsa.Emulator.from_params(sim, params)


def test_a_save_whose_permissions_cannot_be_copied_leaves_the_file_and_no_temporary(
    tmp_path, monkeypatch
):
    """os.chmod failing (a FAT stick, a share without permissions) left a '.e.gpmsa.*.part'
    file and its open descriptor behind, and raised a bare PermissionError."""
    emu = _small()
    path = emu.save(tmp_path / "e.gpmsa")
    before = path.read_bytes()

    def refused(*args, **kwargs):
        raise PermissionError(1, "Operation not permitted")

    monkeypatch.setattr(atomic.os, "chmod", refused)
    with pytest.raises(GPMSAError, match=r"e\.gpmsa: cannot write \(Operation not permitted"):
        emu.save(path)
    assert path.read_bytes() == before
    assert os.listdir(tmp_path) == ["e.gpmsa"]


def test_a_file_cut_short_is_named_truncated_not_foreign(tmp_path):
    """An interrupted download read 'not a gpmsa emulator file', which sends a user looking for
    another file instead of fetching this one again; saving over it named it 'not a gpmsa file'."""
    path = _small().save(tmp_path / "e.gpmsa")
    cut = tmp_path / "cut.gpmsa"
    cut.write_bytes(path.read_bytes()[: path.stat().st_size * 9 // 10])
    with pytest.raises(EmulatorFileError, match="cut short") as err:
        gpmsa.load(cut)
    assert "not a gpmsa emulator file" not in str(err.value)
    with pytest.raises(GPMSAError, match="a gpmsa file cut short") as err:
        _small().save(cut)  # still refused (it cannot be told apart), but named for what it is
    assert "not a gpmsa file" not in str(err.value)


@pytest.fixture(scope="module")
def study_path(tmp_path_factory):
    study = two_model_study(n_samples=20, n_burn=10, tune_rounds=2)
    return study.save(tmp_path_factory.mktemp("study") / "run.gpmsa")


def test_a_study_file_given_for_an_emulator_file_is_named_a_study(study_path, capsys):
    """gpmsa.load and `gpmsa calibrate` called a study file a 'foreign file'."""
    with pytest.raises(EmulatorFileError, match="format is 'gpmsa-study'.*a study file"):
        gpmsa.load(study_path)
    from gpmsa.cli.main import main

    assert main(["calibrate", str(study_path), "--x", "x=0.5", "--y", "y=1"]) == 2
    err = capsys.readouterr().err
    assert "gpmsa.load_study" in err and "foreign" not in err
    model = study_path.with_name("run.a.gpmsa")
    with pytest.raises(EmulatorFileError, match="an emulator file.*gpmsa.load"):
        gpmsa.load_study(model)
