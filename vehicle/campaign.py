"""The training campaign: one fresh road and one drive per design point, f per run.

f is the variance of the front-axle vertical acceleration normalised by T (``np.var``, ddof=0),
the paper's eq. 5, computed over two spans of each drive:

* ``f_full``: every sample after the start-up transient, i.e. once the rear axle has passed the
  road's lead-in taper (front-axle position >= lead_in_m + wheelbase), up to the road's end;
* ``f_window``: the last ``window`` (1,000) samples of the drive, i.e. the window that ends when
  the front axle reaches the road's end (as far from the start as possible);

each noise-free and with N(0, noise_std^2) accelerometer noise (``*_noisy``). With ``keep_s > 0``
the campaign also keeps the last ``keep_s`` seconds of each drive's accelerations (``accel`` and
``accel_measured``), lengthening each road so that they follow the start-up span: training data
for features of many short blocks per run.
"""

from __future__ import annotations

import errno
import functools
import hashlib
import json
import math
import multiprocessing
import multiprocessing.connection
import os
import queue
import re
import secrets
import select
import signal
import socket
import stat
import sys
import tempfile
import threading
import time
import tokenize
import zipfile
import zlib
from collections import Counter
from collections.abc import Callable
from concurrent.futures import BrokenExecutor, Executor, Future, ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import roadgen
from roadgen.errors import bound_text, distinct_texts
from vehicle import checks, kinematics
from vehicle.design import check_design, lhs_design
from vehicle.errors import CampaignFileError, SimulationDivergedError, VehicleError
from vehicle.linear import warn_if_step_too_coarse
from vehicle.models import Jackal, Model, check_model
from vehicle.sensor import check_noise, check_rate
from vehicle.simulate import SUBSTEPS, _simulate

FORMAT = "vehicle.campaign/1"
_F_NAMES = ("f_full", "f_window", "f_full_noisy", "f_window_noisy")
_ARRAYS = ("v", "gd", "seed", *_F_NAMES, "status")
_TRACES = ("accel", "accel_measured")
_MEMBERS = frozenset(f"{name}.npy" for name in (*_ARRAYS, "settings", *_TRACES))
"""The members a campaign file may hold."""
_MAX_DEFLATE_RATIO = 1032
"""Most bytes that one deflated byte expands to: what a compressed member can hold."""
_READ_ERRORS = (
    OSError, EOFError, ValueError, KeyError, RuntimeError, NotImplementedError,
    zipfile.BadZipFile, zlib.error, SyntaxError, tokenize.TokenError,
)  # fmt: skip
"""What reading a damaged or hostile ``.npz`` raises (zipfile: RuntimeError for an encrypted
member, NotImplementedError for an unknown method; zlib; numpy's .npy parser: ValueError, and
tokenize's TokenError for a header with an unclosed bracket or string or SyntaxError for a dtype
such as ',f8', raised as it parses a header before zipfile has checked the member's CRC: one
flipped bit of a large member's header)."""


@dataclass(frozen=True)
class RunSpec:
    """Everything one run needs (picklable, so any Executor can ship it)."""

    model: Model
    v: float
    gd: float
    seed: int
    road_length_m: float
    dx_m: float
    lead_in_m: float
    band: tuple[float, float] | None
    rate_hz: float
    noise_std: float
    window: int
    substeps: int
    keep_samples: int = 0

    def key(self) -> str:
        """Hash of the run's settings and of the code that computes it (``code_fingerprint``):
        its cache file name."""
        text = json.dumps(
            {**_spec_settings(self), "v": self.v, "gd": self.gd, "seed": self.seed,
             "code": code_fingerprint()},
            sort_keys=True,
        )  # fmt: skip
        return hashlib.sha256(text.encode()).hexdigest()[:32]


@dataclass(frozen=True, eq=False)
class Campaign:
    """The campaign's table; arrays (n,) in design order.

    v: speed, m/s. gd: GD, 1e-6 m^3. seed: the run's road seed, int64 in [0, 2**63) (its noise
    seed is [seed, 1]; ``run_campaign`` draws them in [0, 2**32), as
    ``SeedSequence(seed).generate_state(n)``). f_full, f_window, f_full_noisy, f_window_noisy:
    (m/s^2)^2, finite where the status is "ok", NaN for a failed run (see the module docstring
    for the spans). status: "ok" or the failure message. settings: dict of the campaign's
    settings (model description, road, sensor, window, solver, seed). accel, accel_measured:
    (n, keep) the last ``keep_s`` seconds of each drive's noise-free and measured front-axle
    accelerations, m/s^2 (NaN rows for failed runs); None unless kept.
    """

    v: np.ndarray
    gd: np.ndarray
    seed: np.ndarray
    f_full: np.ndarray
    f_window: np.ndarray
    f_full_noisy: np.ndarray
    f_window_noisy: np.ndarray
    status: np.ndarray
    settings: dict
    accel: np.ndarray | None = None
    accel_measured: np.ndarray | None = None

    def __post_init__(self) -> None:
        """Check the table (VehicleError naming the field) and hold its arrays as numpy arrays
        (float v, gd, f and traces; int64 seed; str status), so that what is saved can be read."""
        for name, array in _checked_table(self).items():
            object.__setattr__(self, name, array)

    @property
    def ok(self) -> np.ndarray:
        """Boolean mask (n,) of the runs that finished."""
        return self.status == "ok"

    def save(self, path: str | os.PathLike) -> None:
        """Write a plain ``.npz`` (no pickle): the arrays and the settings as JSON. The table is
        checked again first (its arrays may have been changed in place since construction);
        VehicleError if it is invalid or ``path`` names no file. A campaign file (or an empty
        file) at ``path`` is replaced in one step, keeping its permissions (a refusal or a
        failure leaves it whole); a symbolic link at ``path`` is written through (the file it
        leads to is replaced, as ``open`` and gpmsa's ``atomic_write`` do), not replaced.
        CampaignFileError if it cannot be written, or if ``path`` (or the link's target) holds
        anything else (another program's file, a folder), which is never replaced."""
        _check_path(path)
        target = roadgen.checks.home_path(path)  # ~: the home folder
        if target.name in ("", ".."):
            raise VehicleError(f"path={str(path)!r} names no file: need a file name, e.g. 'c.npz'")
        target = _through_link(target)
        _refuse_to_replace(target)
        table = _checked_table(self)
        arrays = {name: table[name] for name in _ARRAYS}
        arrays["settings"] = np.asarray(json.dumps({"format": FORMAT, **self.settings}))
        if table["accel"] is not None:
            arrays.update({name: table[name] for name in _TRACES})
        try:
            _save_npz(target, arrays)
        except OSError as exc:
            why = str(exc)  # the temporary file's name in it says little: name the folder
            if isinstance(exc, FileNotFoundError) and not os.path.isdir(target.parent):
                why = f"the folder {str(target.parent)!r} does not exist; make it or save elsewhere"
            raise CampaignFileError(f"cannot write campaign file {str(path)!r}: {why}") from exc


def load_campaign(path: str | os.PathLike) -> Campaign:
    """Read a file written by ``Campaign.save``; CampaignFileError if missing, not a regular
    file, damaged or invalid, VehicleError if ``path`` is not a path."""
    _check_path(path)
    arrays = _read_npz(roadgen.checks.home_path(path), (*_ARRAYS, "settings"), _TRACES)
    settings = arrays.pop("settings")
    if settings.dtype.kind != "U" or settings.ndim != 0:
        raise CampaignFileError(
            f"campaign file {str(path)!r}: settings must be one JSON string, got a "
            f"{settings.dtype} array of shape {settings.shape}"
        )
    try:
        settings = json.loads(str(settings))
    except (ValueError, RecursionError) as exc:  # also an integer beyond str/int's digit limit
        raise CampaignFileError(
            f"campaign file {str(path)!r}: settings are not JSON that Python reads (or nested "
            f"too deep): {exc}"
        ) from exc
    if not isinstance(settings, dict) or settings.pop("format", None) != FORMAT:
        raise CampaignFileError(f"campaign file {str(path)!r}: unknown format, need {FORMAT!r}")
    keep_s = settings.get("keep_s", 0.0)
    if isinstance(keep_s, int | float) and keep_s > 0 and "accel" not in arrays:
        shown = f"{keep_s:g}" if keep_s <= sys.float_info.max else "more than 1.8e308"
        raise CampaignFileError(
            f"campaign file {str(path)!r} is damaged: its settings keep {shown} s of traces "
            "per run, but it holds no traces"
        )
    try:
        return Campaign(**arrays, settings=settings)
    except VehicleError as exc:
        raise CampaignFileError(
            f"campaign file {str(path)!r} is not a valid campaign: {exc}"
        ) from exc


def _read_npz(
    path: Path, names: tuple[str, ...], optional: tuple[str, ...] = ()
) -> dict[str, np.ndarray]:
    """The arrays ``names`` and those of ``optional`` that are present in the ``.npz`` file at
    ``path``, read without pickle; CampaignFileError naming the problem if the file is missing,
    not a regular file (a FIFO would block), or damaged (each member's size is checked against
    what its bytes can hold before any array is allocated)."""
    try:
        info = os.stat(path)
    except FileNotFoundError as exc:
        raise CampaignFileError(f"campaign file {str(path)!r} does not exist") from exc
    except (OSError, ValueError) as exc:
        raise CampaignFileError(f"cannot read campaign file {str(path)!r}: {exc}") from exc
    if not stat.S_ISREG(info.st_mode):
        raise CampaignFileError(f"campaign file {str(path)!r} is not a regular file")
    try:
        with zipfile.ZipFile(path) as zf:
            listed = zf.namelist()
            twice = sorted(n for n, k in Counter(listed).items() if k > 1)
            if twice:  # zipfile would read the last of them, another reader the first
                raise ValueError(f"it holds the member {twice[0]!r} more than once")
            present = {n.removesuffix(".npy") for n in listed}
            wanted = (*names, *(n for n in optional if n in present))
            return {name: _read_member(zf, name, info.st_size) for name in wanted}
    except _READ_ERRORS as exc:
        raise CampaignFileError(
            f"campaign file {str(path)!r} is damaged or not a campaign: {exc}"
        ) from exc


def _read_member(zf: zipfile.ZipFile, name: str, file_bytes: int) -> np.ndarray:
    """The array of member ``name``.npy; ValueError unless it is a plain .npy (version 1 or 2,
    no objects) whose declared size fits in its bytes (``file_bytes``: the whole file's size)."""
    member = zf.getinfo(f"{name}.npy")
    if member.compress_type not in (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED):
        raise ValueError(f"member {name}.npy is compressed with method {member.compress_type}")
    ratio = 1 if member.compress_type == zipfile.ZIP_STORED else _MAX_DEFLATE_RATIO
    capacity = min(member.file_size, ratio * min(member.compress_size, file_bytes))
    with zf.open(member) as fh:
        version = np.lib.format.read_magic(fh)
        if version not in ((1, 0), (2, 0)):
            raise ValueError(f"member {name}.npy has .npy version {version}: need 1.0 or 2.0")
        read_header = getattr(np.lib.format, f"read_array_header_{version[0]}_0")
        shape, _, dtype = read_header(fh)
        nbytes = math.prod(shape) * max(dtype.itemsize, 1)  # an element takes >= 1 byte
        if dtype.hasobject:
            raise ValueError(f"member {name}.npy holds Python objects (dtype {dtype}): no pickle")
        if nbytes > capacity:
            raise ValueError(
                f"member {name}.npy declares a {dtype} array of shape {shape} ({nbytes} bytes), "
                f"more than its {capacity} bytes in the file can hold"
            )
        fh.seek(0)
        array = np.lib.format.read_array(fh, allow_pickle=False)
        if fh.read(1):  # reading to the end also checks the member's CRC
            raise ValueError(f"member {name}.npy has data after its array")
    return array


def _checked_table(c: Campaign) -> dict[str, np.ndarray | None]:
    """The campaign's arrays, checked and converted (see ``Campaign.__post_init__``)."""
    out: dict[str, np.ndarray | None] = {}
    for name in ("v", "gd", *_F_NAMES):
        out[name] = checks.real_array(f"Campaign.{name}", getattr(c, name))
    try:
        seed = np.asarray(c.seed)  # (copied below, as int64)
        status = np.array(c.status)  # a copy: the caller's array may change later
    except (TypeError, ValueError) as exc:
        raise VehicleError(f"Campaign.seed and .status must be arrays: {exc}") from exc
    if seed.size == 0 and status.size == 0:  # an empty table: any dtype will do
        seed, status = seed.astype(np.int64), status.astype(str)
    if seed.dtype.kind in "fO" and not isinstance(c.seed, np.ndarray):
        # integers beyond int64 in a list: numpy holds them as floats or objects
        items = np.asarray(c.seed, dtype=object)
        seed = items if all(map(_is_integer, items.flat)) else seed
    if not (
        seed.dtype.kind in "iu" or (seed.dtype.kind == "O" and all(map(_is_integer, seed.flat)))
    ):
        raise VehicleError(f"Campaign.seed must hold integers, got dtype {seed.dtype}")
    if status.dtype.kind != "U":
        raise VehicleError(f"Campaign.status must hold strings, got dtype {status.dtype}")
    out["seed"], out["status"] = seed, status
    n = out["v"].shape
    if len(n) != 1 or any(out[k].shape != n for k in _ARRAYS):
        shapes = {k: out[k].shape for k in _ARRAYS}
        raise VehicleError(f"Campaign arrays must be 1-D of one length, got shapes {shapes}")
    beyond = np.asarray((seed < 0) | (seed > np.iinfo(np.int64).max), dtype=bool)
    if np.any(beyond):
        i = int(np.argmax(beyond))
        raise VehicleError(
            f"Campaign.seed[{i}]={int(seed[i])} is out of range: allowed integers in [0, 2**63) "
            "(the int64 column; run_campaign's seeds lie in [0, 2**32))"
        )
    out["seed"] = seed.astype(np.int64)
    for name in ("v", "gd"):
        if not np.all(np.isfinite(out[name]) & (out[name] > 0)):
            raise VehicleError(f"Campaign.{name} must be finite and > 0 in every run")
    for name in _F_NAMES:
        if np.any(out[name] < 0) or np.any(np.isinf(out[name])):
            raise VehicleError(f"Campaign.{name} must be >= 0 and finite, or NaN for a failed run")
        unfinished = np.isnan(out[name]) & (status == "ok")
        if np.any(unfinished):
            i = int(np.argmax(unfinished))
            raise VehicleError(f"Campaign.{name}[{i}] is NaN but status[{i}] is 'ok'")
    if not isinstance(c.settings, dict) or "format" in c.settings:
        raise VehicleError("Campaign.settings must be a dict without the key 'format' (the file's)")
    try:
        json.dumps(c.settings)
    except (TypeError, ValueError, RecursionError) as exc:
        raise VehicleError(f"Campaign.settings must be JSON-able: {exc}") from exc
    if (c.accel is None) != (c.accel_measured is None):
        raise VehicleError("Campaign.accel and .accel_measured are both given or both None")
    for name in ("accel", "accel_measured"):
        out[name] = (
            None if c.accel is None else checks.real_array(f"Campaign.{name}", getattr(c, name))
        )
    if c.accel is not None and not (
        out["accel"].ndim == 2 and out["accel"].shape[0] == n[0]
        and out["accel"].shape == out["accel_measured"].shape
    ):  # fmt: skip
        raise VehicleError(
            f"Campaign.accel and .accel_measured must be ({n[0]}, samples) arrays of one shape, "
            f"got {out['accel'].shape} and {out['accel_measured'].shape}"
        )
    for name in ("accel", "accel_measured"):  # a failed run's traces are NaN, a finished one's not
        if out[name] is not None:
            broken = (status == "ok") & ~np.all(np.isfinite(out[name]), axis=1)
            if np.any(broken):
                i = int(np.argmax(broken))
                raise VehicleError(f"Campaign.{name}[{i}] is not finite but status[{i}] is 'ok'")
    return out


def _is_integer(value: object) -> bool:
    """Whether ``value`` is a Python or numpy integer (not a bool)."""
    return isinstance(value, int | np.integer) and not isinstance(value, bool | np.bool_)


def _through_link(path: Path) -> Path:
    """``path``, or where it leads if it is a symbolic link (a file that need not exist yet, as
    ``open`` would create it); CampaignFileError for a link that leads nowhere (a loop) or a
    path the OS cannot look at (a name too long)."""
    try:
        if not path.is_symlink():
            return path
        return Path(os.path.realpath(path, strict=True))
    except FileNotFoundError:  # a link to a file not made yet: write it there
        return Path(os.path.realpath(path))
    except (OSError, ValueError) as exc:  # a loop, or a name too long for the file system
        raise CampaignFileError(f"cannot write campaign file {str(path)!r}: {exc}") from exc


def _refuse_to_replace(path: Path) -> None:
    """CampaignFileError if ``path`` holds what a campaign file must not replace: a folder or
    other non-regular file, or a non-empty file that is not a campaign file (a zip of campaign
    members only, the settings among them), e.g. an emulator file or a user's notes."""
    try:
        info = os.stat(path)
    except (OSError, ValueError):  # nothing there (or nothing the write can reach: it says why)
        return
    if not stat.S_ISREG(info.st_mode):
        raise CampaignFileError(
            f"refusing to write {str(path)!r}: it exists and is not a regular file"
        )
    if info.st_size == 0:
        return
    try:
        with zipfile.ZipFile(path) as zf:
            names = set(zf.namelist())
    except _READ_ERRORS:
        names = set()
    if "settings.npy" not in names or not names <= _MEMBERS:
        raise CampaignFileError(
            f"refusing to write {str(path)!r}: it holds a file that is not a campaign file "
            f"({info.st_size} bytes), which the campaign would replace; choose another path or "
            "remove it first"
        )


def _save_npz(path: Path, arrays: dict[str, np.ndarray]) -> None:
    """``np.savez`` to a new temporary file beside ``path``, moved over it in one step: a crash
    or an error never leaves a half-written file, and an existing one stays whole and keeps
    its permissions. The temporary file is named as gpmsa's ``atomic_write`` names its own
    (the process id and host in it): one left by a save killed outright (SIGKILL) is removed
    by a later process's first save into that folder on that host, once its process no longer
    runs (`_remove_stale_temporaries`)."""
    try:
        mode = stat.S_IMODE(os.stat(path).st_mode)
    except (OSError, ValueError):
        mode = None
    _remove_stale_temporaries(path.parent)
    # the name's start (at most 32 characters) keeps the temporary name within the 255 bytes
    # a file name may have
    tmp = path.with_name(
        f".{path.name[:32]}.{os.getpid()}@{_host_id()}.{secrets.token_hex(6)}.part"
    )
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0), 0o666)
    try:
        with os.fdopen(fd, "wb") as fh:
            if mode is not None:  # a private file stays private
                os.chmod(tmp, mode)
            np.savez(fh, **arrays)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    _flush_folder(path.parent)


def _flush_folder(folder: Path) -> None:
    """Flush ``folder``'s entries to disk (``fsync`` of the folder, POSIX; as gpmsa.io.atomic's
    twin), so that a power cut just after a save keeps the new file: its bytes were flushed
    before the move, its new name only by this. Nothing where the OS or file system cannot
    (Windows, a folder this process cannot open for reading, no ``fsync`` of a folder); an I/O
    error raises OSError naming the folder."""
    if sys.platform == "win32":
        return
    try:
        fd = os.open(folder, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError as exc:
        if exc.errno not in _NO_FOLDER_FSYNC:
            raise OSError(
                exc.errno,
                f"{folder}: the file was moved into place, but the folder could not be flushed "
                f"to disk ({exc.strerror or exc}): a power cut could still undo the save; check "
                "the disk and save again",
            ) from exc
    finally:
        os.close(fd)


_NO_FOLDER_FSYNC = frozenset(
    getattr(errno, name)
    for name in ("EINVAL", "ENOTSUP", "EOPNOTSUPP", "EBADF")
    if hasattr(errno, name)
)
"""The errors of an ``fsync`` of a folder that mean the file system does not take one."""


_STALE_PART = re.compile(r"\..+\.(\d{1,10})@([0-9a-f]{8})\.[0-9a-f]{12}\.part", re.DOTALL)
"""A temporary file's name (``.NAME[:32].PID@HOST.RANDOM.part``): the writer's process id and
host."""


def _host_id() -> str:
    """8 hexadecimal digits naming this host and its process-id space (the host name, the
    machine id and, on Linux, the pid namespace), as gpmsa.io.atomic names them."""
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


_SWEPT: set[str] = set()
"""The folders (absolute) this process has swept of stale temporaries; a forked child (a
campaign's worker) starts with none, so that it sweeps again at its first save. At most
`_SWEPT_FOLDERS` of them."""
if hasattr(os, "register_at_fork"):  # POSIX
    os.register_at_fork(after_in_child=_SWEPT.clear)

_SWEPT_FOLDERS = 1024
"""The folders `_SWEPT` holds at most (as gpmsa.io.atomic's): a process that saves campaigns
into ever new folders would otherwise keep a name for each for good. Past it the record starts
afresh, and a folder saved into again is swept once more (each time it starts afresh)."""


def _remove_stale_temporaries(folder: Path) -> None:
    """At this process's first save into ``folder`` (one listing a folder and process: a cache
    of one file a run must not be listed at every save), remove the temporary files there of
    saves killed outright, whatever their target: those of a process of this host that no
    longer runs. Never one of a running process (another save in progress, another worker of a
    campaign sharing the cache), of another host, or on Windows."""
    key = os.path.abspath(folder)
    if sys.platform == "win32" or key in _SWEPT:
        return
    if len(_SWEPT) >= _SWEPT_FOLDERS:
        _SWEPT.clear()
    _SWEPT.add(key)
    host = _host_id()
    try:
        names = [e.name for e in os.scandir(folder) if e.name.endswith(".part")]
    except (OSError, ValueError):
        return
    for name in names:
        found = _STALE_PART.fullmatch(name)
        if found is None or found[2] != host or _runs(int(found[1])):
            continue
        try:
            os.unlink(folder / name)
        except OSError:  # gone meanwhile (another save removed it), or a folder of that name
            pass


def _runs(pid: int) -> bool:
    """Whether a process ``pid`` runs on this host (another user's or a zombie too)."""
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (OSError, OverflowError):  # another user's (EPERM), or not a process id at all
        return True
    return True


def _check_path(path: object, name: str = "path", what: str = "file") -> None:
    """Raise VehicleError unless ``path`` (the argument ``name``, a ``what`` path) is a str or
    os.PathLike (an int would be taken for an open file descriptor) without a NUL byte that the
    file system's encoding can write (a lone surrogate such as "\\ud800" it cannot)."""
    if not isinstance(path, (str, os.PathLike)):
        raise VehicleError(
            f"{name}={path!r} must be a {what} path, str or os.PathLike (got {type(path).__name__})"
        )
    try:
        text = os.fspath(path)
    except TypeError as exc:  # a PathLike whose __fspath__ returns neither str nor bytes
        raise VehicleError(f"{name}={path!r} must be a {what} path: {exc}") from exc
    if isinstance(text, bytes):  # Path() refuses it: a TypeError deep in the save
        raise VehicleError(
            f"{name}={path!r} must be a {what} path, str or os.PathLike giving a str (its "
            f"__fspath__ gives bytes, {text!r}: decode them with os.fsdecode)"
        )
    if "\0" in text:
        raise VehicleError(f"{name}={text!r} must be a {what} path: it contains a NUL byte")
    try:
        os.fsencode(text)
    except UnicodeEncodeError as exc:  # os.open would raise it, deep in the write or read
        bad = exc.object[exc.start : exc.end]
        raise VehicleError(
            f"{name}={text!r} must be a {what} path: it holds {bad!r}, which the file system's "
            f"encoding ({sys.getfilesystemencoding()}) cannot write"
        ) from exc
    if what == "file" and text.endswith(("/", os.sep)):  # "out/" names a folder, not a file
        raise VehicleError(f"{name}={text!r} names a folder (it ends in a separator), not a file")


def run_campaign(
    design: np.ndarray | None = None,
    model: Model | None = None,
    road_length_m: float = 21.0,
    *,
    dx_m: float = 0.006,
    lead_in_m: float = 1.0,
    band: tuple[float, float] | None = None,
    rate_hz: float = 120.0,
    noise_std: float = 1.0,
    window: int = 1000,
    substeps: int = SUBSTEPS,
    executor: Executor | None = None,
    progress: bool = True,
    cache_dir: str | os.PathLike | None = None,
    seed: int = 0,
    keep_s: float = 0.0,
) -> Campaign:
    """Run one drive per design point and tabulate f (see the module docstring).

    Each run gets a fresh road: ``roadgen.iso8608_profile(road_length_m, gd, dx_m, seed=...,
    band=band, lead_in_m=lead_in_m)``, which the tyres follow enveloped by the model's wheel
    radius (``simulate``'s default); the vehicle drives it at constant speed v from rest, front axle
    starting a wheelbase in (rear axle at the road's start), to the road's end.

    Args:
        design: (n, 2) array [v (m/s), GD]; default ``lhs_design(198, seed=seed)``.
        model: default ``Jackal()``. band: road content band (cycles/m), default the full grid.
        road_length_m: length of each road, m (lengthened where ``keep_s`` needs it).
        dx_m: the roads' grid step, m, in [``roadgen.checks.MIN_DX_M``, road_length_m / 1.5].
        lead_in_m: the roads' raised-cosine lead-in, m (``roadgen.iso8608_profile``'s).
        rate_hz: accelerometer sample rate, Hz. substeps: solver steps per sample period (as
            ``simulate``'s).
        noise_std: accelerometer noise std for the ``*_noisy`` columns (paper: 1 m/s^2), in
            [0, ``vehicle.sensor.MAX_NOISE_STD``].
        window: samples in the ``f_window`` span.
        progress: show a tqdm bar over the runs (on by default; False: none).
        executor: any ``concurrent.futures.Executor`` (e.g. a dask ``Client.get_executor()``);
            default a process pool over all cores, shut down at the end (its workers end
            with this process, even one killed outright).
        cache_dir: finished runs are stored there, one ``.npz`` per run named by a hash of its
            settings and of the code that computes it (``code_fingerprint``: the roadgen and
            vehicle source, numpy, scipy and exudyn), and reused: an interrupted campaign loses
            no finished run, and an entry of other code is not reused. Failed runs are
            not stored (they run again next time), and a damaged entry is recomputed; an entry
            that reads as a finished run of the same settings is trusted as the user's own.
        seed: the campaign's seed; run i gets road seed ``SeedSequence(seed).generate_state(n)[i]``.
            None: a fresh seed from the OS's entropy, recorded in ``settings["seed"]`` like a
            given one, so that the campaign can be run again.
        keep_s: keep the last keep_s seconds of each drive's accelerations (``Campaign.accel``);
            each road is lengthened (beyond ``road_length_m`` where needed) so that they begin
            at least 1 s after the front axle has passed the lead-in.
    Returns:
        Campaign. A run that fails (diverges) is recorded with NaN f and its message.

    Raises VehicleError for bad input (checked before any run: each argument's type and range,
    a road too short for the window, traces or a drive's solver time grid (rate_hz x substeps
    steps a second) beyond ``vehicle.checks.MAX_MEMORY_BYTES``, a
    ``keep_s`` that keeps no sample, a drive longer than ``simulate``'s limit
    ``vehicle.kinematics.MAX_DRIVE_S``, a ``cache_dir`` that cannot be a folder), and
    RoadgenError for road settings that no road can have (too long for
    ``roadgen.checks.MAX_MEMORY_BYTES``, a band its length cannot hold).
    """
    model = Jackal() if model is None else check_model(model)
    seed = checks.seed("seed", seed, generator=False)
    if seed is None:  # a fresh seed, recorded (SeedSequence entropy: 128 bits, as the range)
        seed = int(np.random.SeedSequence().entropy)
    design = lhs_design(198, seed=seed) if design is None else design
    points = check_design(design, model)
    road_length_m = checks.positive("road_length_m", road_length_m, unit="m")
    dx_m = checks.grid_step("dx_m", dx_m, road_length_m, "road_length_m")
    lead_in_m = checks.non_negative("lead_in_m", lead_in_m, unit="m")
    band = None if band is None else checks.band("band", band, 0.5 / dx_m)
    rate_hz = check_rate(rate_hz)
    noise_std = check_noise(noise_std)
    window = checks.integer("window", window, 2)
    substeps = checks.integer("substeps", substeps, 1)
    warn_if_step_too_coarse(model, rate_hz, substeps)  # here, not in each run (`_drive`)
    progress = checks.flag("progress", progress)
    keep_s = checks.non_negative("keep_s", keep_s, unit="s")
    if executor is not None and not callable(getattr(executor, "submit", None)):
        raise VehicleError(
            f"executor={executor!r} must be None or an Executor (an object with a callable "
            f"submit), got {type(executor).__name__}"
        )
    if cache_dir is not None:
        _check_path(cache_dir, "cache_dir", "folder")
        if not os.fsdecode(cache_dir):  # Path("") is the working directory: never by accident
            raise VehicleError("cache_dir='' must be a folder path, got the empty string")
    n_points = roadgen.profile.grid_points(road_length_m, dx_m)  # one road fits in memory
    if band is not None:  # and holds the band: roadgen's checks, on the shortest road
        roadgen.profile.unit_road(
            n_points, dx_m, 0, band, "deterministic", 2.0, 0.0, length_name="road_length_m"
        )
        roadgen.iso8608_profile(road_length_m, 1.0, dx_m, seed=0, band=band, lead_in_m=lead_in_m)
    keep = int(round(keep_s * rate_hz))
    if keep_s > 0 and keep == 0:
        raise VehicleError(
            f"keep_s={keep_s!r} s keeps 0 samples at rate_hz={rate_hz:g} Hz: use 0 or at least "
            f"{1 / rate_hz:.4g} s (one sample)"
        )
    checks.memory(
        16.0 * keep * points.shape[0], f"keep_s={keep_s!r} s of traces for {points.shape[0]} runs"
    )

    def length(v: float) -> float:
        need = lead_in_m + model.wheelbase_m + v * (keep_s + 1.0) if keep else 0.0
        return float(max(road_length_m, need))

    # each run's own road, lengthened for keep_s or not, must hold the window after the lead-in
    speeds = points[:, 0]
    lengths = [length(float(v)) for v in speeds]
    usable_m = np.array(lengths) - lead_in_m - 2 * model.wheelbase_m
    short = ~(usable_m >= window * speeds / rate_hz)
    if short.any():
        v_short = float(np.max(speeds[short]))
        need_m = window * v_short / rate_hz
        least = bound_text(need_m + lead_in_m + 2 * model.wheelbase_m, up=True, digits=4)
        while not float(least) - lead_in_m - 2 * model.wheelbase_m >= need_m:  # as above, in
            least = bound_text(np.nextafter(float(least), np.inf), up=True, digits=4)  # float64
        raise VehicleError(
            f"road_length_m={road_length_m!r} is too short: a {window}-sample window at "
            f"{v_short:.4g} m/s after the lead-in ({lead_in_m} m) needs "
            f"road_length_m >= {least} m"
        )

    _check_drives(points, lengths, model, dx_m, rate_hz * substeps)
    seeds = np.random.SeedSequence(seed).generate_state(points.shape[0]).astype(np.int64)
    specs = [
        RunSpec(model, float(v), float(gd), int(s), road_m, dx_m, lead_in_m, band, rate_hz,
                noise_std, window, substeps, keep)
        for (v, gd), s, road_m in zip(points, seeds, lengths, strict=True)
    ]  # fmt: skip
    cache = None if cache_dir is None else _cache_folder(cache_dir)
    results: list[RunResult | None] = [None] * len(specs)
    todo = []
    for i, spec in enumerate(specs):
        cached = None if cache is None else _read_cached(cache / f"run-{spec.key()}.npz", spec)
        if cached is None:
            todo.append(i)
        else:
            results[i] = cached
    own = executor is None and len(todo) > 0
    ctx = multiprocessing.get_context()  # the pool's: its workers set `started` once started
    started = None if not own or ctx.get_start_method() == "fork" else ctx.Value("b", 0, lock=False)
    pool = (
        ProcessPoolExecutor(
            max_workers=min(os.cpu_count() or 1, len(todo)),
            initializer=_end_with_parent,
            initargs=(os.getpid(), started),
        )
        if own
        else executor
    )  # (before the bar: a pool that cannot be made leaves no bar open; it starts no process yet)
    bar = _progress_bar(progress, len(specs), len(specs) - len(todo), f"campaign {model.name}")
    futures: dict[Future, int] = {}
    try:
        try:  # (a pool broken while runs are still submitted refuses the next submit)
            for i in todo:
                futures[pool.submit(run_one, specs[i], None if cache is None else str(cache))] = i
            for fut in _completed(futures, pool if own else None):
                results[futures[fut]] = fut.result()
                bar.update()
        except BrokenExecutor as exc:
            why = _start_failure(pool, started) if own else None
            if why is None:
                raise
            raise VehicleError(why) from exc
    except BaseException:  # an error or Ctrl-C: our own pool's running runs end at once
        if own:
            _stop(pool)
        raise
    finally:  # the runs not yet started are cancelled, not waited for
        bar.close()
        for fut in futures:
            fut.cancel()
        if own:
            pool.shutdown(cancel_futures=True)
    f = np.array([r[0] for r in results])
    traces = {}
    if keep:
        traces = {
            "accel": np.stack([r[2] if r[2].size else np.full(keep, np.nan) for r in results]),
            "accel_measured": np.stack(
                [r[3] if r[3].size else np.full(keep, np.nan) for r in results]
            ),
        }
    settings = {
        **_spec_settings(specs[0]),
        "road_length_m": float(road_length_m),
        "keep_s": float(keep_s),
        "seed": int(seed),
        "f_full": "var(accel_front) over front-axle position >= lead_in_m + wheelbase",
        "f_window": f"var(accel_front) over the last {window} samples (ending at the road's end)",
        "versions": package_versions(),
    }
    return Campaign(
        v=points[:, 0].copy(),
        gd=points[:, 1].copy(),
        seed=seeds,
        **{name: f[:, j] for j, name in enumerate(_F_NAMES)},
        status=np.array([r[1] for r in results], dtype=str),
        settings=settings,
        **traces,
    )


class _NoBar:
    """The campaign's bar without ``progress``: counts, shows nothing, starts no thread."""

    def __init__(self, total: int, initial: int) -> None:
        self.total, self.n = total, initial

    def update(self, n: int = 1) -> None:
        self.n += n

    def close(self) -> None:
        pass


@functools.cache
def _bar_class():
    from tqdm.auto import tqdm

    class Bar(tqdm):
        """tqdm.auto's bar without tqdm's monitor thread (see `_progress_bar`)."""

        monitor_interval = 0

    return Bar


def _progress_bar(progress: bool, total: int, initial: int, desc: str):
    """The campaign's bar over its runs (tqdm on stderr) when ``progress``, else a `_NoBar`.
    Neither starts a thread: tqdm starts its monitor thread with its first bar, a disabled one
    too, and keeps it; the pool would fork its workers beside it (Python >= 3.12: "This process
    is multi-threaded, use of fork() may lead to deadlocks", and a rare real deadlock). The bar
    is a tqdm subclass whose ``monitor_interval`` is 0 (tqdm's own class is left as it is; the
    monitor only refreshes a bar that has waited over ``maxinterval``, and this one updates
    at each run). (gpmsa's bars do the same; vehicle does not import gpmsa.)"""
    if not progress:
        return _NoBar(total, initial)
    return _bar_class()(total=total, initial=initial, desc=desc, unit="run")


_POLL_S = 0.25
"""Seconds between the campaign's checks for an interrupt while runs are simulated. The kernel
may hand a process's SIGINT to any of its threads (the pool's, BLAS's); Python acts on it in the
main thread only, and a wait without a timeout would hold it until a run ends."""

_JOIN_S = 5.0
"""Seconds to wait for a terminated worker process to exit."""


_STUCK_S = 2.0
"""Seconds a worker of the campaign's own pool may have ended while the pool is not marked
broken before the wait gives up (`_ended_mid_send`); the pool marks itself broken within
milliseconds of a worker's end unless its manager thread is reading a result that worker was
sending."""


def _completed(futures: dict[Future, int], pool: ProcessPoolExecutor | None = None):
    """``as_completed(futures)``, waking every `_POLL_S` seconds so that an interrupt taken by
    another thread is acted on within that time (each future reports itself done to a queue:
    O(1) a wake, where re-waiting on the pending futures would cost O(runs)), and checking our
    own ``pool`` (None: a user's executor) for a worker killed mid-send (`_ended_mid_send`:
    BrokenProcessPool)."""
    done: queue.SimpleQueue[Future] = queue.SimpleQueue()
    for fut in futures:
        fut.add_done_callback(done.put)
    first_seen: list[float] = []
    for _ in range(len(futures)):
        while True:
            try:
                fut = done.get(timeout=_POLL_S)
            except queue.Empty:
                if pool is not None and _ended_mid_send(pool, first_seen):
                    raise BrokenProcessPool(
                        "a campaign worker process ended while it sent its run's result "
                        "(killed: out of memory?); the pool cannot go on: run the campaign "
                        "again (finished runs are cached with cache_dir)"
                    ) from None
                continue
            break
        yield fut


def _ended_mid_send(pool: ProcessPoolExecutor, first_seen: list[float]) -> bool:
    """Whether a worker of our own ``pool`` has been seen ended for `_STUCK_S` while the pool is
    not marked broken (``first_seen``: [] or [when it was first seen, ``time.monotonic``],
    updated). A worker killed while it sent a result (the OOM killer, ``kill -9``) leaves the
    pool's manager thread reading the rest of that message for ever: it never marks the pool
    broken, and the run's future never finishes (`_stop`, called then, ends the manager).
    (gpmsa's chain pools do the same; vehicle does not import gpmsa.)"""
    sentinels = [p.sentinel for p in (getattr(pool, "_processes", None) or {}).values()]
    if getattr(pool, "_broken", False) or not sentinels:
        first_seen.clear()
        return False
    if not multiprocessing.connection.wait(sentinels, timeout=0):
        first_seen.clear()
        return False
    if not first_seen:
        first_seen.append(time.monotonic())
    return time.monotonic() - first_seen[0] >= _STUCK_S


def _stop(pool: ProcessPoolExecutor) -> None:
    """End our own ``pool`` at once after an error or an interrupt (Ctrl-C, a notebook's
    interrupt, which signals this process alone): cancel the runs not started and terminate the
    workers still simulating one (``terminate_workers`` of Python 3.14), so that the interrupt
    does not wait for their runs and no process goes on simulating runs nobody will read. A run
    cut off leaves no cache entry (each is written whole or not at all). (gpmsa's chain pools do
    the same; vehicle does not import gpmsa.)"""
    processes = list((getattr(pool, "_processes", None) or {}).values())
    manager = getattr(pool, "_executor_manager_thread", None)  # shutdown forgets it
    results = getattr(pool, "_result_queue", None)  # this too
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in processes:
        if proc.is_alive():
            proc.terminate()
    for proc in processes:
        proc.join(timeout=_JOIN_S)
    if all(not proc.is_alive() for proc in processes):
        _close_writer(results)
    if manager is not None:  # it takes the pool's locks: a fork while it runs inherits them
        manager.join(timeout=_JOIN_S)


def _close_writer(results: object) -> None:
    """Close this process's end of a pool's result pipe (its workers all ended): a worker ended
    while it sent a result leaves the rest of that message unwritten, and the pool's manager
    thread would wait for it for ever (the interpreter joins that thread at exit: it would never
    end); with no writer left it reads an end of file, and winds down as after any broken
    worker. Nothing in this process writes there."""
    writer = getattr(results, "_writer", None)
    if writer is not None:
        writer.close()


def _end_with_parent(owner: int | None = None, started=None) -> None:
    """The campaign pool's worker initializer: set the shared flag ``started`` (a ``Value``;
    None: none) to 1, and end this worker when ``owner`` (the process that runs the campaign;
    None: its parent) ends. (Spawn and forkserver run the main script before the initializer:
    a worker that set the flag got past it.) A campaign killed (SIGTERM, SIGKILL, the OOM
    killer: its cleanup never runs) would leave its workers waiting for runs for ever, each
    holding a copy of its memory. On Linux, where the owner started the worker itself (fork,
    spawn), the kernel kills the worker then (prctl PR_SET_PDEATHSIG); elsewhere on POSIX, and
    where a forkserver started it (Python 3.14's default on Linux: its parent, which outlives the
    owner while any worker holds its pipe), a thread checks the parent and the owner each second
    (on Windows none: a process's parent id there is not updated when the parent ends). (gpmsa's
    chain pools do the same; vehicle does not import gpmsa.) The kernel's signal follows the
    thread that started the worker: the one that runs the campaign, which outlives the pool."""
    if started is not None:
        started.value = 1
    parent = os.getppid()
    owner = parent if owner is None else owner
    if sys.platform == "linux" and owner == parent:
        try:
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            if libc.prctl(1, int(signal.SIGKILL), 0, 0, 0) == 0:  # 1: PR_SET_PDEATHSIG
                if os.getppid() != parent:  # it ended before the call
                    os._exit(1)
                return
        except (OSError, AttributeError):  # no libc.prctl: watch as elsewhere
            pass
    if sys.platform == "win32":  # os.getppid() keeps the ended parent's id: nothing to watch
        return
    threading.Thread(target=_watch_parent, args=(parent, owner), name="vehicle-end-with-parent",
                     daemon=True).start()  # fmt: skip


def _watch_parent(parent: int, owner: int) -> None:
    ended = _ended(owner)
    while os.getppid() == parent and not ended():
        time.sleep(1.0)
    os._exit(1)


def _ended(pid: int) -> Callable[[], bool]:
    """A test whether process ``pid`` has ended: on Linux by a pidfd, readable once it ended,
    before its parent reaps it (a killed campaign whose parent does not wait for it stays a
    zombie), and never by another process that reuses the id; elsewhere by `_alive`."""
    try:
        fd = os.pidfd_open(pid)
    except ProcessLookupError:
        return lambda: True
    except (AttributeError, OSError):  # not Linux, or a kernel before 5.3
        return lambda: not _alive(pid)
    poller = select.poll()
    poller.register(fd, select.POLLIN)
    return lambda: bool(poller.poll(0))


def _alive(pid: int) -> bool:
    """Whether process ``pid`` exists."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's
        pass
    return True


def _start_failure(pool: ProcessPoolExecutor, started=None) -> str | None:
    """Why the campaign's own ``pool`` broke, where a worker started by spawn or forkserver (not
    fork) ended with an error (exit code > 0) while it started: it runs the main script again
    (as ``"__mp_main__"``), which fails where the script runs the campaign outside an
    ``if __name__ == "__main__":`` block or was read from standard input; else None (also where
    a worker got past the main script, its flag ``started`` set: one that ended in a run, by
    ``exit(1)`` in a library, was no start failure). (gpmsa's chain pools say the same; vehicle
    does not import gpmsa.)"""
    context = getattr(pool, "_mp_context", None)
    method = context.get_start_method() if context is not None else "fork"
    if method == "fork" or (started is not None and started.value):
        return None
    manager = getattr(pool, "_executor_manager_thread", None)
    if manager is not None:  # it joins the workers: a worker may not have ended quite yet
        manager.join(timeout=5.0)
    codes = [p.exitcode for p in (getattr(pool, "_processes", None) or {}).values()]
    code = next((c for c in codes if c is not None and c > 0), None)
    if code is None:
        return None
    main = sys.modules.get("__main__")
    path = getattr(main, "__file__", None)
    if getattr(main, "__spec__", None) is None and path is not None and not os.path.isfile(path):
        fix = f"a script read from {path} cannot be read again: save it as a file and run that"
    else:
        where = f" of {path}" if path is not None else ""
        fix = f'call run_campaign inside an `if __name__ == "__main__":` block{where}'
    return (
        f"a campaign worker process ended while starting (exit code {code}; its error is above, "
        f"on stderr). The workers start by {method!r} (this platform's default, or "
        f"multiprocessing.set_start_method's choice), which runs the main script again in each: "
        f"{fix}"
    )


def _check_drives(
    points: np.ndarray, lengths: list[float], model: Model, dx_m: float, steps_per_s: float
) -> None:
    """Raise, before any run, for what would make runs fail: a road (``lengths``, m, one per
    design point) beyond ``roadgen.checks.MAX_MEMORY_BYTES`` (RoadgenError), or a drive,
    from a wheelbase in to the road's end at the point's speed, longer than ``simulate``'s limit
    ``kinematics.MAX_DRIVE_S`` or whose time grid of ``steps_per_s`` (rate_hz x substeps)
    solver steps a second needs more than ``vehicle.checks.MAX_MEMORY_BYTES`` (VehicleError
    naming the point)."""
    roadgen.profile.grid_points(max(lengths), dx_m)
    drives = np.round(np.asarray(lengths) / dx_m) * dx_m - model.wheelbase_m  # as grid_points
    seconds = drives / points[:, 0]
    i = int(np.argmax(seconds))
    if seconds[i] > kinematics.MAX_DRIVE_S:
        took = distinct_texts(seconds[i], kinematics.MAX_DRIVE_S, digits=4)[0]
        most = distinct_texts(seconds[i], kinematics.MAX_DRIVE_S)[1]
        raise VehicleError(
            f"design[{i}] (v={points[i, 0]:.4g} m/s) drives {drives[i]:.6g} m of road in "
            f"{took} s: simulate allows drives of <= {most} s "
            "(vehicle.kinematics.MAX_DRIVE_S); use a shorter road_length_m or keep_s"
        )
    steps = seconds[i] * steps_per_s + 1  # as simulate's own check (kinematics.schedule_grid)
    checks.memory(
        checks.BYTES_PER_STEP * steps,
        f"design[{i}] (v={points[i, 0]:.4g} m/s): a drive of {steps:.4g} solver steps "
        "(rate_hz x substeps a second)",
    )


def package_versions() -> dict[str, str]:
    """Versions of what computes a campaign's f: Python, numpy, scipy, exudyn, this project,
    the machine and its BLAS (see docs/vehicle-models.md, "Reproducibility": f of a run depends
    on the floating-point details of the machine, so a campaign records where it was made)."""
    import platform
    from importlib import metadata

    import exudyn
    import scipy

    out = {
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "exudyn": str(getattr(exudyn, "__version__", None) or metadata.version("exudyn")),
        "machine": f"{platform.system()} {platform.machine()}",
    }
    try:
        out["terrain-gpmsa"] = metadata.version("terrain-gpmsa")
    except metadata.PackageNotFoundError:
        out["terrain-gpmsa"] = "not installed"
    try:
        from threadpoolctl import threadpool_info

        out["blas"] = "; ".join(
            f"{i.get('internal_api')} {i.get('version')} ({i.get('architecture')})"
            for i in threadpool_info()
            if i.get("user_api") == "blas"
        )
    except Exception:  # informative only
        out["blas"] = "unknown"
    return out


RunResult = tuple[np.ndarray, str, np.ndarray, np.ndarray]
"""f values (4,), "ok" or the failure message, kept noise-free and measured accelerations."""


def run_one(spec: RunSpec, cache_dir: str | None = None) -> RunResult:
    """One run: f values (4,) in ``_F_NAMES`` order, "ok" or the failure message, and the last
    ``spec.keep_samples`` noise-free and measured accelerations (empty when none are kept or
    the run failed). Writes a finished run to ``cache_dir`` (if given) before returning; a
    failed one is not stored (its cause, e.g. a memory limit, may be gone next time).
    """
    empty = np.zeros(0)
    try:
        f, acc, measured = _drive(spec)
        status = "ok"
    except (VehicleError, SimulationDivergedError, roadgen.RoadgenError) as exc:
        f, status = np.full(len(_F_NAMES), np.nan), f"{type(exc).__name__}: {exc}"
        acc = measured = empty
    if cache_dir is not None and status == "ok":
        cached = roadgen.checks.home_path(cache_dir) / f"run-{spec.key()}.npz"
        _write_cached(cached, (f, status, acc, measured), spec)
    return f, status, acc, measured


def _drive(spec: RunSpec) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    profile = roadgen.iso8608_profile(
        spec.road_length_m, spec.gd, dx_m=spec.dx_m, seed=spec.seed, band=spec.band,
        lead_in_m=spec.lead_in_m,
    )  # fmt: skip
    # run_campaign warned of a coarse step, once, at the user's call
    trace = _simulate(
        spec.model, profile, spec.v, spec.rate_hz, spec.noise_std,
        np.random.default_rng([spec.seed, 1]), speed_of="time", start_m=None, end_m=None,
        substeps=spec.substeps, envelope=True, step_warning=False,
    )  # fmt: skip
    full = trace.position >= spec.lead_in_m + spec.model.wheelbase_m
    need = max(spec.window, spec.keep_samples)
    if np.count_nonzero(full) < need:
        raise VehicleError(
            f"run v={spec.v:.4g} m/s has {np.count_nonzero(full)} samples after the lead-in: "
            f"need >= {need} (window={spec.window}, keep={spec.keep_samples})"
        )
    win = slice(len(trace) - spec.window, None)
    kept = slice(len(trace) - spec.keep_samples, None) if spec.keep_samples else slice(0, 0)
    f = np.array(
        [
            np.var(trace.accel_front[full]),
            np.var(trace.accel_front[win]),
            np.var(trace.accel_front_measured[full]),
            np.var(trace.accel_front_measured[win]),
        ]
    )
    return f, trace.accel_front[kept].copy(), trace.accel_front_measured[kept].copy()


@functools.cache
def code_fingerprint() -> str:
    """SHA-256 of what computes a run: the source of ``roadgen`` and ``vehicle`` and the versions
    of numpy, scipy and exudyn. Part of every cache key, so that a cache written by other code
    (a road drawn differently, another solver) is never taken for this code's runs. Line ends
    are read as LF: a checkout with CRLF ones (git's autocrlf on Windows) is the same code."""
    from importlib import metadata

    import scipy

    digest = hashlib.sha256()
    for folder in (Path(roadgen.__file__).parent, Path(__file__).parent):
        for source in sorted(folder.glob("*.py")):
            digest.update(f"{folder.name}/{source.name}\0".encode())
            digest.update(source.read_bytes().replace(b"\r\n", b"\n"))
    try:
        exudyn_version = metadata.version("exudyn")
    except metadata.PackageNotFoundError:
        exudyn_version = "not installed"
    versions = {"numpy": np.__version__, "scipy": scipy.__version__, "exudyn": exudyn_version}
    digest.update(json.dumps(versions, sort_keys=True).encode())
    return digest.hexdigest()


def _spec_settings(spec: RunSpec) -> dict:
    return {
        "model": spec.model.describe(),
        "road_length_m": spec.road_length_m,
        "dx_m": spec.dx_m,
        "lead_in_m": spec.lead_in_m,
        "band": None if spec.band is None else list(spec.band),
        "wheel_envelope_radius_m": spec.model.wheel_radius_m,
        "rate_hz": spec.rate_hz,
        "noise_std": spec.noise_std,
        "window": spec.window,
        "keep_samples": spec.keep_samples,
        "substeps": spec.substeps,
        "solver": "exudyn generalised-alpha, spectral radius 0.9",
    }


def _write_cached(path: Path, result: RunResult, spec: RunSpec) -> None:
    f, status, acc, measured = result
    _save_npz(path, {"f": f, "status": np.asarray(status), "key": np.asarray(spec.key()),
                     "accel": acc, "accel_measured": measured})  # fmt: skip


def _cache_folder(cache_dir: str | os.PathLike) -> Path:
    """``cache_dir`` as a Path, made if missing; VehicleError naming it if it cannot be a folder
    (a file, below a file, not writable)."""
    cache = roadgen.checks.home_path(cache_dir)  # not a folder named "~"
    try:
        cache.mkdir(parents=True, exist_ok=True)
        # an existing folder may not be writable: a probe of a name of its own (campaigns on
        # other machines sharing the folder may have this one's process id), without a name
        # where the OS allows (O_TMPFILE: an interrupted probe leaves nothing behind)
        with tempfile.TemporaryFile(dir=cache, prefix=".write-test-"):
            pass
    except OSError as exc:
        raise VehicleError(
            f"cache_dir={str(cache_dir)!r} cannot be used as a folder: {exc}"
        ) from exc
    return cache


def _read_cached(path: Path, spec: RunSpec) -> RunResult | None:
    """The finished run of ``spec`` stored at ``path``, or None if there is none or the entry is
    damaged or not a finished run of ``spec`` (it is recomputed); CampaignFileError if the entry
    is not a regular file (a run could not replace it)."""
    if not path.exists():
        return None
    if not path.is_file():
        raise CampaignFileError(f"cache entry {str(path)!r} is not a regular file: remove it")
    try:
        data = _read_npz(path, ("f", "status", "key", *_TRACES))
    except CampaignFileError:
        return None
    f, status, key = data["f"], data["status"], data["key"]
    traces = [data[name] for name in _TRACES]
    finished = (
        status.shape == () and str(status) == "ok"
        and key.shape == () and str(key) == spec.key()
        and f.shape == (len(_F_NAMES),) and f.dtype.kind == "f"
        and bool(np.all(np.isfinite(f) & (f >= 0)))
        and all(
            a.shape == (spec.keep_samples,) and a.dtype.kind == "f" and bool(np.all(np.isfinite(a)))
            for a in traces
        )
    )  # fmt: skip
    return (f, "ok", *traces) if finished else None
