"""gpmsa.io.atomic, mutation testing (s89): exact checks of the lock's deadline, the folders a
group locks, the OS-failure paths (a full disk, a refused move, an interrupt) and the messages
that name what cannot be written."""

import errno
import os
import stat
from pathlib import Path

import pytest

import gpmsa
from gpmsa.io import atomic
from gpmsa.io.atomic import atomic_group, atomic_write, folder_lock

fcntl = pytest.importorskip("fcntl")


def test_a_group_naming_one_folder_two_ways_does_not_lock_itself_out(tmp_path, monkeypatch):
    """A group staging ``a`` (relative) and ``<folder>/b`` (absolute) in one folder took two
    locks on it, the second waiting for the first for LOCK_WAIT_S and then blaming "another
    process"; the folder is locked once."""
    monkeypatch.setattr(atomic, "LOCK_WAIT_S", 0.2)
    monkeypatch.chdir(tmp_path)
    with atomic_group() as stage:
        with stage(Path("a")) as fh:
            fh.write(b"new a")
        with stage(tmp_path / "b") as fh:
            fh.write(b"new b")
    assert (tmp_path / "a").read_bytes() == b"new a"
    assert (tmp_path / "b").read_bytes() == b"new b"
    assert sorted(os.listdir(tmp_path)) == ["a", "b"]


def test_a_folder_locked_elsewhere_is_waited_for_exactly_lock_wait_s(tmp_path, monkeypatch):
    """The deadline is LOCK_WAIT_S (60 s) after the first try: at 60.0 s it waits on, past it
    the caller's error names the folder and the wait."""
    other = os.open(tmp_path, os.O_RDONLY)
    fcntl.flock(other, fcntl.LOCK_EX)
    clock = iter([0.0, 60.0, 60.5, 1e9])
    sleeps = []
    monkeypatch.setattr(atomic.time, "monotonic", lambda: next(clock))
    monkeypatch.setattr(atomic.time, "sleep", sleeps.append)
    try:
        with pytest.raises(gpmsa.GPMSAError) as info, folder_lock(tmp_path):
            pass
    finally:
        os.close(other)
    assert sleeps == [0.01]
    assert str(info.value) == (
        f"{tmp_path}: another process has held the folder's lock for 60 s "
        "(gpmsa.io.atomic.LOCK_WAIT_S) while reading or replacing files there; let it finish "
        "(or end it) and save again"
    )
    assert atomic.LOCK_WAIT_S == 60.0


def test_a_shared_lock_admits_readers_and_an_exclusive_one_none(tmp_path):
    """``shared=True`` takes a shared flock (another reader's shared lock is granted, a save's
    exclusive one refused), ``shared=False`` an exclusive one (both refused); the lock ends
    with the block."""
    other = os.open(tmp_path, os.O_RDONLY)
    try:
        with folder_lock(tmp_path, shared=True):
            fcntl.flock(other, fcntl.LOCK_SH | fcntl.LOCK_NB)
            fcntl.flock(other, fcntl.LOCK_UN)
            with pytest.raises(BlockingIOError):
                fcntl.flock(other, fcntl.LOCK_EX | fcntl.LOCK_NB)
        with folder_lock(tmp_path):
            with pytest.raises(BlockingIOError):
                fcntl.flock(other, fcntl.LOCK_SH | fcntl.LOCK_NB)
        fcntl.flock(other, fcntl.LOCK_EX | fcntl.LOCK_NB)  # released
    finally:
        os.close(other)


def test_a_reader_waiting_past_the_deadline_is_told_to_load_again(tmp_path, monkeypatch):
    other = os.open(tmp_path, os.O_RDONLY)
    fcntl.flock(other, fcntl.LOCK_EX)
    clock = iter([100.0, 161.0])
    monkeypatch.setattr(atomic.time, "monotonic", lambda: next(clock))
    try:
        with pytest.raises(KeyError) as info, folder_lock(tmp_path, KeyError, shared=True):
            pass
    finally:
        os.close(other)
    assert info.value.args[0] == (
        f"{tmp_path}: another process has held the folder's lock for 60 s "
        "(gpmsa.io.atomic.LOCK_WAIT_S) while replacing files there; let it finish "
        "(or end it) and load again"
    )


def test_a_single_file_takes_no_folder_lock(tmp_path, monkeypatch):
    """Only a group of several files locks its folder: one file is replaced in one step, and a
    reader holding the folder's lock does not hold it up."""
    monkeypatch.setattr(atomic, "LOCK_WAIT_S", 0.0)
    other = os.open(tmp_path, os.O_RDONLY)
    fcntl.flock(other, fcntl.LOCK_EX)
    try:
        with atomic_write(tmp_path / "f") as fh:
            fh.write(b"x")
        with atomic_group() as stage, stage(tmp_path / "g") as fh:
            fh.write(b"y")
    finally:
        os.close(other)
    assert (tmp_path / "f").read_bytes() == b"x" and (tmp_path / "g").read_bytes() == b"y"


def test_the_handle_is_closed_after_a_save_and_after_a_failed_one(tmp_path):
    with atomic_write(tmp_path / "f") as fh:
        fh.write(b"x")
    assert fh.closed
    with pytest.raises(ZeroDivisionError), atomic_write(tmp_path / "g", text=True) as fh:
        fh.write("y")
        raise ZeroDivisionError
    assert fh.closed
    assert os.listdir(tmp_path) == ["f"]


def test_a_stale_temporary_of_a_dead_process_is_removed_and_returned(tmp_path):
    import subprocess
    import sys

    child = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                           capture_output=True, text=True, check=True)  # fmt: skip
    dead = int(child.stdout)
    host = atomic._host_id()
    stale = f".run.gpmsa.{dead}@{host}.0123456789ab.part"
    live = f".run.gpmsa.{os.getpid()}@{host}.0123456789ab.part"
    foreign = f".run.gpmsa.{dead}@{'0' * 8 if host != '0' * 8 else '1' * 8}.0123456789ab.part"
    for name in (stale, live, foreign, "x.part"):
        (tmp_path / name).write_bytes(b"")
    assert atomic.remove_stale_temporaries(tmp_path) == [tmp_path / stale]
    assert sorted(os.listdir(tmp_path)) == sorted([live, foreign, "x.part"])
    assert atomic.remove_stale_temporaries(tmp_path / "missing") == []


def test_whether_a_process_runs_asks_without_signalling_it():
    import subprocess
    import sys

    child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    sent = []
    real_kill = os.kill
    try:
        with pytest.MonkeyPatch.context() as mp:
            mp.setattr(
                atomic.os, "kill", lambda pid, sig: (sent.append((pid, sig)), real_kill(pid, sig))
            )
            assert atomic._runs(child.pid) is True
        assert sent == [(child.pid, 0)]  # asked with signal 0, not signalled
    finally:
        child.kill()
        child.wait()
    assert atomic._runs(child.pid) is False  # waited for: gone
    assert atomic._runs(os.getpid()) is True
    assert atomic._runs(2**40) is True  # not a process id: never taken for a dead one


@pytest.mark.parametrize(("held", "after"), [(1023, 1024), (1024, 1)])
def test_the_swept_record_starts_afresh_at_1024_folders(tmp_path, monkeypatch, held, after):
    swept = {f"/elsewhere/{k}" for k in range(held)}
    monkeypatch.setattr(atomic, "_SWEPT", swept)
    atomic._sweep_once(tmp_path)
    assert len(swept) == after and os.path.abspath(tmp_path) in swept
    assert atomic._SWEPT_FOLDERS == 1024


@pytest.mark.parametrize(
    ("code", "folder_exists", "remedy"),
    [
        (errno.ENOENT, False, ": the folder {f} does not exist; make it first or save elsewhere"),
        (errno.ENOENT, True, ""),
        (errno.EACCES, True, ": the folder {f} cannot be written; save elsewhere"),
        (errno.EPERM, True, ": the folder {f} cannot be written; save elsewhere"),
        (errno.EROFS, True, ": the folder {f} cannot be written; save elsewhere"),
        (errno.EACCES, False, ": the folder {f} cannot be written; save elsewhere"),
        (errno.EIO, True, ""),
    ],
)
def test_the_remedy_for_a_folder_a_file_cannot_be_made_in(tmp_path, code, folder_exists, remedy):
    folder = tmp_path if folder_exists else tmp_path / "missing"
    exc = OSError(code, os.strerror(code))
    assert atomic._folder_remedy(folder / "f", exc) == remedy.format(f=folder)


def test_a_folder_that_refuses_a_new_file_is_named_with_its_remedy(tmp_path, monkeypatch):
    real_open = os.open

    def refuse(path, *args, **kwargs):
        if os.fspath(path).endswith(".part"):
            raise PermissionError(errno.EACCES, os.strerror(errno.EACCES))
        return real_open(path, *args, **kwargs)

    monkeypatch.setattr(atomic.os, "open", refuse)
    with pytest.raises(gpmsa.GPMSAError) as info, atomic_write(tmp_path / "f"):
        pass
    assert str(info.value) == (
        f"{tmp_path / 'f'}: cannot write (Permission denied): the folder {tmp_path} cannot be "
        "written; save elsewhere"
    )
    monkeypatch.undo()
    assert os.listdir(tmp_path) == []


def test_the_data_is_flushed_before_the_file_is_synced(tmp_path, monkeypatch):
    sizes = []
    real_fsync = os.fsync

    def fsync(fd):
        st = os.fstat(fd)
        if stat.S_ISREG(st.st_mode):  # (the folder is synced after the move: s90's tests)
            sizes.append(st.st_size)
        real_fsync(fd)

    monkeypatch.setattr(atomic.os, "fsync", fsync)
    with atomic_write(tmp_path / "f") as fh:
        fh.write(b"0123456789")
    assert sizes == [10]


class _FailingClose:
    """A file whose close reports a write error (as NFS may, at close)."""

    def __init__(self, fh):
        self._fh = fh

    def __getattr__(self, name):
        return getattr(self._fh, name)

    def close(self):
        self._fh.close()
        raise OSError(errno.EIO, os.strerror(errno.EIO))


def test_an_error_at_close_names_the_file_and_leaves_the_old_one(tmp_path, monkeypatch):
    path = tmp_path / "f"
    path.write_bytes(b"old")
    real_fdopen = os.fdopen
    monkeypatch.setattr(atomic.os, "fdopen", lambda *a, **k: _FailingClose(real_fdopen(*a, **k)))
    with pytest.raises(gpmsa.GPMSAError) as info, atomic_write(path) as fh:
        fh.write(b"new")
    assert str(info.value) == f"{path}: cannot write (Input/output error)"
    assert isinstance(info.value.__cause__, OSError)
    monkeypatch.undo()
    assert path.read_bytes() == b"old" and os.listdir(tmp_path) == ["f"]


@pytest.mark.parametrize("length", [255, 256])
def test_a_name_too_long_says_which_limit(tmp_path, length):
    """At the file system's 255-byte limit the name is allowed: the path is what is too long."""
    path = tmp_path / ("a" * length)
    exc = OSError(errno.ENAMETOOLONG, os.strerror(errno.ENAMETOOLONG))
    most = os.pathconf(tmp_path, "PC_NAME_MAX")
    assert most == 255
    why = (
        f"the path is {len(os.fsencode(path))} bytes, too long for the OS"
        if length == 255
        else "the file name is 256 bytes, the file system allows at most 255"
    )
    assert atomic._cannot_write(path, exc) == f"{path}: cannot write (File name too long: {why})"
    missing = tmp_path / "missing" / ("b" * 256)  # no folder to ask: 255 taken
    assert atomic._cannot_write(missing, exc) == (
        f"{missing}: cannot write (File name too long: the file name is 256 bytes, the file "
        "system allows at most 255)"
    )


def test_a_file_given_as_the_folder_is_not_locked(tmp_path):
    """``folder_lock`` opens a folder only (O_DIRECTORY): a file of that name is not locked."""
    file = tmp_path / "f"
    file.write_bytes(b"")
    other = os.open(file, os.O_RDONLY)
    try:
        with folder_lock(file):
            fcntl.flock(other, fcntl.LOCK_EX | fcntl.LOCK_NB)
    finally:
        os.close(other)


def test_the_folders_of_a_group_are_locked_once_each_in_one_order(tmp_path, monkeypatch):
    """However the caller names them, the folders are ordered by device and inode (the same in
    every process, so that two groups never lock them in opposite orders)."""
    (tmp_path / "x").mkdir()
    (tmp_path / "y").mkdir()
    monkeypatch.chdir(tmp_path)
    inode = {os.stat(tmp_path / n).st_ino: n for n in ("x", "y")}
    order = [inode[k] for k in sorted(inode)]
    for paths in (
        [Path("x/f"), tmp_path / "y" / "g", tmp_path / "x" / "h"],
        [Path("y/g"), tmp_path / "x" / "f", Path("y") / "h"],
    ):
        folders = atomic._distinct_folders(paths)
        assert [f.name for f in folders] == order
    assert atomic._distinct_folders([tmp_path / "gone" / "f", Path("x/f")]) == [Path("x")]


def test_a_refused_chmod_leaves_no_temporary_and_no_open_descriptor(tmp_path, monkeypatch):
    """Replacing a file copies its permissions to the temporary; where the file system refuses
    (EPERM), the temporary is closed and removed and the error names the file."""
    if not os.path.isdir("/proc/self/fd"):
        pytest.skip("needs /proc/self/fd")
    path = tmp_path / "f"
    path.write_bytes(b"old")
    os.chmod(path, 0o640)

    def refuse(*args, **kwargs):
        raise PermissionError(errno.EPERM, os.strerror(errno.EPERM))

    monkeypatch.setattr(atomic.os, "chmod", refuse)
    before = len(os.listdir("/proc/self/fd"))
    with pytest.raises(gpmsa.GPMSAError) as info, atomic_write(path):
        pass
    assert len(os.listdir("/proc/self/fd")) == before
    assert str(info.value) == f"{path}: cannot write (Operation not permitted)"
    monkeypatch.undo()
    assert path.read_bytes() == b"old" and os.listdir(tmp_path) == ["f"]
    assert stat.S_IMODE(os.stat(path).st_mode) == 0o640


def test_on_windows_no_folder_is_locked_and_no_temporary_swept(tmp_path, monkeypatch):
    """Windows has no flock, and its ``os.kill`` cannot ask whether a process runs."""
    monkeypatch.setattr(atomic.sys, "platform", "win32")
    stale = tmp_path / f".f.{2**31 - 1}@{atomic._host_id()}.0123456789ab.part"
    stale.write_bytes(b"")
    other = os.open(tmp_path, os.O_RDONLY)
    fcntl.flock(other, fcntl.LOCK_EX)
    try:
        with folder_lock(tmp_path):
            entered = True
    finally:
        os.close(other)
    assert entered
    assert atomic.remove_stale_temporaries(tmp_path) == []
    assert stale.exists()


class _File:
    def __init__(self, data):
        self.data = data
        self.asked = []

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False

    def read(self, n):
        self.asked.append(n)
        return self.data[:n]


@pytest.mark.parametrize(("space", "machine"), [("pid:[4026531836]", b"m" * 70), (None, None)])
def test_the_host_id_hashes_host_name_pid_space_and_machine_id(monkeypatch, space, machine):
    """sha256 of "<host name>\\0<pid namespace>\\0<first 64 bytes of /etc/machine-id>", its first
    8 hexadecimal digits; where Linux's namespace or the machine id cannot be read, empty."""
    import hashlib

    def readlink(path):
        assert path == "/proc/self/ns/pid"
        if space is None:
            raise OSError(errno.ENOENT, "no /proc")
        return space

    file = _File(machine)

    def fake_open(path, mode):
        assert (path, mode) == ("/etc/machine-id", "rb")
        if machine is None:
            raise FileNotFoundError(errno.ENOENT, "no machine id")
        return file

    monkeypatch.setattr(atomic.socket, "gethostname", lambda: "host")
    monkeypatch.setattr(atomic.os, "readlink", readlink)
    monkeypatch.setattr(atomic, "open", fake_open, raising=False)
    text = b"host\0" + (space or "").encode() + b"\0" + (machine or b"")[:64]
    assert atomic._host_id() == hashlib.sha256(text).hexdigest()[:8]
    assert file.asked == ([] if machine is None else [64])
