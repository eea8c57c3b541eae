"""gpmsa.io.atomic (s90): after its moves a save flushes each folder to disk, so that a power
cut just after it keeps the new files (a file's bytes were flushed before its move, its new
name in the folder only by the folder's fsync)."""

import errno
import os
import stat
import sys

import pytest

import gpmsa
from gpmsa.io import atomic
from gpmsa.io.atomic import atomic_group, atomic_write
from tests._fsync import fail_fsync

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="no fsync of a folder there")


def _record_syncs(monkeypatch, paths):
    """Record each fsync as ("file", size) or ("folder", inode, what ``paths`` hold then)."""
    events = []
    real_fsync = os.fsync

    def fsync(fd):
        st = os.fstat(fd)
        if stat.S_ISDIR(st.st_mode):
            now = tuple(p.read_bytes() if p.exists() else None for p in paths)
            events.append(("folder", st.st_ino, now))
        else:
            events.append(("file", st.st_size))
        real_fsync(fd)

    monkeypatch.setattr(atomic.os, "fsync", fsync)
    return events


def test_one_file_saved_then_its_folder_flushed(tmp_path, monkeypatch):
    target = tmp_path / "f"
    target.write_bytes(b"old")
    events = _record_syncs(monkeypatch, [target])
    with atomic_write(target) as fh:
        fh.write(b"new!")
    assert events == [("file", 4), ("folder", os.stat(tmp_path).st_ino, (b"new!",))]


def test_a_group_flushes_each_folder_once_after_every_move(tmp_path, monkeypatch):
    a_dir, b_dir = tmp_path / "a", tmp_path / "b"
    a_dir.mkdir()
    b_dir.mkdir()
    paths = [a_dir / "x", a_dir / "y", b_dir / "z"]
    events = _record_syncs(monkeypatch, paths)
    with atomic_group() as stage:
        for i, path in enumerate(paths):
            with stage(path) as fh:
                fh.write(b"%d" % i)
    files = [e for e in events if e[0] == "file"]
    folders = [e for e in events if e[0] == "folder"]
    assert files == [("file", 1)] * 3
    assert events[:3] == files  # the files' data first, the folders after
    assert sorted(e[1] for e in folders) == sorted([os.stat(a_dir).st_ino, os.stat(b_dir).st_ino])
    assert all(e[2] == (b"0", b"1", b"2") for e in folders)  # every move made before


def test_an_io_error_flushing_the_folder_names_it_and_leaves_the_file(tmp_path, monkeypatch):
    fail_fsync(monkeypatch, atomic)
    with pytest.raises(gpmsa.GPMSAError) as info:
        with atomic_write(tmp_path / "f") as fh:
            fh.write(b"data")
    assert str(info.value) == (
        f"{tmp_path}: the files were moved into place, but the folder could not be flushed to "
        f"disk ({os.strerror(errno.EIO)}): a power cut could still undo the save; check the "
        "disk and save again"
    )
    assert isinstance(info.value.__cause__, OSError)
    assert (tmp_path / "f").read_bytes() == b"data"
    assert os.listdir(tmp_path) == ["f"]


@pytest.mark.parametrize("code", ["EINVAL", "EBADF", "ENOTSUP"])
def test_a_file_system_without_folder_fsync_saves_as_before(tmp_path, monkeypatch, code):
    fail_fsync(monkeypatch, atomic, code=getattr(errno, code))
    with atomic_write(tmp_path / "f", error=ValueError) as fh:
        fh.write(b"data")
    assert (tmp_path / "f").read_bytes() == b"data"


def test_a_folder_that_cannot_be_opened_for_reading_saves_as_before(tmp_path, monkeypatch):
    real_open = os.open
    opened = []

    def no_read(path, flags, *args):
        if flags & getattr(os, "O_DIRECTORY", 0) or os.path.isdir(path):
            opened.append(path)
            raise PermissionError(errno.EACCES, os.strerror(errno.EACCES))
        return real_open(path, flags, *args)

    monkeypatch.setattr(atomic.os, "open", no_read)
    with atomic_write(tmp_path / "f") as fh:
        fh.write(b"data")
    assert opened == [tmp_path]
    assert (tmp_path / "f").read_bytes() == b"data"


def test_the_folder_descriptor_is_closed(tmp_path, monkeypatch):
    closed, real_close = [], os.close
    monkeypatch.setattr(atomic.os, "close", lambda fd: (closed.append(fd), real_close(fd)))
    fail_fsync(monkeypatch, atomic)
    with pytest.raises(gpmsa.GPMSAError):
        with atomic_write(tmp_path / "f") as fh:
            fh.write(b"data")
    assert len(closed) == 1
    with pytest.raises(OSError):
        os.fstat(closed[0])


def test_a_group_flushes_every_folder_though_one_fails_and_raises_the_first(tmp_path, monkeypatch):
    # session 91: the first folder whose flush failed stopped the others' flushes
    folders = [tmp_path / "a", tmp_path / "b", tmp_path / "c"]
    for folder in folders:
        folder.mkdir()
    flushed, real_fsync = [], os.fsync

    def fsync(fd):
        st = os.fstat(fd)
        if stat.S_ISDIR(st.st_mode):
            flushed.append(st.st_ino)
            if len(flushed) < 3:
                raise OSError(errno.EIO, f"flush {len(flushed)} failed")
        real_fsync(fd)

    monkeypatch.setattr(atomic.os, "fsync", fsync)
    with pytest.raises(gpmsa.GPMSAError, match=r"\(flush 1 failed\)") as info:
        with atomic_group() as stage:
            for folder in folders:
                with stage(folder / "f") as fh:
                    fh.write(b"new")
    assert sorted(flushed) == sorted(os.stat(f).st_ino for f in folders)
    assert str(info.value).startswith(f"{atomic._distinct_folders([f / 'f' for f in folders])[0]}:")
    assert [(f / "f").read_bytes() for f in folders] == [b"new"] * 3


def test_on_moved_runs_after_the_moves_before_the_flush_and_not_on_a_failed_write(
    tmp_path, monkeypatch
):
    events = _record_syncs(monkeypatch, [tmp_path / "x"])
    seen = []
    with atomic_group(on_moved=lambda: seen.append((tmp_path / "x").read_bytes())) as stage:
        with stage(tmp_path / "x") as fh:
            fh.write(b"1")
    assert seen == [b"1"] and [e[0] for e in events] == ["file", "folder"]
    seen.clear()
    with pytest.raises(RuntimeError):
        with atomic_group(on_moved=lambda: seen.append("moved")) as stage:
            with stage(tmp_path / "y") as fh:
                raise RuntimeError("writer failed")
    assert seen == [] and not (tmp_path / "y").exists()


def test_a_study_whose_folder_flush_fails_records_the_digest_of_its_new_files(
    tmp_path, monkeypatch
):
    # session 91: Study.save kept the old sha256 (None for a new study) while the new files
    # were in place
    from tests.gpmsa._study_cases import two_model_study

    with pytest.warns(gpmsa.ConvergenceWarning):  # (a short chain)
        study = two_model_study(n_samples=20, n_burn=10, tune_rounds=2)
    fail_fsync(monkeypatch, atomic)
    with pytest.raises(gpmsa.GPMSAError, match="could not be flushed to disk"):
        study.save(tmp_path / "run.gpmsa")
    monkeypatch.undo()
    assert study.sha256 is not None
    assert study.sha256 == gpmsa.load_study(tmp_path / "run.gpmsa").sha256
