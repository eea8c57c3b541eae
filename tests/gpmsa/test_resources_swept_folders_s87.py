"""A long-running process that saves into ever new folders holds a bounded record of them.

`gpmsa.io.atomic` remembers each folder it has swept of stale temporaries (`_sweep_once`), so
that a folder is listed once a process, not at every save. The record kept every folder for good:
a service that saved an emulator into a new job folder per request grew by ~90 B a save (2,000
saves, 2,003 names held), never flattening. It now holds `_SWEPT_FOLDERS` names at most and
starts afresh past that; a folder forgotten so is swept again at its next save.
"""

import subprocess
import sys

from gpmsa.io import atomic


def _save(path) -> None:
    with atomic.atomic_write(path, text=True) as fh:
        fh.write("whole")


def _dead_pid() -> int:
    """The id of a process that ran and ended (and was waited for)."""
    proc = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)  # fmt: skip
    return int(proc.stdout)


def test_saves_into_many_new_folders_keep_a_bounded_record(tmp_path, monkeypatch):
    monkeypatch.setattr(atomic, "_SWEPT", set())
    monkeypatch.setattr(atomic, "_SWEPT_FOLDERS", 16, raising=False)
    sizes = []
    for k in range(200):
        folder = tmp_path / f"job-{k}"
        folder.mkdir()
        _save(folder / "e.gpmsa")
        sizes.append(len(atomic._SWEPT))
    assert max(sizes) <= 16  # before: 200 names, one a folder
    assert all((tmp_path / f"job-{k}" / "e.gpmsa").read_text() == "whole" for k in range(200))


def test_a_folder_forgotten_is_swept_again_and_one_remembered_is_not(tmp_path, monkeypatch):
    monkeypatch.setattr(atomic, "_SWEPT", set())
    monkeypatch.setattr(atomic, "_SWEPT_FOLDERS", 4, raising=False)
    listed = []
    sweep = atomic.remove_stale_temporaries
    monkeypatch.setattr(atomic, "remove_stale_temporaries", lambda f: listed.append(f) or sweep(f))
    home = tmp_path / "home"
    home.mkdir()
    _save(home / "a.txt")
    _save(home / "b.txt")  # remembered: not listed again
    assert listed == [home]
    stale = f".c.txt.{_dead_pid()}@{atomic._host_id()}.0123456789ab.part"
    (home / stale).write_bytes(b"half a file")
    for k in range(4):  # four other folders: the record starts afresh
        (tmp_path / f"o{k}").mkdir()
        _save(tmp_path / f"o{k}" / "x.txt")
    _save(home / "d.txt")
    assert listed.count(home) == 2
    assert sorted(p.name for p in home.iterdir()) == ["a.txt", "b.txt", "d.txt"]
