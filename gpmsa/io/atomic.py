"""Replace a file in one step (or several files together): readers see the old file or the whole
new one, never a part."""

from __future__ import annotations

import errno
import hashlib
import os
import re
import secrets
import socket
import stat
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path
from typing import IO

from gpmsa.errors import GPMSAError


@contextmanager
def atomic_write(
    path: str | os.PathLike, *, text: bool = False, error: type[Exception] = GPMSAError
) -> Iterator[IO]:
    """Open a new temporary file beside ``path`` for writing (and reading back); on a clean exit
    flush it to disk, move it over ``path`` and flush the folder (`flush_folder`); on any
    exception remove it, leaving an existing ``path`` untouched.

    Args:
        path: the file to write (its folder must exist); an existing ``path`` that is not a
            regular file (a directory, device, FIFO) is refused.
        text: a text handle (UTF-8, newlines written as given) instead of a binary one.
        error: the exception type raised when the file cannot be written.

    Yields:
        the open handle, positioned at 0 (opened "w+", so a writer may check what it wrote).
        A new file gets the permissions of a newly created file (0o666 less the umask); a file
        replaced keeps its permissions, and a symbolic link is written through (its target is
        replaced, as ``open`` would write it; the link stays a link).

    The temporary file is named after ``path``, the process and its host (`_temporary_name`):
    one left by a save killed outright (SIGKILL, a power cut) is removed by a later process's
    first save into that folder on that host, once its process no longer runs
    (`remove_stale_temporaries`).
    """
    with atomic_group(error=error) as stage, stage(path, text=text) as fh:
        yield fh


@contextmanager
def atomic_group(
    *, error: type[Exception] = GPMSAError, on_moved: Callable[[], None] | None = None
) -> Iterator[Callable]:
    """Replace several files together: each is written whole to a temporary file first, and
    none is moved over its path until every one is written.

    Yields ``stage``: ``with stage(path, text=False) as fh:`` gives the handle of a new temporary
    file beside ``path`` (as ``atomic_write``'s), flushed to disk when its block ends. When the
    group's block ends without an exception the temporary files are moved over their paths in
    the order staged, then each folder is flushed to disk (`flush_folder`: a power cut after the
    save keeps the new files); on any exception (while writing any of them) every temporary file is
    removed and no path is touched. Only an OS failure during the final moves (each one step) can
    leave some paths replaced and others not. Where it can (`folder_lock`), a group of several files
    holds a lock on each folder during its moves (not their flush), so that two processes saving the
    same files at once leave one's files, all of them, not a mix of both, and a reader holding the
    folder's shared lock reads them all before the moves or after.

    An OS error while a file is written (a full disk, a quota, an I/O error), flushed to disk or
    moved (e.g. no permission) raises ``error`` naming the path (an I/O error flushing a
    folder after the moves: naming the folder), the OS error chained. ``on_moved`` (None:
    none) is called once every file is moved into place, before the folders are flushed: a
    caller that records what it saved (`Study.save`'s digest) does so even where the flush then
    fails, the new files being in place; the folders are flushed though ``on_moved`` raises
    (its error raised then, unless a flush fails: that error, ``on_moved``'s its context).
    """
    staged: list[tuple[Path, Path]] = []

    @contextmanager
    def stage(path: str | os.PathLike, *, text: bool = False) -> Iterator[IO]:
        if "\0" in os.fsdecode(path):
            raise error(f"{os.fsdecode(path)!r}: cannot write (a path holds no NUL byte)")
        path = Path(path)
        try:
            if path.is_symlink():  # write through the link, as open() would, not over it
                path = Path(os.path.realpath(path))
        except OSError as exc:  # e.g. a name longer than the file system allows
            raise error(_cannot_write(path, exc)) from exc
        tmp, fd = _new_temporary(path, error)
        staged.append((tmp, path))
        kw = {"encoding": "utf-8", "newline": ""} if text else {}
        fh = os.fdopen(fd, "w+" if text else "w+b", **kw)
        try:
            try:
                yield fh
            except OSError as exc:  # the writer's writes: the disk full, say (an error of its
                if exc.errno not in _WRITE_ERRNOS:  # own, e.g. a font it reads, stays as is)
                    raise
                raise error(_cannot_write(path, exc)) from exc
            try:
                fh.flush()
                os.fsync(fh.fileno())
            except OSError as exc:
                raise error(_cannot_write(path, exc)) from exc
        except BaseException:
            _close_quietly(fh)  # what it still buffers fails as the write did: the first error
            raise
        try:
            fh.close()
        except OSError as exc:
            raise error(_cannot_write(path, exc)) from exc

    try:
        yield stage
        folders = _distinct_folders([path for _, path in staged])
        with ExitStack() as locks:
            for folder in folders if len(staged) > 1 else []:
                locks.enter_context(folder_lock(folder, error))
            for tmp, path in staged:
                try:
                    os.replace(tmp, path)
                except OSError as exc:
                    raise error(_cannot_write(path, exc)) from exc
        try:  # (the files are in place: their folders are flushed though on_moved raises)
            if on_moved is not None:
                on_moved()
        finally:
            _flush_folders(folders, error)  # after the locks: a reader need not wait for the disk
    except BaseException:
        for tmp, _ in staged:
            try:
                os.unlink(tmp)
            except OSError:
                pass
        raise


def _distinct_folders(paths: list[Path]) -> list[Path]:
    """The folders of ``paths``, each once however it is named ("out" and "/home/me/out", or
    through a link: two locks on one folder from one process wait for each other), ordered by
    device and inode, the same for every process, so that two groups lock in one order. A
    folder that cannot be found is left out (`folder_lock` could not open it either)."""
    found: dict[tuple[int, int], Path] = {}
    for path in paths:
        try:
            st = os.stat(path.parent)
        except (OSError, ValueError):  # gone since it was staged: its move says so
            continue
        found.setdefault((st.st_dev, st.st_ino), path.parent)
    return [found[key] for key in sorted(found)]


def flush_folder(folder: str | os.PathLike, error: type[Exception]) -> None:
    """Flush ``folder``'s entries to disk (``fsync`` of the folder, POSIX): a file's bytes are
    flushed before its move, its new name in the folder only by this, so that a power cut just
    after a save keeps the new file rather than the old one (or, for a new path, none). Where the
    OS or file system cannot (Windows, a folder this process cannot open for reading, a file
    system that takes no ``fsync`` of a folder) nothing is done; an I/O error raises ``error``
    naming the folder (the files are in place, but the disk failed to store the move)."""
    if sys.platform == "win32":
        return
    try:
        fd = os.open(folder, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
    except OSError:  # e.g. a folder with write but not read permission
        return
    try:
        os.fsync(fd)
    except OSError as exc:
        if exc.errno not in _NO_FOLDER_FSYNC:
            raise error(
                f"{folder}: the files were moved into place, but the folder could not be "
                f"flushed to disk ({exc.strerror or exc}): a power cut could still undo the "
                "save; check the disk and save again"
            ) from exc
    finally:
        os.close(fd)


def _flush_folders(folders: list[Path], error: type[Exception]) -> None:
    """`flush_folder` each of ``folders``, every one even after one fails (its files are in
    place as the others' are); the first failure is raised then."""
    failure: Exception | None = None
    for folder in folders:
        try:
            flush_folder(folder, error)
        except error as exc:
            failure = failure or exc
    if failure is not None:
        raise failure


_NO_FOLDER_FSYNC = frozenset(
    getattr(errno, name)
    for name in ("EINVAL", "ENOTSUP", "EOPNOTSUPP", "EBADF")
    if hasattr(errno, name)
)
"""The errors of an ``fsync`` of a folder that mean the file system does not take one (not a
failure to store the move)."""


def _close_quietly(fh: IO) -> None:
    """Close ``fh`` (its descriptor always) after an error: the flush of what it still buffers
    may fail again (a full disk), and that error would replace the one being raised."""
    try:
        fh.close()
    except OSError:
        pass


_WRITE_ERRNOS = frozenset(
    getattr(errno, name) for name in ("ENOSPC", "EDQUOT", "EFBIG", "EIO") if hasattr(errno, name)
)
"""The OS errors a write to a file raises (no space, over the quota, too large, an I/O error)."""

LOCK_WAIT_S = 60.0
"""Seconds a group's moves wait for another process's moves into the same folder, or a
reader's read of a study there, to end (they take milliseconds): past that (a process stopped
midway), ``error`` names the folder."""


@contextmanager
def folder_lock(
    folder: str | os.PathLike, error: type[Exception] = GPMSAError, *, shared: bool = False
) -> Iterator[None]:
    """An advisory lock (``flock``) on ``folder`` while the block runs, where the OS and the file
    system give one (POSIX; not Windows, and on some network file systems not): elsewhere none,
    and the block runs as it would without it. ``shared=False``: exclusive, held by a group's
    moves (`atomic_group`); ``shared=True``: shared, held by a reader of several files that
    must match (``gpmsa.load_study``), so that it waits for a save's moves in progress and a save
    waits for its read. The lock is taken on the folder itself, opened for reading: a read-only
    folder is locked as any other (no lock file is made), and a folder that cannot be opened is
    not locked. A lock held by another process for ``LOCK_WAIT_S`` seconds raises ``error``
    naming the folder."""
    if sys.platform == "win32":
        yield
        return
    import fcntl

    try:
        fd = os.open(folder, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
    except OSError:  # a folder that cannot be opened: the moves or reads say why, if they fail
        yield
        return
    try:
        deadline = time.monotonic() + LOCK_WAIT_S
        while True:
            try:
                fcntl.flock(fd, (fcntl.LOCK_SH if shared else fcntl.LOCK_EX) | fcntl.LOCK_NB)
                break
            except BlockingIOError:  # another process is replacing or reading files there
                if time.monotonic() > deadline:
                    raise error(
                        f"{folder}: another process has held the folder's lock for "
                        f"{LOCK_WAIT_S:g} s (gpmsa.io.atomic.LOCK_WAIT_S) while "
                        f"{'replacing' if shared else 'reading or replacing'} files there; let it "
                        f"finish (or end it) and {'load' if shared else 'save'} again"
                    ) from None
                time.sleep(0.01)
            except OSError:  # no locks on this file system: go on without one
                break
        yield
    finally:
        os.close(fd)  # (releases the lock)


_STALE_RE = re.compile(r"\..+\.(\d{1,10})@([0-9a-f]{8})\.[0-9a-f]{12}\.part", re.DOTALL)
"""A temporary file's name (`_temporary_name`): the writer's process id and host."""


def _host_id() -> str:
    """8 hexadecimal digits naming this host and its process-id space: the host name, the
    machine id (``/etc/machine-id``, where there is one: two machines may share a host name) and,
    on Linux, the pid namespace (two containers that share a host name and a folder do not share
    process ids, and each must never take the other's live process for a dead one). Stable
    across a reboot outside containers, so that a temporary file left by a power cut is
    recognised as this host's (a restarted container's pid namespace is another: its leftovers
    stay). Two cloned machines sharing a folder must not share a machine id (systemd's rule)."""
    try:
        space = os.readlink("/proc/self/ns/pid")
    except OSError:  # not Linux: the host name alone (and the machine id, where there is one)
        space = ""
    try:  # two machines of one host name ("localhost") have their own
        with open("/etc/machine-id", "rb") as fh:
            machine = fh.read(64).strip()
    except OSError:
        machine = b""
    text = f"{socket.gethostname()}\0{space}\0".encode() + machine
    return hashlib.sha256(text).hexdigest()[:8]


def _temporary_name(path: Path) -> str:
    """The name of a new temporary file beside ``path``: hidden, the start of ``path``'s name (32
    characters at most: a 255-byte name plus the suffix would exceed the file system's limit),
    the writing process's id and host (`_host_id`), 12 random hexadecimal digits, ``.part``."""
    return f".{path.name[:32]}.{os.getpid()}@{_host_id()}.{secrets.token_hex(6)}.part"


def remove_stale_temporaries(folder: str | os.PathLike) -> list[Path]:
    """Remove the temporary files that saves into ``folder`` left there when killed outright
    (SIGKILL, a power cut: no ``finally`` ran): those named by `_temporary_name` (any target's)
    for a process of this host that no longer runs. A temporary of a running process (another
    save in progress, in this process or another), of another host or of a process that cannot
    be told (a reused process id: it runs) is never touched. Returns the paths removed; nothing
    on Windows (whose ``os.kill`` cannot ask whether a process runs) or where the folder cannot
    be listed."""
    folder = Path(folder)
    if sys.platform == "win32":
        return []
    host, removed = _host_id(), []
    try:
        names = [e.name for e in os.scandir(folder) if e.name.endswith(".part")]
    except (OSError, ValueError):
        return []
    for name in names:
        found = _STALE_RE.fullmatch(name)
        if found is None or found[2] != host or _runs(int(found[1])):
            continue
        try:
            os.unlink(folder / name)
            removed.append(folder / name)
        except OSError:  # gone meanwhile (another save removed it), or a folder of that name
            pass
    return removed


_SWEPT: set[str] = set()
"""The folders (absolute) this process has swept of stale temporaries (`_sweep_once`); a forked
child starts with none (a worker forked after its parent's sweep sweeps again: a temporary left
by another worker killed since is removed by the next one's first save). At most
`_SWEPT_FOLDERS` of them."""
if hasattr(os, "register_at_fork"):  # POSIX
    os.register_at_fork(after_in_child=_SWEPT.clear)

_SWEPT_FOLDERS = 1024
"""The folders `_SWEPT` holds at most: a process that saves into ever new folders (a service's
folder per job) would otherwise keep a name for each for good (~90 B a save). Past it the
record starts afresh (one step, safe beside another thread's save), and a folder saved into
again is swept once more: one more listing of it each time the record starts afresh (a process
that cycles over more than ``_SWEPT_FOLDERS`` folders lists about every folder it saves into,
as before the record was kept)."""


def _sweep_once(folder: Path) -> None:
    """`remove_stale_temporaries` of ``folder`` at this process's first save there: one listing a
    folder and process, not one a save (a campaign cache of 10,000 files took 5.5 ms a save to
    list), and a killed save's temporary is removed whatever target the next save has (again
    once `_SWEPT` has started afresh, `_SWEPT_FOLDERS`)."""
    key = os.path.abspath(folder)
    if key not in _SWEPT:
        if len(_SWEPT) >= _SWEPT_FOLDERS:
            _SWEPT.clear()
        _SWEPT.add(key)
        remove_stale_temporaries(folder)


def _runs(pid: int) -> bool:
    """Whether a process ``pid`` runs on this host (one of another user's too; a zombie, not
    yet waited for, counts as running)."""
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (OSError, OverflowError):  # another user's (EPERM), or not a process id at all
        return True
    return True


def _new_temporary(path: Path, error: type[Exception]) -> tuple[Path, int]:
    """A new empty file beside ``path`` (created exclusively) and its open descriptor; ``error``
    when ``path`` exists and is not a regular file, or the folder cannot be written."""
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        mode = None
    except (OSError, ValueError) as exc:  # ValueError: a name the file system cannot encode
        raise error(_cannot_write(path, exc)) from exc
    if mode is not None and not stat.S_ISREG(mode):
        raise error(f"{path} exists and is not a regular file: refusing to replace it")
    _sweep_once(path.parent)
    tmp = path.with_name(_temporary_name(path))
    flags = os.O_RDWR | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0)
    try:
        fd = os.open(tmp, flags, 0o666)
    except OSError as exc:  # e.g. a missing folder or one without write permission
        raise error(_cannot_write(path, exc) + _folder_remedy(path, exc)) from exc
    if mode is not None:  # a file replaced keeps its permissions (a private one stays so)
        try:
            os.chmod(tmp, stat.S_IMODE(mode))
        except OSError as exc:  # e.g. a file system without permissions: nothing left behind
            os.close(fd)
            os.unlink(tmp)
            raise error(_cannot_write(path, exc)) from exc
    return tmp, fd


def _folder_remedy(path: Path, exc: OSError) -> str:
    """What to do where a new file cannot be made in ``path``'s folder (``exc``): make a
    missing folder (a save makes none), or save to a folder that can be written."""
    folder = path.parent
    if exc.errno == errno.ENOENT and not os.path.isdir(folder):
        return f": the folder {folder} does not exist; make it first or save elsewhere"
    if exc.errno in (errno.EACCES, errno.EPERM, errno.EROFS):
        return f": the folder {folder} cannot be written; save elsewhere"
    return ""


def _cannot_write(path: Path, exc: OSError | ValueError) -> str:
    """Why ``path`` cannot be written, from the OS error ``exc``; a name or path too long says
    how long it is and what the file system allows, a name the file system's encoding cannot
    write (a lone surrogate such as "\\ud800": UnicodeEncodeError) which character."""
    if isinstance(exc, UnicodeEncodeError):
        bad = exc.object[exc.start : exc.end]
        return (
            f"{path}: cannot write (the path holds {bad!r}, which the file system's encoding, "
            f"{exc.encoding}, cannot write)"
        )
    why = getattr(exc, "strerror", None) or str(exc)
    if getattr(exc, "errno", None) == errno.ENAMETOOLONG:  # a ValueError has none
        name = len(os.fsencode(path.name))
        try:
            most = os.pathconf(path.parent, "PC_NAME_MAX")
        except (OSError, ValueError, AttributeError):  # no pathconf (Windows), or no folder
            most = 255
        if name > most:
            why += f": the file name is {name} bytes, the file system allows at most {most}"
        else:
            why += f": the path is {len(os.fsencode(path))} bytes, too long for the OS"
    return f"{path}: cannot write ({why})"
