"""The emulator file container (``*.gpmsa``): a zip of .npy arrays plus ``manifest.json``.

It knows nothing of the Emulator: ``write_raw`` and ``read_raw`` move a (manifest dict, arrays
dict) pair; what goes into them is the Emulator's record (``gpmsa.fitting.emulator``). The container
owns the envelope: the format name, the schema version (and the upgrade of older ones), the
library version and time of writing, the arrays' shapes and dtypes, and the content hash.

Safe to read from an untrusted source: arrays load with allow_pickle=False and only float64,
int64 or bool dtypes; member names, counts and sizes are checked before anything is decompressed
further than the stated limits; a sha256 over the arrays and the manifest detects any edit.
Layout and schema: docs/emulator-file.md.
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import os
import re
import stat
import struct
import zipfile
import zlib
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from gpmsa import limits
from gpmsa._version import __version__
from gpmsa.errors import EmulatorFileError, GPMSAError
from gpmsa.io.atomic import atomic_write

FORMAT = "gpmsa-emulator"
STUDY_FORMAT = "gpmsa-study"
"""The format of a study file (several models' shared draws; gpmsa.studies, docs/models.md)."""
SCHEMA_VERSION = 1
MANIFEST = "manifest.json"
ARRAY_DIR = "arrays/"
NAME_RE = re.compile(r"\A[A-Za-z0-9_]{1,64}\Z")  # \Z: "$" also matches before a final "\n"
ALLOWED_DTYPES = {"<f8", "<i8", "|b1"}
MAX_NDIM = 8
"""Most dimensions of an array of the file."""
NPY_HEADER_MAX = 65536 + 16
"""Longest .npy preamble (magic, header length, header) a member may carry before its data."""
READ_CHUNK = 8 * 1024**2
"""Bytes decompressed per step when a member is read."""
CENTRAL_ENTRY_MAX = 1024
"""Bytes of the zip's central directory allowed per member (names are at most 75 characters)."""
# The size limits live in gpmsa.limits (MAX_FILE_BYTES, MAX_ARRAY_BYTES, MAX_MANIFEST_BYTES,
# MAX_MEMBERS, MAX_RATIO) and are read when a file is read or written.

ENVELOPE = ("format", "schema_version", "library_version", "created_utc", "arrays",
            "content_sha256")  # fmt: skip
"""Manifest fields the container writes itself (``write_raw`` refuses them from its caller)."""
FIELDS = (("arrays", dict), ("names", dict), ("units", dict), ("priors", dict),
          ("settings", dict), ("metadata", dict), ("diagnostics", dict),
          ("content_sha256", str))  # fmt: skip
"""Schema 1: manifest fields every file has, and their JSON types."""


def jsonable(obj):
    """Replace non-finite floats (not valid JSON) by None, recursively; tuples become lists."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {str(k): jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [jsonable(v) for v in obj]
    if isinstance(obj, np.generic):
        return jsonable(obj.item())
    return obj


def _key_not_str(obj, where: str) -> str | None:
    """Where the first dict key of ``obj`` (dicts and lists within) that is not a str lies
    ("manifest['metadata']: key 2 (int)"), or None."""
    if isinstance(obj, dict):
        for key, value in obj.items():
            if not isinstance(key, str):
                return f"{where}: key {key!r:.40} ({type(key).__name__})"
            found = _key_not_str(value, f"{where}[{key!r:.40}]")
            if found is not None:
                return found
    elif isinstance(obj, (list, tuple)):
        for i, value in enumerate(obj):
            found = _key_not_str(value, f"{where}[{i}]")
            if found is not None:
                return found
    return None


def _canonical(manifest: dict) -> bytes:
    body = {k: v for k, v in manifest.items() if k != "content_sha256"}
    return json.dumps(body, sort_keys=True, separators=(",", ":"), allow_nan=False).encode()


def content_hash(arrays: dict[str, np.ndarray], manifest: dict) -> str:
    """sha256 over every array (name, dtype, shape, bytes; sorted by name) and the manifest."""
    h = hashlib.sha256()
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        h.update(f"{name}\0{a.dtype.str}\0{a.shape}\0".encode())
        if a.dtype.hasobject or not a.size:
            h.update(a.tobytes())
        else:
            h.update(a.reshape(-1).view(np.uint8))  # the data's bytes, without a copy
    h.update(_canonical(manifest))
    return h.hexdigest()


# --- writing ------------------------------------------------------------------------------------
def _npy_bytes(arr: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.save(buf, arr, allow_pickle=False)
    return buf.getvalue()


def _deflated_size(data: bytes) -> int:
    """Size of ``data`` deflated as zipfile does it (raw deflate, default level)."""
    c = zlib.compressobj(zlib.Z_DEFAULT_COMPRESSION, zlib.DEFLATED, -15)
    return len(c.compress(data)) + len(c.flush())


def _too_compressible(file_size: int, compress_size: int) -> bool:
    """The reader's zip-bomb test of one member."""
    return file_size > limits.MAX_RATIO * max(compress_size, 1) + 1024


def _span_bytes(shape, itemsize: int) -> int:
    """Bytes of an array of ``shape`` with its zero dimensions counted as 1: bounds the
    dimensions of an empty array too (numpy cannot even describe ``(0, 2**70)``)."""
    return math.prod(max(n, 1) for n in shape) * itemsize


def _span_problem(name: str, shape, itemsize: int) -> str | None:
    """Why an array of ``shape`` is refused for its dimensions (None: it is not): an empty
    array whose other dimensions would exceed ``limits.MAX_ARRAY_BYTES``."""
    span = _span_bytes(shape, itemsize)
    if span <= limits.MAX_ARRAY_BYTES:
        return None
    return (
        f"array {name!r} declares shape {_short(list(shape))}: with each 0 counted as 1 it spans "
        f"{span} bytes, above gpmsa.limits.MAX_ARRAY_BYTES = {limits.MAX_ARRAY_BYTES}"
    )


def check_writable(manifest: dict, arrays: dict[str, np.ndarray]) -> bytes:
    """Apply the reader's limits to a record about to be written; returns the manifest's JSON.

    Raises GPMSAError naming what exceeds which limit (member count, array bytes, manifest
    bytes, names, dtypes, dimensions), so that ``write_raw`` never writes a file ``read_raw``
    refuses.
    """
    for name, arr in arrays.items():
        if not NAME_RE.match(name) or arr.dtype.str not in ALLOWED_DTYPES:
            raise GPMSAError(
                f"array {name!r} ({arr.dtype.str}): names must match {NAME_RE.pattern} and "
                f"dtypes be one of {sorted(ALLOWED_DTYPES)}"
            )
        if arr.ndim > MAX_NDIM:
            raise GPMSAError(f"array {name!r} has {arr.ndim} dimensions (limit {MAX_NDIM})")
        if not arr.size and (why := _span_problem(name, arr.shape, arr.itemsize)) is not None:
            raise GPMSAError(why)  # a full array counts in the total below
    if len(arrays) + 1 > limits.MAX_MEMBERS:
        raise GPMSAError(
            f"{len(arrays)} arrays: a file holds at most gpmsa.limits.MAX_MEMBERS - 1 = "
            f"{limits.MAX_MEMBERS - 1}"
        )
    total = sum(int(a.nbytes) + NPY_HEADER_MAX for a in arrays.values())
    if total > limits.MAX_ARRAY_BYTES:
        big = max(arrays, key=lambda k: arrays[k].nbytes)
        raise GPMSAError(
            f"the arrays take {total} bytes (the largest, {big!r} {list(arrays[big].shape)}: "
            f"{arrays[big].nbytes}), above gpmsa.limits.MAX_ARRAY_BYTES = "
            f"{limits.MAX_ARRAY_BYTES} that readers accept; keep fewer draws or outputs, or raise "
            "the limit (on every reader's machine too)"
        )
    try:
        raw = json.dumps(manifest, indent=1, allow_nan=False).encode()  # the record's order
    except (TypeError, ValueError, RecursionError) as exc:  # NaN, a set, nested too deep
        raise GPMSAError(f"the manifest is not JSON-able ({exc})") from exc
    if len(raw) > limits.MAX_MANIFEST_BYTES:
        sizes = {k: len(json.dumps(v, allow_nan=False)) for k, v in manifest.items()}
        big = max(sizes, key=sizes.get)
        raise GPMSAError(
            f"the manifest takes {len(raw)} bytes (field {big!r}: {sizes[big]}), above "
            f"gpmsa.limits.MAX_MANIFEST_BYTES = {limits.MAX_MANIFEST_BYTES} that readers accept; "
            "store less in metadata (large data belong in arrays or beside the file)"
        )
    return raw


def check_path(path) -> Path:
    """``path`` as a Path, a leading ``~`` (alone or before a separator) the home folder
    (`home_path`; not a folder named "~"); GPMSAError unless it is a non-empty str or
    path-like (bytes, numbers and None are not file names here), or for a str that ends with a
    path separator (it names a folder; Path would drop the separator, and save("out/") write a
    file named out). A bytes path (or a path-like whose ``__fspath__`` gives bytes) is refused,
    naming the remedy: its name decoded, ``os.fsdecode(path)``."""
    try:
        text = os.fspath(path) if isinstance(path, str | os.PathLike) else None
    except TypeError as exc:  # a path-like whose __fspath__ gives neither str nor bytes
        raise GPMSAError(
            f"path must be a file name (str or path-like), got {path!r}: {exc}"
        ) from None
    if isinstance(path, bytes) or isinstance(text, bytes):
        raise GPMSAError(
            f"path must be a file name (str or path-like), got {path!r}, which gives bytes: pass "
            "its name as a str (os.fsdecode(path))"
        )
    if not text:
        raise GPMSAError(f"path must be a file name (str or path-like), got {path!r}")
    if isinstance(path, str) and path.endswith(tuple(filter(None, (os.sep, os.altsep)))):
        raise GPMSAError(f"path {path!r} ends with a separator: it names a folder, not a file")
    return home_path(path)


def home_path(path: str | os.PathLike) -> Path:
    """``path`` as a Path, a leading ``~`` alone or before a separator the home folder (as the
    shell reads it: ``~/runs``); any other name as it is, ``~x`` included (a file may be named
    so, and ``Path.expanduser`` reads it as user x's home, a RuntimeError where there is none).
    """
    text = os.fspath(path)
    seps = tuple("~" + s for s in filter(None, (os.sep, os.altsep)))
    if isinstance(text, str) and (text == "~" or text.startswith(seps)):
        return Path(os.path.expanduser(text))  # no home known: left as it is, never raises
    return Path(path)


def check_expected_sha256(sha256) -> str | None:
    """A reader's ``sha256=`` argument (the file's expected ``content_sha256``) in lower case,
    or None; GPMSAError unless it is None or 64 hexadecimal digits."""
    if sha256 is None:
        return None
    if not (isinstance(sha256, str) and re.fullmatch(r"[0-9a-fA-F]{64}", sha256.strip())):
        raise GPMSAError(f"sha256 must be 64 hexadecimal digits, got {str(sha256)[:80]!r}")
    return sha256.strip().lower()


def verify_content(manifest: dict, expected: str | None, path) -> None:
    """EmulatorFileError where ``expected`` (`check_expected_sha256`) is not None and differs
    from the file's ``content_sha256``."""
    if expected is not None and manifest["content_sha256"] != expected:
        raise EmulatorFileError(
            f"{path}: content sha256 {manifest['content_sha256']} differs from the expected "
            f"{expected!r}"
        )


def seal(manifest: dict, arrays: dict[str, np.ndarray], *, fmt: str = FORMAT) -> tuple[dict, bytes]:
    """``manifest`` with the container's envelope (``ENVELOPE``: format ``fmt``, schema and
    library versions, time, the arrays' shapes and dtypes, the content sha256) and its JSON as
    written. Raises GPMSAError for a record the reader would refuse (``check_writable``)."""
    reserved = sorted(set(manifest) & set(ENVELOPE))
    if reserved:
        raise GPMSAError(f"manifest fields {reserved} are written by the container itself")
    manifest = {
        **manifest,
        "format": fmt,
        "schema_version": SCHEMA_VERSION,
        "library_version": __version__,
        "created_utc": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "arrays": {k: {"shape": list(v.shape), "dtype": v.dtype.str} for k, v in arrays.items()},
    }
    try:  # the hash encodes the manifest first: a NaN or a set would raise from json
        _canonical(manifest)
        where = _key_not_str(manifest, "manifest")
    except (TypeError, ValueError, RecursionError) as exc:
        raise GPMSAError(f"the manifest is not JSON-able ({exc})") from exc
    if where is not None:  # JSON writes 2 as "2": the reader's hash would sort it otherwise
        raise GPMSAError(
            f"{where}: the manifest's keys must be strings (JSON writes them as strings, so "
            "the file would not read back as written)"
        )
    manifest["content_sha256"] = content_hash(arrays, manifest)
    return manifest, check_writable(manifest, arrays)


def write_raw(
    path: str | Path, manifest: dict, arrays: dict[str, np.ndarray], *, fmt: str = FORMAT
) -> Path:
    """Write ``manifest`` and ``arrays`` to ``path`` (a zip: manifest.json + arrays/NAME.npy).

    manifest: the content fields, JSON-able (see ``jsonable``); the envelope fields (``ENVELOPE``)
    are added here (``seal``). arrays: name -> array; names match ``NAME_RE``, dtypes are float64,
    int64 or bool, as the reader accepts. Everything the reader checks is checked first
    (``check_writable``): a record it would refuse raises GPMSAError and nothing is written. The
    zip is written as ``write_sealed`` writes it. ``fmt``: the format name written (``FORMAT``,
    or ``STUDY_FORMAT`` for a study). Returns the path.
    """
    path = check_path(path)
    _, raw = seal(manifest, arrays, fmt=fmt)
    return write_sealed(path, raw, arrays)


def write_sealed(
    path: str | Path, raw_manifest: bytes, arrays: dict[str, np.ndarray], stage=None
) -> Path:
    """Write a sealed record (``seal``'s JSON and the arrays) to ``path``.

    The zip is written to a new temporary file beside ``path``, checked as the reader checks a
    zip's structure and size (above ``limits.MAX_FILE_BYTES``: GPMSAError), flushed to disk and
    then moved over ``path`` in one step: a failure before the move leaves an existing ``path``
    untouched and no temporary file behind (an I/O error flushing the folder after it, a
    GPMSAError naming the folder, leaves the new file in place). ``stage``: an
    ``atomic_group``'s stage, to defer the move to the end of that group (several files replaced
    together); None: moved at once. A member that deflates beyond ``limits.MAX_RATIO`` (e.g.
    zero padding) is stored uncompressed. An existing ``path`` that is not a regular file (a
    directory, device, FIFO) is refused. Returns the path.
    """
    path = check_path(path)
    with (atomic_write if stage is None else stage)(path) as fh:
        with zipfile.ZipFile(fh, "w", compression=zipfile.ZIP_DEFLATED) as zf:
            _write_member(zf, MANIFEST, raw_manifest)
            for name, arr in arrays.items():
                _write_member(zf, ARRAY_DIR + name + ".npy", _npy_bytes(arr))
        size = fh.seek(0, os.SEEK_END)  # the reader's structural checks, before it is seen
        if size > limits.MAX_FILE_BYTES:
            raise GPMSAError(
                f"refusing to write {path}: the file would take {size} bytes, above "
                f"gpmsa.limits.MAX_FILE_BYTES = {limits.MAX_FILE_BYTES} that readers accept; "
                "keep fewer draws or outputs, or raise the limit (on every reader's machine too)"
            )
        _check_directory(fh, size, path)
        fh.seek(0)
        with zipfile.ZipFile(fh) as zf:
            _check_members(zf, path)
    return path


def _write_member(zf: zipfile.ZipFile, name: str, data: bytes) -> None:
    info = zipfile.ZipInfo(name, date_time=(1980, 1, 1, 0, 0, 0))
    info.compress_type = zipfile.ZIP_DEFLATED
    if _too_compressible(len(data), _deflated_size(data)):
        info.compress_type = zipfile.ZIP_STORED  # the reader would take it for a zip bomb
    info.external_attr = 0o644 << 16
    zf.writestr(info, data)


# --- reading ------------------------------------------------------------------------------------
def _fail(path, what: str) -> EmulatorFileError:
    return EmulatorFileError(f"{path}: {what}")


def _open_regular(path: Path):
    """Open ``path`` for reading if it is a regular file within the size limit; never opens a
    device, FIFO or directory (``/dev/zero`` would grow memory without end, a FIFO block)."""
    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError) as exc:
        raise EmulatorFileError(f"{path}: cannot read ({getattr(exc, 'strerror', exc)})") from exc
    if not stat.S_ISREG(mode):
        kind = "a directory" if stat.S_ISDIR(mode) else "a device, FIFO or socket"
        raise _fail(path, f"not a regular file ({kind}): gpmsa reads emulator files only")
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0)
    try:
        fd = os.open(path, flags)
    except OSError as exc:
        raise EmulatorFileError(f"{path}: cannot read ({exc.strerror})") from exc
    fh = os.fdopen(fd, "rb")
    st = os.fstat(fd)
    if not stat.S_ISREG(st.st_mode):  # replaced between the stat and the open
        fh.close()
        raise _fail(path, "not a regular file: gpmsa reads emulator files only")
    if st.st_size > limits.MAX_FILE_BYTES:
        fh.close()
        raise _fail(
            path, f"file is {st.st_size} bytes (limit gpmsa.limits.MAX_FILE_BYTES = "
                  f"{limits.MAX_FILE_BYTES})"
        )  # fmt: skip
    return fh, st.st_size


def _check_directory(fh, size: int, path) -> None:
    """Read the zip's end-of-central-directory record and refuse, before zipfile parses the
    directory, more entries or a larger directory than a gpmsa file has."""
    tail_len = min(size, 22 + 65535)
    fh.seek(size - tail_len)
    tail = fh.read(tail_len)
    at = tail.rfind(b"PK\x05\x06")
    if at < 0 or len(tail) - at < 22:
        fh.seek(0)
        if _cut_gpmsa(fh.read(len(CUT_HEAD))):
            raise _fail(path, f"{CUT_SHORT}: its zip end record is missing (not a readable zip; "
                              "an incomplete download or copy? fetch it again)")  # fmt: skip
        raise _fail(path, "not a gpmsa emulator file (not a readable zip: no end record)")
    (comment_len,) = struct.unpack("<H", tail[at + 20 : at + 22])
    if (extra := len(tail) - (at + 22 + comment_len)) != 0:
        what = f"{extra} bytes follow" if extra > 0 else "a truncated comment ends"
        raise _fail(path, f"damaged zip: {what} the end record (appended to, or cut?)")
    entries, cd_size = struct.unpack("<xxxxxxxxxxHI", tail[at : at + 16])
    # zipfile takes the sizes of a zip64 record whenever its locator precedes the end record
    # (whatever the classic fields say), reading the record just before the locator: check the
    # values zipfile will use
    end = size - tail_len + at  # where the end record starts
    fh.seek(max(end - 76, 0))
    before = fh.read(min(end, 76))
    rec, loc = before[:-20], before[-20:]
    if len(before) == 76 and loc[:4] == b"PK\x06\x07" and rec[:4] == b"PK\x06\x06":
        entries, cd_size = struct.unpack("<QQ", rec[32:48])
    elif entries == 0xFFFF or cd_size == 0xFFFFFFFF:
        raise _fail(path, "damaged zip64 end record")
    if entries > limits.MAX_MEMBERS:
        raise _fail(path, f"{entries} members (limit gpmsa.limits.MAX_MEMBERS = "
                          f"{limits.MAX_MEMBERS})")  # fmt: skip
    if cd_size > CENTRAL_ENTRY_MAX * max(entries, 1):
        raise _fail(path, f"zip directory of {cd_size} bytes for {entries} members")


CUT_HEAD = b"PK\x03\x04" + bytes(26) + MANIFEST.encode()
"""The start of every file gpmsa writes: a zip's first local header, of member manifest.json."""
CUT_SHORT = "a gpmsa file cut short"


def _cut_gpmsa(head: bytes) -> bool:
    """Whether ``head``, a file's first bytes, starts as gpmsa writes a file (``CUT_HEAD``, the
    header's fields aside): of a file without a zip end record, one cut short."""
    n = len(CUT_HEAD)
    return len(head) >= n and head[:4] == CUT_HEAD[:4] and head[30:n] == CUT_HEAD[30:]


def _read_member(zf: zipfile.ZipFile, info: zipfile.ZipInfo, path) -> bytearray:
    """A member's bytes (exactly its declared size, CRC checked), in a writable buffer that the
    loaded array then shares (no second copy of a large array)."""
    data = bytearray(info.file_size)
    view = memoryview(data)
    got = 0
    try:
        with zf.open(info) as fh:
            while got < info.file_size:  # in chunks: zipfile's read(n) would join a second copy
                chunk = fh.read(min(READ_CHUNK, info.file_size - got))
                if not chunk:
                    break
                view[got : got + len(chunk)] = chunk
                got += len(chunk)
            rest = fh.read(1)  # reaching the end checks the CRC
    except Exception as exc:  # zipfile/zlib raise many types on hostile bytes
        raise _fail(path, f"member {info.filename!r} is damaged ({exc})") from exc
    if got != info.file_size or rest:
        raise _fail(path, f"member {info.filename!r} size differs from its zip header")
    return data


def _check_members(zf: zipfile.ZipFile, path) -> dict[str, zipfile.ZipInfo]:
    infos = zf.infolist()
    if len(infos) > limits.MAX_MEMBERS:
        raise _fail(path, f"{len(infos)} members (limit {limits.MAX_MEMBERS})")
    if all(info.filename != MANIFEST for info in infos):  # before its members' names are judged
        if not infos:
            raise _fail(path, f"not a gpmsa emulator file (an empty zip: no {MANIFEST})")
        first = infos[0].filename
        npz = ": a numpy .npz such as a vehicle campaign file?" if first.endswith(".npy") else ""
        raise _fail(path, f"not a gpmsa emulator file (a zip without {MANIFEST}; its first "
                          f"member {first[:60]!r}{npz})")  # fmt: skip
    members: dict[str, zipfile.ZipInfo] = {}
    total = 0
    for info in infos:
        name = info.filename
        if name in members:
            raise _fail(path, f"duplicate member {name!r}")
        if name != MANIFEST:
            stem = (
                name[len(ARRAY_DIR) : -4]
                if name.startswith(ARRAY_DIR) and name.endswith(".npy")
                else ""
            )
            if not NAME_RE.match(stem):
                raise _fail(
                    path, f"unexpected member {name!r} (only {MANIFEST} and arrays/NAME.npy)"
                )
        if info.flag_bits & 0x1:
            raise _fail(path, f"member {name!r} is encrypted")
        if info.compress_type not in (zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED):
            raise _fail(path, f"member {name!r} uses compression method {info.compress_type} "
                              "(only stored or deflated)")  # fmt: skip
        if info.compress_type == zipfile.ZIP_STORED and info.file_size != info.compress_size:
            raise _fail(path, f"stored member {name!r} has unequal sizes in its zip header")
        if _too_compressible(info.file_size, info.compress_size):
            raise _fail(
                path, f"member {name!r} expands {info.file_size}/{info.compress_size}x (zip bomb?)"
            )
        if name == MANIFEST and info.file_size > limits.MAX_MANIFEST_BYTES:
            limit = limits.MAX_MANIFEST_BYTES
            raise _fail(path, f"{MANIFEST} declares {info.file_size} bytes (limit "
                              f"gpmsa.limits.MAX_MANIFEST_BYTES = {limit})")  # fmt: skip
        if name != MANIFEST:
            total += info.file_size
        members[name] = info
    if total > limits.MAX_ARRAY_BYTES:
        raise _fail(path, f"arrays of {total} bytes once decompressed exceed "
                          f"gpmsa.limits.MAX_ARRAY_BYTES = {limits.MAX_ARRAY_BYTES}")  # fmt: skip
    return members


MAX_MANIFEST_DEPTH = 72
"""Deepest nesting a manifest may have: a writer's metadata nests at most 64 levels, a few
more hold it; deeper JSON cannot be re-encoded within Python's recursion limit."""


def _nesting(value) -> int:
    """How deep JSON ``value`` nests (iteratively: no recursion on hostile input)."""
    deepest, stack = 0, [(value, 1)]
    while stack:
        item, depth = stack.pop()
        deepest = max(deepest, depth)
        if isinstance(item, dict):
            stack.extend((v, depth + 1) for v in item.values())
        elif isinstance(item, list):
            stack.extend((v, depth + 1) for v in item)
    return deepest


def _parse_manifest(raw: bytes, path, formats: tuple[str, ...] = (FORMAT,)) -> dict:
    def reject_constant(token):
        raise ValueError(f"non-standard JSON constant {token}")

    def finite_float(token):
        value = float(token)
        if not math.isfinite(value):  # 1e999 parses as inf
            raise ValueError(f"number {token[:40]} is beyond float64")
        return value

    def unique_keys(pairs):  # a repeated key would silently take its last value
        obj = dict(pairs)
        if len(obj) != len(pairs):
            seen = set()
            twice = next(k for k, _ in pairs if k in seen or seen.add(k))
            raise ValueError(f"key {_short(twice)} appears twice in one object")
        return obj

    try:
        manifest = json.loads(
            raw.decode("utf-8"), parse_constant=reject_constant, parse_float=finite_float,
            object_pairs_hook=unique_keys,
        )  # fmt: skip
    except (UnicodeDecodeError, ValueError, RecursionError) as exc:
        raise _fail(path, f"manifest.json is not valid JSON ({exc})") from exc
    if not isinstance(manifest, dict):
        raise _fail(path, "manifest.json must hold a JSON object")
    if _nesting(manifest) > MAX_MANIFEST_DEPTH:
        raise _fail(path, f"manifest.json nests deeper than {MAX_MANIFEST_DEPTH} levels")
    if manifest.get("format") not in formats:
        want = " or ".join(repr(f) for f in formats)
        kind = {FORMAT: "an emulator file, which gpmsa.load reads",
                STUDY_FORMAT: "a study file, which gpmsa.load_study reads"}  # fmt: skip
        found = manifest.get("format")
        what = kind.get(found, "foreign file") if isinstance(found, str) else "foreign file"
        raise _fail(path, f"format is {_short(manifest.get('format'))}, expected {want} ({what})")
    version = manifest.get("schema_version")
    if not isinstance(version, int) or isinstance(version, bool) or version < 1:
        raise _fail(path, f"schema_version must be a positive integer, got {_short(version)}")
    if version > SCHEMA_VERSION:
        raise _fail(
            path,
            f"schema_version {version} is newer than this library reads ({SCHEMA_VERSION}); "
            f"upgrade gpmsa (file written by gpmsa {_short(manifest.get('library_version'))})",
        )
    for key, kind in FIELDS:
        if not isinstance(manifest.get(key), kind):
            raise _fail(path, f"manifest field {key!r} missing or not a {kind.__name__}")
    return _upgrade(manifest)


def _short(value, n: int = 60) -> str:
    """repr of a value from a file, cut to ``n`` characters (messages stay readable)."""
    text = repr(value)
    return text if len(text) <= n else text[: n - 3] + "..."


def _upgrade(manifest: dict) -> dict:
    """Bring an older schema's manifest to the current one (schema 1 is the first)."""
    return manifest


def _check_specs(specs: dict, npy: dict[str, zipfile.ZipInfo], path) -> None:
    """Each listed array's declared shape and dtype, and its member's size, agree (checked
    before anything is decompressed)."""
    if set(specs) != set(npy):
        missing = sorted(set(specs) - set(npy))
        extra = sorted(set(npy) - set(specs))
        raise _fail(path, f"arrays do not match the manifest (missing {missing[:10]}, unlisted "
                          f"{extra[:10]})")  # fmt: skip
    for name, spec in specs.items():
        shape = spec.get("shape") if isinstance(spec, dict) else None
        dtype = spec.get("dtype") if isinstance(spec, dict) else None
        if not isinstance(dtype, str) or dtype not in ALLOWED_DTYPES:  # a list: unhashable
            allowed = sorted(ALLOWED_DTYPES)
            shown = dtype if isinstance(dtype, str) and len(dtype) < 20 else _short(dtype)
            raise _fail(path, f"array {name!r} has dtype {shown} (allowed {allowed}; "
                              "object/pickled arrays are refused)")  # fmt: skip
        if (
            not isinstance(shape, list)
            or len(shape) > MAX_NDIM
            or not all(isinstance(n, int) and not isinstance(n, bool) and n >= 0 for n in shape)
        ):
            raise _fail(path, f"manifest entry of array {name!r} is malformed: {_short(spec)}")
        nbytes = math.prod(shape) * np.dtype(dtype).itemsize
        extra = npy[name].file_size - nbytes
        if not 10 <= extra <= NPY_HEADER_MAX:
            raise _fail(
                path,
                f"array {name!r}: its member holds {npy[name].file_size} bytes, not a .npy of "
                f"shape {shape} {dtype} ({nbytes} bytes of data)",
            )
        if (why := _span_problem(name, shape, np.dtype(dtype).itemsize)) is not None:
            raise _fail(path, why)  # an empty array (a full one's size was checked just now)


def _load_array(raw: bytearray, name: str, spec: dict, path) -> np.ndarray:
    buf = io.BytesIO(bytes(raw[:NPY_HEADER_MAX]))  # the header only: BytesIO copies
    try:
        major, minor = np.lib.format.read_magic(buf)
        if (major, minor) == (1, 0):
            shape, fortran, dtype = np.lib.format.read_array_header_1_0(buf)
        elif (major, minor) == (2, 0):
            shape, fortran, dtype = np.lib.format.read_array_header_2_0(buf)
        else:
            raise ValueError(f"npy version {major}.{minor}")
    except Exception as exc:  # the header parser (literal_eval) raises many types
        raise _fail(path, f"array {name!r} has a bad .npy header ({exc})") from exc
    if dtype.str not in ALLOWED_DTYPES or dtype.hasobject:
        raise _fail(
            path, f"array {name!r} has dtype {dtype.str} (allowed {sorted(ALLOWED_DTYPES)})"
        )
    if list(shape) != spec["shape"] or dtype.str != spec.get("dtype"):
        raise _fail(path, f"array {name!r} is {dtype.str}{list(shape)}, manifest says "
                          f"{spec.get('dtype')}{spec['shape']}")  # fmt: skip
    offset = buf.tell()
    count = math.prod(shape)
    if len(raw) - offset != count * dtype.itemsize:
        need = count * dtype.itemsize
        raise _fail(path, f"array {name!r} is truncated or damaged (its data are "
                          f"{len(raw) - offset} bytes, its shape needs {need})")  # fmt: skip
    flat = np.frombuffer(raw, dtype=dtype, count=count, offset=offset)  # shares raw's memory
    return np.ascontiguousarray(flat.reshape(shape, order="F" if fortran else "C"))


def read_manifest(path: str | Path, formats: tuple[str, ...] = (FORMAT,)) -> dict:
    """The manifest of the gpmsa file at ``path`` with ``read_raw``'s checks of the zip and the
    envelope (``formats``: the format names accepted); no array is read, and the content is
    neither hashed nor validated. Raises EmulatorFileError naming the problem."""
    path = check_path(path)
    with _opened(path) as (zf, members):
        raw = bytes(_read_member(zf, members[MANIFEST], path))
    return _parse_manifest(raw, path, formats)


def stored_format(path: str | Path) -> str | None:
    """The format name (``FORMAT`` or ``STUDY_FORMAT``) of the gpmsa file at ``path``; None when
    there is none (no file, another kind of file, or one too damaged to tell). Reads the
    manifest only, with ``read_raw``'s checks; its content is not verified."""
    path = check_path(path)
    try:
        if not path.exists():
            return None
        return read_manifest(path, (FORMAT, STUDY_FORMAT))["format"]
    except Exception:  # any damage (or a name the OS refuses): not a gpmsa file to tell apart
        return None


def _gpmsa_layout(path: Path) -> bool:
    """Whether the regular file ``path`` is a zip laid out as a gpmsa file (``manifest.json``
    and ``arrays/*.npy`` members only): a file gpmsa wrote that ``stored_format`` cannot read
    (damaged content, a newer schema, sizes beyond the limits set now)."""
    try:
        with open(path, "rb") as fh:
            _check_directory(fh, os.fstat(fh.fileno()).st_size, path)  # bounds the directory
            fh.seek(0)
            with zipfile.ZipFile(fh) as zf:
                names = zf.namelist()
    except Exception:  # not a zip, or too damaged to tell: not known to be gpmsa's
        return False
    arrays = (n.startswith(ARRAY_DIR) and n.endswith(".npy") for n in names if n != MANIFEST)
    return MANIFEST in names and all(arrays)


def _declared_format(path: Path) -> str | None:
    """The format (``FORMAT`` or ``STUDY_FORMAT``) that a gpmsa file's manifest declares, read
    without the manifest's other checks (a newer schema, a field this version refuses); None
    where even that cannot be read."""
    try:
        with _opened(path) as (zf, members):
            raw = bytes(_read_member(zf, members[MANIFEST], path))
        declared = json.loads(raw.decode("utf-8")).get("format")
    except Exception:  # no file, not a zip, a manifest that is no JSON object: not known
        return None
    return declared if declared in (FORMAT, STUDY_FORMAT) else None


def _foreign_size(target: Path) -> int | None:
    """Size in bytes of the regular, non-empty file at ``target`` that is not a gpmsa file;
    None when replacing ``target`` loses nothing of another program's (no file, an empty one,
    a gpmsa file) or when it is not a regular file (``write_sealed`` refuses that)."""
    try:
        st = os.stat(target)
    except (OSError, ValueError):
        return None
    if not stat.S_ISREG(st.st_mode) or st.st_size == 0 or _gpmsa_layout(target):
        return None
    return st.st_size


def _starts_cut(target: Path) -> bool:
    """Whether the file at ``target`` starts as a gpmsa file does (`_cut_gpmsa`)."""
    try:
        with open(target, "rb") as fh:
            return _cut_gpmsa(fh.read(len(CUT_HEAD)))
    except OSError:
        return False


def refuse_to_replace(target: Path, fmt: str) -> None:
    """GPMSAError if ``target`` holds data a file of format ``fmt`` must not replace: a file that
    is not a gpmsa file (a user's CSV or notes; an empty file may be replaced), or a gpmsa file
    of the other kind, as a study written over an emulator file (another study's model, say) or
    an emulator file written over a study would leave that file's owner unreadable."""
    wanted = "a study file" if fmt == STUDY_FORMAT else "an emulator file"
    found = stored_format(target) or _declared_format(target)  # a newer schema's too
    if found is None:
        size = _foreign_size(target)
        if size is not None:
            held = CUT_SHORT if _starts_cut(target) else "a file that is not a gpmsa file"
            raise GPMSAError(
                f"refusing to write {target}: it holds {held} ({size} bytes), which {wanted} "
                "would replace; choose another path or remove it first"
            )
    elif found != fmt:
        held = (
            "a study file" if found == STUDY_FORMAT else "an emulator file (another study's model?)"
        )
        raise GPMSAError(
            f"refusing to write {target}: it holds {held}, which {wanted} would replace; "
            "choose another path or remove it first"
        )


@contextmanager
def _opened(path: Path) -> Iterator[tuple[zipfile.ZipFile, dict[str, zipfile.ZipInfo]]]:
    """The zip at ``path`` and its checked members (``read_raw``'s steps 1-3: a regular file
    within the size limit, its directory, then its members), open for reading."""
    fh, size = _open_regular(path)
    with fh:
        _check_directory(fh, size, path)
        fh.seek(0)
        try:
            zf = zipfile.ZipFile(fh)
        except Exception as exc:  # zipfile raises many types on hostile bytes
            raise _fail(path, f"not a gpmsa emulator file (not a readable zip: {exc})") from exc
        with zf:
            yield zf, _check_members(zf, path)


def read_raw(
    path: str | Path,
    check: Callable[[dict], None] | None = None,
    *,
    formats: tuple[str, ...] = (FORMAT,),
) -> tuple[dict, dict[str, np.ndarray]]:
    """Validated manifest and arrays of an emulator file (no Emulator built).

    Only regular files are read. Before anything is decompressed: the file's size, the zip's
    directory (members, names, compression, ratios, declared sizes against gpmsa.limits), the
    manifest, and each array's declared shape and dtype against its member's size; then
    ``check(manifest)`` (the caller's test of the declared content, e.g. consistent shapes).
    ``formats``: the format names accepted (default: an emulator file). Raises
    EmulatorFileError naming the problem.
    """
    path = check_path(path)
    with _opened(path) as (zf, members):
        raw = bytes(_read_member(zf, members[MANIFEST], path))
        manifest = _parse_manifest(raw, path, formats)
        specs = manifest["arrays"]
        npy = {n[len(ARRAY_DIR) : -4]: info for n, info in members.items() if n != MANIFEST}
        _check_specs(specs, npy, path)
        if check is not None:
            try:
                check(manifest)
            except EmulatorFileError as exc:
                raise _fail(path, str(exc)) from exc
        arrays = {
            name: _load_array(_read_member(zf, info, path), name, specs[name], path)
            for name, info in npy.items()
        }
    if content_hash(arrays, manifest) != manifest["content_sha256"]:
        raise _fail(
            path, "content hash mismatch: the file was edited or damaged after it was written"
        )
    return manifest, arrays
