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
import zipfile
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from gpmsa._version import __version__
from gpmsa.errors import EmulatorFileError, GPMSAError

FORMAT = "gpmsa-emulator"
SCHEMA_VERSION = 1
MANIFEST = "manifest.json"
ARRAY_DIR = "arrays/"
NAME_RE = re.compile(r"^[A-Za-z0-9_]{1,64}$")
ALLOWED_DTYPES = {"<f8", "<i8", "|b1"}
MAX_FILE_BYTES = 2 * 1024**3
MAX_TOTAL_BYTES = 4 * 1024**3
MAX_MEMBERS = 512
MAX_MANIFEST_BYTES = 16 * 1024**2
MAX_RATIO = 200
"""Largest allowed uncompressed/compressed size ratio of a member (zip-bomb guard)."""

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


def _canonical(manifest: dict) -> bytes:
    body = {k: v for k, v in manifest.items() if k != "content_sha256"}
    return json.dumps(body, sort_keys=True, separators=(",", ":"), allow_nan=False).encode()


def content_hash(arrays: dict[str, np.ndarray], manifest: dict) -> str:
    """sha256 over every array (name, dtype, shape, bytes; sorted by name) and the manifest."""
    h = hashlib.sha256()
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        h.update(f"{name}\0{a.dtype.str}\0{a.shape}\0".encode())
        h.update(a.tobytes())
    h.update(_canonical(manifest))
    return h.hexdigest()


def write_raw(path: str | Path, manifest: dict, arrays: dict[str, np.ndarray]) -> Path:
    """Write ``manifest`` and ``arrays`` to ``path`` (a zip: manifest.json + arrays/NAME.npy).

    manifest: the content fields, JSON-able (see ``jsonable``); the envelope fields (``ENVELOPE``)
    are added here. arrays: name -> array; names match ``NAME_RE``, dtypes are float64, int64 or
    bool, as the reader accepts. The zip is written beside ``path`` and then moved over it.
    Returns the path.
    """
    path = Path(path)
    reserved = sorted(set(manifest) & set(ENVELOPE))
    if reserved:
        raise GPMSAError(f"manifest fields {reserved} are written by the container itself")
    for name, arr in arrays.items():
        if not NAME_RE.match(name) or arr.dtype.str not in ALLOWED_DTYPES:
            raise GPMSAError(
                f"array {name!r} ({arr.dtype.str}): names must match {NAME_RE.pattern} and "
                f"dtypes be one of {sorted(ALLOWED_DTYPES)}"
            )
    manifest = {
        **manifest,
        "format": FORMAT,
        "schema_version": SCHEMA_VERSION,
        "library_version": __version__,
        "created_utc": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "arrays": {k: {"shape": list(v.shape), "dtype": v.dtype.str} for k, v in arrays.items()},
    }
    manifest["content_sha256"] = content_hash(arrays, manifest)
    tmp = path.with_name(path.name + ".part")
    with zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        zf.writestr(MANIFEST, json.dumps(manifest, indent=1, sort_keys=True, allow_nan=False))
        for name, arr in arrays.items():
            buf = io.BytesIO()
            np.save(buf, arr, allow_pickle=False)
            zf.writestr(ARRAY_DIR + name + ".npy", buf.getvalue())
    os.replace(tmp, path)
    return path


# --- reading ------------------------------------------------------------------------------------
def _fail(path, what: str) -> EmulatorFileError:
    return EmulatorFileError(f"{path}: {what}")


def _read_member(zf: zipfile.ZipFile, info: zipfile.ZipInfo, path, limit: int) -> bytes:
    if info.file_size > limit:
        raise _fail(
            path, f"member {info.filename!r} declares {info.file_size} bytes (limit {limit})"
        )
    try:
        with zf.open(info) as fh:
            data = fh.read(limit + 1)
    except Exception as exc:  # zipfile/zlib raise many types on hostile bytes
        raise _fail(path, f"member {info.filename!r} is damaged ({exc})") from exc
    if len(data) != info.file_size:
        raise _fail(path, f"member {info.filename!r} size differs from its zip header")
    return data


def _check_members(zf: zipfile.ZipFile, path) -> dict[str, zipfile.ZipInfo]:
    infos = zf.infolist()
    if len(infos) > MAX_MEMBERS:
        raise _fail(path, f"{len(infos)} members (limit {MAX_MEMBERS})")
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
        if info.file_size > MAX_RATIO * max(info.compress_size, 1) + 1024:
            raise _fail(
                path, f"member {name!r} expands {info.file_size}/{info.compress_size}x (zip bomb?)"
            )
        total += info.file_size
        members[name] = info
    if total > MAX_TOTAL_BYTES:
        raise _fail(path, f"uncompressed size {total} exceeds {MAX_TOTAL_BYTES} bytes")
    if MANIFEST not in members:
        raise _fail(path, f"no {MANIFEST}: not a gpmsa emulator file")
    return members


def _parse_manifest(raw: bytes, path) -> dict:
    def reject_constant(token):
        raise ValueError(f"non-standard JSON constant {token}")

    try:
        manifest = json.loads(raw.decode("utf-8"), parse_constant=reject_constant)
    except (UnicodeDecodeError, ValueError, RecursionError) as exc:
        raise _fail(path, f"manifest.json is not valid JSON ({exc})") from exc
    if not isinstance(manifest, dict):
        raise _fail(path, "manifest.json must hold a JSON object")
    if manifest.get("format") != FORMAT:
        raise _fail(
            path, f"format is {manifest.get('format')!r}, expected {FORMAT!r} (foreign file)"
        )
    version = manifest.get("schema_version")
    if not isinstance(version, int) or isinstance(version, bool) or version < 1:
        raise _fail(path, f"schema_version must be a positive integer, got {version!r}")
    if version > SCHEMA_VERSION:
        raise _fail(
            path,
            f"schema_version {version} is newer than this library reads ({SCHEMA_VERSION}); "
            f"upgrade gpmsa (file written by gpmsa {manifest.get('library_version')!r})",
        )
    for key, kind in FIELDS:
        if not isinstance(manifest.get(key), kind):
            raise _fail(path, f"manifest field {key!r} missing or not a {kind.__name__}")
    return _upgrade(manifest)


def _upgrade(manifest: dict) -> dict:
    """Bring an older schema's manifest to the current one (schema 1 is the first)."""
    return manifest


def _load_array(raw: bytes, name: str, spec, path) -> np.ndarray:
    if not isinstance(spec, dict) or not isinstance(spec.get("shape"), list):
        raise _fail(path, f"manifest entry of array {name!r} is malformed")
    buf = io.BytesIO(raw)
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
    try:
        arr = np.load(io.BytesIO(raw), allow_pickle=False)
    except Exception as exc:  # np.load on damaged bytes raises many types
        raise _fail(path, f"array {name!r} is truncated or damaged ({exc})") from exc
    return arr


def read_raw(path: str | Path) -> tuple[dict, dict[str, np.ndarray]]:
    """Validated manifest and arrays of an emulator file (no Emulator built)."""
    path = Path(path)
    try:
        size = path.stat().st_size
    except OSError as exc:
        raise EmulatorFileError(f"{path}: cannot read ({exc.strerror})") from exc
    if size > MAX_FILE_BYTES:
        raise _fail(path, f"file is {size} bytes (limit {MAX_FILE_BYTES})")
    try:
        zf = zipfile.ZipFile(path)
    except Exception as exc:  # zipfile raises many types on hostile bytes
        raise _fail(path, f"not a gpmsa emulator file (not a readable zip: {exc})") from exc
    with zf:
        members = _check_members(zf, path)
        manifest = _parse_manifest(
            _read_member(zf, members[MANIFEST], path, MAX_MANIFEST_BYTES), path
        )
        specs = manifest["arrays"]
        npy = {n[len(ARRAY_DIR) : -4]: info for n, info in members.items() if n != MANIFEST}
        if set(specs) != set(npy):
            missing = sorted(set(specs) - set(npy))
            extra = sorted(set(npy) - set(specs))
            raise _fail(
                path, f"arrays do not match the manifest (missing {missing}, unlisted {extra})"
            )
        arrays = {
            name: _load_array(_read_member(zf, info, path, MAX_FILE_BYTES), name, specs[name], path)
            for name, info in npy.items()
        }
    if content_hash(arrays, manifest) != manifest["content_sha256"]:
        raise _fail(
            path, "content hash mismatch: the file was edited or damaged after it was written"
        )
    return manifest, arrays
