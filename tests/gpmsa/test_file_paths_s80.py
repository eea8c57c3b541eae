"""Odd but valid paths and concurrent processes (session 80 sweep of every saver and loader):
a path-like giving bytes is refused by name, a missing folder is named, a save killed outright
leaves no temporary file for ever, and a study read while another process saves it is read
whole (the folder's shared lock), never as one save's study file beside the other's models."""

import os
import subprocess
import sys

import pytest

import gpmsa
from gpmsa.errors import EmulatorFileError, GPMSAError
from gpmsa.io import atomic
from tests.gpmsa._study_cases import two_model_study
from tests.gpmsa.test_files_walk_s70 import _small


class PathLike:
    def __init__(self, value) -> None:
        self.value = value

    def __fspath__(self):
        return self.value


@pytest.mark.parametrize("given", [b"e.gpmsa", PathLike(b"e.gpmsa"), PathLike(3)])
def test_a_path_giving_bytes_or_no_path_is_a_gpmsa_error_on_save_and_load(
    tmp_path, monkeypatch, given
):
    """A path-like whose __fspath__ gives bytes raised a bare TypeError from pathlib."""
    monkeypatch.chdir(tmp_path)  # (restored after the test: later tests read relative paths)
    with pytest.raises(GPMSAError, match="path must be a file name"):
        _small().save(given)
    with pytest.raises(GPMSAError, match="path must be a file name"):
        gpmsa.load(given)
    with pytest.raises(GPMSAError, match="path must be a file name"):
        gpmsa.load_study(given)
    assert os.listdir(tmp_path) == []


def test_a_bytes_path_names_the_remedy(tmp_path):
    with pytest.raises(GPMSAError, match=r"gives bytes: pass its name as a str \(os.fsdecode"):
        _small().save(PathLike(os.fsencode(tmp_path / "e.gpmsa")))


def test_a_save_into_a_missing_folder_names_the_folder(tmp_path):
    target = tmp_path / "missing" / "model.gpmsa"
    with pytest.raises(GPMSAError, match=rf"the folder {tmp_path / 'missing'} does not exist"):
        _small().save(target)
    assert not target.parent.exists()  # a save makes no folder


def _dead_pid() -> int:
    """The id of a process that ran and ended (and was waited for)."""
    proc = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)  # fmt: skip
    return int(proc.stdout)


@pytest.mark.skipif(sys.platform == "win32", reason="no process check on Windows")
def test_a_temporary_of_a_killed_save_is_removed_by_the_next_save_to_that_folder(
    tmp_path, monkeypatch
):
    """A save killed outright (SIGKILL) left its hidden '.e.gpmsa.*.part' file for ever (50
    kills of a saving process: 28 left, none removed by later saves). A process's first save
    into a folder removes every dead process's temporary there, whatever its target; later
    saves there list the folder no more (a cache of many files)."""
    host = atomic._host_id()
    dead = f".e.gpmsa.{_dead_pid()}@{host}.0123456789ab.part"
    alive = f".e.gpmsa.{os.getppid()}@{host}.0123456789ab.part"  # the parent runs
    mine = f".e.gpmsa.{os.getpid()}@{host}.0123456789ab.part"  # another thread's save
    other_host = "0" * 8 if host != "0" * 8 else "1" * 8
    elsewhere = f".e.gpmsa.{_dead_pid()}@{other_host}.a1b2c3d4e5f6.part"
    old_style = ".e.gpmsa.0123456789ab.part"  # no process named: cannot be told, kept
    other = f".f.gpmsa.{_dead_pid()}@{host}.0123456789ab.part"  # another target's
    for name in (dead, alive, mine, elsewhere, old_style, other):
        (tmp_path / name).write_bytes(b"half a file")
    _small().save(tmp_path / "e.gpmsa")
    left = sorted(os.listdir(tmp_path))
    assert left == sorted(["e.gpmsa", alive, mine, elsewhere, old_style])
    assert gpmsa.load(tmp_path / "e.gpmsa").m == 8
    listed = []
    monkeypatch.setattr(atomic, "remove_stale_temporaries", listed.append)
    later = f".g.gpmsa.{_dead_pid()}@{host}.0123456789ab.part"  # killed after the sweep
    (tmp_path / later).write_bytes(b"half a file")
    _small().save(tmp_path / "g.gpmsa")
    assert listed == [] and later in os.listdir(tmp_path)  # (the next process's first save)


def test_a_temporary_names_its_process_and_host_within_the_name_limit(tmp_path, monkeypatch):
    """A 254-byte name (unicode): the temporary file's name keeps within 255 bytes."""
    name = "émulateur_地形" + "é" * 114 + "abc.gpmsa"
    assert len(os.fsencode(name)) == 254
    seen = []
    real = os.replace

    def replace(src, dst):
        seen.append(os.path.basename(src))
        real(src, dst)

    monkeypatch.setattr(atomic.os, "replace", replace)
    _small().save(tmp_path / name)
    assert seen[0].startswith(f".{name[:32]}.{os.getpid()}@{atomic._host_id()}.")
    assert seen[0].endswith(".part") and len(os.fsencode(seen[0])) < 255
    assert os.listdir(tmp_path) == [name]


@pytest.fixture(scope="module")
def studies(tmp_path_factory):
    """A saved study and a second one, its models' metadata differing (other model files)."""
    folder = tmp_path_factory.mktemp("studies")
    study = two_model_study(n_samples=20, n_burn=10, tune_rounds=2)
    path = study.save(folder / "run.gpmsa")
    return path, study


@pytest.mark.skipif(sys.platform == "win32", reason="no flock on Windows")
def test_a_study_read_during_a_save_waits_for_its_moves(studies, monkeypatch):
    """A reader loading a study while another process saved it met 'study.models[1] (b): ...
    content sha256 ... differs' (65 of 200 loads against a saving process): it read the old
    study file and a new model file. Now the reader holds the folder's shared lock, the save's
    moves its exclusive one: a load between two moves waits (here: at once past its limit)."""
    path, study = studies
    before = [member.metadata for member in study.members]
    for member in study.members:
        member.metadata = {"version": 2}
    met = []
    real = os.replace

    def replace(src, dst):
        real(src, dst)
        if not met:  # one model file moved, the study file not yet: a reader comes
            with pytest.raises(EmulatorFileError) as err:
                gpmsa.load_study(path)
            met.append(str(err.value))

    monkeypatch.setattr(atomic, "LOCK_WAIT_S", 0.0)
    monkeypatch.setattr(atomic.os, "replace", replace)
    try:
        study.save(path)
    finally:
        monkeypatch.undo()
        for member, metadata in zip(study.members, before, strict=True):
            member.metadata = metadata
    assert "another process has held the folder's lock" in met[0], met[0]
    assert "differs" not in met[0]
    assert gpmsa.load_study(path).members[0].metadata == {"version": 2}


@pytest.mark.skipif(sys.platform == "win32", reason="no flock on Windows")
def test_a_study_loads_from_a_read_only_folder_and_files(studies, tmp_path):
    """The reader's lock is on the folder itself (opened for reading): no lock file to make."""
    path, _ = studies
    folder = tmp_path / "ro"
    folder.mkdir()
    for name in ("run.gpmsa", "run.a.gpmsa", "run.b.gpmsa"):
        (folder / name).write_bytes(path.with_name(name).read_bytes())
        os.chmod(folder / name, 0o444)
    os.chmod(folder, 0o555)
    try:
        assert gpmsa.load_study(folder / "run.gpmsa").labels == ("a", "b")
        assert os.listdir(folder) and sorted(os.listdir(folder)) == [
            "run.a.gpmsa", "run.b.gpmsa", "run.gpmsa"
        ]  # fmt: skip
    finally:
        os.chmod(folder, 0o755)
