"""The emulator file (``*.gpmsa``): a zip of .npy arrays plus ``manifest.json``.

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

from gpmsa.errors import EmulatorFileError, GPMSAError
from gpmsa.fitting.emulator import EMULATOR_PARAMS, Emulator
from gpmsa.model.priors import Priors
from gpmsa.model.transforms import Standardizer

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

STD_FIELDS = ("x_min", "x_max", "t_min", "t_max", "y_mean", "grid")
REQUIRED = ("x_unit", "t_unit", "y", "K", "w", "log_post", "y_sd", *STD_FIELDS) + tuple(
    f"param_{k}" for k in EMULATOR_PARAMS
)


def _library_version() -> str:
    from gpmsa import __version__

    return __version__


def _jsonable(obj):
    """Replace non-finite floats (not valid JSON) by None, recursively; tuples become lists."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.generic):
        return _jsonable(obj.item())
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


def _arrays_of(emu: Emulator) -> dict[str, np.ndarray]:
    s = emu.standardizer
    arrays = {
        "x_unit": emu.x_unit, "t_unit": emu.t_unit, "y": emu.y, "K": emu.K, "w": emu.w,
        "x_min": s.x_min, "x_max": s.x_max, "t_min": s.t_min, "t_max": s.t_max,
        "y_mean": s.y_mean, "y_sd": np.array([s.y_sd]), "grid": s.grid, "log_post": emu.log_post,
    }  # fmt: skip
    if emu.index is not None:
        arrays["index"] = emu.index
    for k, v in emu.params.items():
        arrays[f"param_{k}"] = v
    for k, v in emu.draws.items():
        arrays[f"draw_{k}"] = v
    for k, v in (emu.calibration or {}).items():
        arrays[f"cal_{k}"] = v
    return {k: np.ascontiguousarray(v, dtype=np.float64) for k, v in arrays.items()}


def build_manifest(emu: Emulator, arrays: dict[str, np.ndarray]) -> dict:
    """The manifest dict of ``emu`` (without checking JSON-ability)."""
    manifest = {
        "format": FORMAT,
        "schema_version": SCHEMA_VERSION,
        "library_version": _library_version(),
        "created_utc": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "names": {"x": list(emu.x_names), "t": list(emu.t_names), "y": list(emu.y_names)},
        "units": {"x": list(emu.x_units), "t": list(emu.t_units), "y": list(emu.y_units)},
        "domain": {k: list(v) for k, v in emu.domain.items()},
        "model": {
            "m": emu.m,
            "p": emu.p,
            "q": emu.q,
            "p_u": emu.p_u,
            "l_sim": emu.l_sim,
            "correlation": "R(a,b) = exp(-sum_k beta_k (a_k - b_k)^2) on unit-scale inputs",
            "noise": "w_j ~ GP(0, R/lamUz_j) + nugget 1/lamWs_j; residual outside the basis "
            "has precision lamWOs * lam_sim_j; outputs standardised by y_mean, y_sd",
            "point_estimate": emu.settings.get("point", "given"),
        },  # fmt: skip
        "priors": emu.priors.to_dict(),
        "settings": emu.settings,
        "metadata": emu.metadata,
        "diagnostics": emu.diagnostics,
        "arrays": {k: {"shape": list(v.shape), "dtype": v.dtype.str} for k, v in arrays.items()},
    }
    return _jsonable(manifest)


def save(emu: Emulator, path: str | Path) -> Path:
    """Write ``emu`` to ``path`` (a zip: manifest.json + arrays/NAME.npy). Returns the path."""
    path = Path(path)
    arrays = _arrays_of(emu)
    manifest = build_manifest(emu, arrays)
    try:
        json.dumps(manifest["metadata"], allow_nan=False)
    except (TypeError, ValueError) as exc:
        raise GPMSAError(
            f"Emulator.metadata must be JSON-able (str, numbers, lists, dicts): {exc}"
        ) from exc
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
    for key, kind in (("arrays", dict), ("names", dict), ("units", dict), ("priors", dict),
                      ("settings", dict), ("metadata", dict), ("diagnostics", dict),
                      ("content_sha256", str)):  # fmt: skip
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


def load(path: str | Path) -> Emulator:
    """Read an emulator file written by ``Emulator.save`` (any older schema; never unpickles).

    Raises EmulatorFileError naming the problem for a damaged, edited, foreign or newer file.
    """
    manifest, arrays = read_raw(path)
    missing = [k for k in REQUIRED if k not in arrays]
    if missing:
        raise _fail(path, f"required arrays missing: {missing}")
    try:
        std = Standardizer(**{k: arrays[k] for k in STD_FIELDS}, y_sd=float(arrays["y_sd"][0]))
        names = {k: tuple(manifest["names"][k]) for k in ("x", "t", "y")}
        units = {k: tuple(manifest["units"][k]) for k in ("x", "t", "y")}
        draws = {k[5:]: v for k, v in arrays.items() if k.startswith("draw_")}
        cal = {k[4:]: v for k, v in arrays.items() if k.startswith("cal_")} or None
        emu = Emulator(
            standardizer=std, x_unit=arrays["x_unit"], t_unit=arrays["t_unit"], y=arrays["y"],
            K=arrays["K"], w=arrays["w"], index=arrays.get("index"),
            params={k: arrays[f"param_{k}"] for k in EMULATOR_PARAMS},
            priors=Priors.from_dict(manifest["priors"]), names=names, units=units,
            draws=draws, log_post=arrays["log_post"], metadata=manifest["metadata"],
            settings=manifest["settings"], diagnostics=manifest["diagnostics"], calibration=cal,
        )  # fmt: skip
        _check_consistent(emu)
        domain = {k: list(v) for k, v in emu.domain.items()}
        if manifest.get("domain") != domain:
            raise ValueError(
                f"manifest domain {manifest.get('domain')} differs from the arrays' {domain}"
            )
    except EmulatorFileError:
        raise
    except (GPMSAError, KeyError, TypeError, ValueError, IndexError) as exc:
        raise _fail(path, f"inconsistent content ({type(exc).__name__}: {exc})") from exc
    return emu


def _check_consistent(emu: Emulator) -> None:
    m, p, q, l_sim, p_u = emu.m, emu.p, emu.q, emu.l_sim, emu.p_u
    checks = {
        "t_unit": (emu.t_unit.shape, (m, q)), "y": (emu.y.shape, (m, l_sim)),
        "w": (emu.w.shape, (m, p_u)), "x_min": (emu.standardizer.x_min.shape, (p,)),
        "t_min": (emu.standardizer.t_min.shape, (q,)),
        "y_mean": (emu.standardizer.y_mean.shape, (l_sim,)),
        "names.x": ((len(emu.x_names),), (p,)), "names.t": ((len(emu.t_names),), (q,)),
    }  # fmt: skip
    for what, (got, want) in checks.items():
        if tuple(got) != tuple(want):
            raise ValueError(f"{what} has shape {got}, expected {want}")
    for k, v in emu.draws.items():
        if v.shape[1:] != emu.params[k].shape or v.shape[0] != emu.n_draws:
            raise ValueError(f"draws of {k} have shape {v.shape}")
