"""Saves under a full disk or a refused move, saves racing one another, and a process killed
while its chains run: an OS error names the file and leaves the old one whole, a group of files
(a study) is moved under a lock on its folder, and gpmsa's pool workers end with a killed
parent."""

import errno
import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import gpmsa
from gpmsa.io import atomic
from gpmsa.io.atomic import atomic_group, atomic_write
from tests._processes import assert_workers_end

fcntl = pytest.importorskip("fcntl")


def _full(*args, **kwargs):
    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


def _denied(*args, **kwargs):
    raise PermissionError(errno.EACCES, os.strerror(errno.EACCES))


@pytest.mark.parametrize(
    ("where", "failure", "why"),
    [
        ("write", _full, "No space left on device"),
        ("fsync", _full, "No space left on device"),
        ("replace", _denied, "Permission denied"),
    ],
)
def test_an_os_error_while_saving_names_the_file_and_leaves_the_old_one(
    tmp_path, monkeypatch, where, failure, why
):
    """A full disk or a refused move raised a bare OSError ("[Errno 28] No space left on
    device"), which named no file; it is the caller's error naming the path."""
    path = tmp_path / "notes.txt"
    path.write_text("old")
    if where != "write":
        monkeypatch.setattr(os, where, failure)
    with pytest.raises(gpmsa.GPMSAError) as info, atomic_write(path, text=True) as fh:
        fh.write("new")
        if where == "write":
            failure()
    assert str(info.value) == f"{path}: cannot write ({why})"
    assert isinstance(info.value.__cause__, OSError)
    monkeypatch.undo()
    assert path.read_text() == "old" and os.listdir(tmp_path) == ["notes.txt"]


def test_a_writers_own_error_without_a_full_disk_passes_unchanged(tmp_path):
    """Only the errors a write raises (no space, quota, too large, I/O) are the file's: a
    writer's own OS error (a file it reads, missing) is raised as it was."""
    path = tmp_path / "f.png"
    with pytest.raises(FileNotFoundError, match="font"), atomic_write(path):
        raise FileNotFoundError(errno.ENOENT, "no such font")
    assert os.listdir(tmp_path) == []


def test_an_emulator_save_on_a_full_disk_names_the_file(tmp_path, monkeypatch):
    from _study_cases import emulator

    path = tmp_path / "e.gpmsa"
    emulator(None).save(path)
    before = path.read_bytes()
    monkeypatch.setattr(os, "fsync", _full)
    with pytest.raises(gpmsa.GPMSAError, match=rf"^{path}: cannot write \(No space left"):
        emulator(None, lam_w=500.0).save(path)
    monkeypatch.undo()
    assert path.read_bytes() == before and os.listdir(tmp_path) == ["e.gpmsa"]
    gpmsa.load(path)


def _held_by_another(folder: Path) -> bool:
    """Whether another process (here: another open file description) holding the folder's lock
    would wait."""
    fd = os.open(folder, os.O_RDONLY)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        return True
    finally:
        os.close(fd)
    return False


def test_a_group_moves_its_files_under_a_lock_on_their_folder(tmp_path, monkeypatch):
    """Two processes saving one study at once (a study file and its model files) interleaved
    their moves: 37 of 100 simultaneous pairs left a study file beside another save's model
    file, a study neither could load. The moves of a group now hold the folder's lock."""
    real, held = os.replace, []

    def replace(src, dst):
        held.append(_held_by_another(tmp_path))
        real(src, dst)

    monkeypatch.setattr(os, "replace", replace)
    with atomic_group() as stage:
        for name in ("s.a.gpmsa", "s.b.gpmsa", "s.gpmsa"):
            with stage(tmp_path / name) as fh:
                fh.write(name.encode())
    assert held == [True, True, True]
    assert not _held_by_another(tmp_path)  # released
    with atomic_write(tmp_path / "one.txt") as fh:  # a single file needs none: one move
        fh.write(b"x")
    assert held == [True, True, True, False]
    assert sorted(os.listdir(tmp_path)) == ["one.txt", "s.a.gpmsa", "s.b.gpmsa", "s.gpmsa"]


def test_a_lock_held_too_long_names_the_folder_and_leaves_the_files(tmp_path, monkeypatch):
    (tmp_path / "s.gpmsa").write_bytes(b"old")
    fd = os.open(tmp_path, os.O_RDONLY)
    fcntl.flock(fd, fcntl.LOCK_EX)  # a writer stopped midway
    monkeypatch.setattr(atomic, "LOCK_WAIT_S", 0.0)
    try:
        with pytest.raises(gpmsa.GPMSAError, match=rf"^{tmp_path}: another process has held"):
            with atomic_group() as stage:
                for name in ("s.a.gpmsa", "s.gpmsa"):
                    with stage(tmp_path / name) as fh:
                        fh.write(b"new")
    finally:
        os.close(fd)
    assert os.listdir(tmp_path) == ["s.gpmsa"] and (tmp_path / "s.gpmsa").read_bytes() == b"old"


@pytest.mark.skipif(sys.platform != "linux", reason="the pool forks on Linux")
def test_a_killed_parent_takes_its_pool_workers_with_it(tmp_path):
    """A fit killed outright (SIGTERM or SIGKILL: `kill PID`, the OOM killer) left its two
    chain workers idle for ever (seen: 4 minutes and counting), each a copy of its memory."""
    script = textwrap.dedent(
        """
        import os, signal
        from gpmsa.mcmc import parallel
        pool = parallel._own_pool(1)
        print(pool.submit(os.getpid).result(), flush=True)
        os.kill(os.getpid(), signal.SIGKILL)
        """
    )
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    proc = subprocess.Popen(
        [sys.executable, "-c", script], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
        env=env, text=True,
    )  # fmt: skip
    worker = int(proc.stdout.readline())
    proc.stdout.close()
    assert proc.wait() == -signal.SIGKILL
    assert_workers_end([worker])
