"""Input checks shared by roadgen's functions; each raises RoadgenError naming the argument
(those with an ``error`` parameter raise that class instead: ``vehicle.checks`` reuses them
with VehicleError).

Resource limit: ``MAX_MEMORY_BYTES`` (module attribute, read at call time). A road is made only
when the memory its synthesis needs (about ``BYTES_PER_POINT`` per grid point) is below it;
otherwise RoadgenError states the estimate and the limit. A program that has the memory raises
it: ``roadgen.checks.MAX_MEMORY_BYTES = 16 * 1024**3``.
"""

from __future__ import annotations

import math
import numbers
import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from roadgen.errors import RoadgenError, distinct_texts

MAX_MEMORY_BYTES = 4 * 1024**3
"""Largest memory (bytes) one call may need; change it by assignment."""
BYTES_PER_POINT = 96
"""Memory a road's synthesis needs per grid point: x, z and the unit road (8 bytes each), the
half-length complex spectrum with its phases and amplitudes, the inverse FFT's work space, the
taper and the amplitude profile."""
MAX_SEED = 2**128
MIN_DX_M, MAX_DX_M = 1e-9, 1e6
"""Grid steps allowed, m: beyond them a road's spatial frequencies under- or overflow."""
MIN_GD = 1e-12
"""Smallest GD allowed (1e-6 m^3): below it the PSD and the heights' squares underflow."""


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


def memory(nbytes: float, what: str) -> None:
    """Raise RoadgenError when ``nbytes`` (an estimate) exceeds ``MAX_MEMORY_BYTES``."""
    memory_limit(
        nbytes, what, MAX_MEMORY_BYTES, "roadgen.checks.MAX_MEMORY_BYTES",
        "use a shorter road or a coarser dx_m", RoadgenError,
    )  # fmt: skip


def memory_limit(
    nbytes: float, what: str, limit: float, setting: str, advice: str, error: type[Exception]
) -> None:
    """Raise ``error`` when ``nbytes`` (an estimate) exceeds ``limit``, naming the ``setting``
    that holds the limit and the ``advice`` (shared with ``vehicle.checks``)."""
    if nbytes > limit:
        need, most = distinct_texts(nbytes / 1024**3, limit / 1024**3, digits=3)
        raise error(
            f"{what} needs about {need} GiB of memory, above the limit {setting} = {most} GiB; "
            f"{advice}, or raise the limit ({setting} = ...) if the machine has the memory"
        )


def seed(
    name: str, value, generator: bool = True, error: type[Exception] = RoadgenError
):  # fmt: skip
    """Return ``value`` if it is None, an integer in [0, 2**128) or (``generator``) a numpy
    Generator; else raise ``error`` (numpy refuses a negative seed only deep inside
    SeedSequence). ``vehicle.checks`` calls it with its own error class."""
    if value is None or (generator and isinstance(value, np.random.Generator)):
        return value
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        kinds = "None, an integer or a numpy Generator" if generator else "None or an integer"
        raise error(f"{name}={value!r} must be {kinds} (got {type(value).__name__})")
    if not 0 <= int(value) < MAX_SEED:
        raise error(f"{name}={int(value)} is out of range: allowed integers in [0, 2**128)")
    return int(value)


def real(name: str, value: object, error: type[Exception] = RoadgenError) -> float:
    """Return ``value`` as a float if it is a real number: a Python or numpy int or float (or a
    0-d array of one), not a bool, a string or a complex number; else raise ``error``. NaN and
    inf pass."""
    if isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind in "iuf":
        value = value.item()
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise error(f"{name}={value!r} must be a real number (got {type(value).__name__})")
    try:
        return float(value)
    except OverflowError:  # an int beyond float64's range
        bits = int(value).bit_length()  # (str() of a huge int is itself refused by Python)
        raise error(
            f"{name}=<an integer of {bits} bits> is out of range: beyond float64's"
        ) from None


def integer(name: str, value: object, minimum: int, error: type[Exception] = RoadgenError) -> int:
    """Return ``value`` as an int if it is a Python or numpy integer (or a 0-d array of one), not
    a bool, and >= ``minimum``; else raise ``error``."""
    if isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind in "iu":
        value = value.item()
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
        raise error(
            f"{name}={value!r} must be an integer >= {minimum} (got {type(value).__name__})"
        )
    if value < minimum:
        raise error(f"{name}={int(value)} is out of range: allowed integers >= {minimum}")
    return int(value)


def flag(name: str, value: object, error: type[Exception] = RoadgenError) -> bool:
    """Return ``value`` as a bool if it is True or False (Python or numpy); else raise ``error``
    (a string such as "no" or a number is not read as a truth value)."""
    if not isinstance(value, (bool, np.bool_)):
        raise error(f"{name}={value!r} must be True or False (got {type(value).__name__})")
    return bool(value)


def tensor_values(value: object) -> object:
    """``value``, or for a torch tensor (an object with a bool ``requires_grad`` and a
    ``detach`` method) the tensor without its gradient record: numpy refuses one that records
    gradients ("Can't call numpy() on Tensor that requires grad"); only the values are read."""
    if getattr(value, "requires_grad", None) is True and callable(getattr(value, "detach", None)):
        return value.detach()
    return value


def real_array(name: str, value: object, error: type[Exception] = RoadgenError) -> np.ndarray:
    """Return ``value`` as a new float array if it holds real numbers (ints or floats, not
    bools, strings, complex numbers or objects); else raise ``error``. NaN and inf pass. A bool
    inside a list is refused too (numpy would read ``[[True, 300]]`` as integers). A torch
    tensor's values are read (`tensor_values`)."""
    value = tensor_values(value)
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError) as exc:  # e.g. ragged nested lists
        raise error(f"{name} must be an array of real numbers: {exc}") from exc
    if arr.dtype.kind not in "iuf":
        raise error(f"{name} must be an array of real numbers, got dtype {arr.dtype}")
    if not isinstance(value, np.ndarray) and any(
        isinstance(x, bool | np.bool_) for x in np.asarray(value, dtype=object).flat
    ):
        raise error(f"{name} must be an array of real numbers, got a bool element")
    return arr.astype(float)


def positive(
    name: str, value: object, error: type[Exception] = RoadgenError, unit: str = ""
) -> float:
    """Return ``value`` as a float, or raise ``error`` if it is not a finite real number > 0
    (``unit`` ends the range in the message)."""
    v = _finite(name, value, error)
    if v <= 0.0:
        raise error(f"{name}={value!r} is out of range: allowed (0, inf){_unit(unit)}")
    return v


def grid_step(name: str, value: object, error: type[Exception] = RoadgenError) -> float:
    """Return ``value`` as a float, or raise ``error`` unless it is a grid step in
    [MIN_DX_M, MAX_DX_M] m."""
    v = _finite(name, value, error)
    if not MIN_DX_M <= v <= MAX_DX_M:
        raise error(
            f"{name}={value!r} is out of range: allowed [{MIN_DX_M:g}, {MAX_DX_M:g}] m (a road's "
            "grid step)"
        )
    return v


def gd(name: str, value: object, error: type[Exception] = RoadgenError) -> float:
    """Return ``value`` as a float, or raise ``error`` unless it is a finite GD >= MIN_GD
    (units 1e-6 m^3)."""
    v = _finite(name, value, error)
    if v < MIN_GD:
        raise error(
            f"{name}={value!r} is out of range: allowed [{MIN_GD:g}, inf) in 1e-6 m^3 (ISO 8608's "
            "smoothest class A lies below 32)"
        )
    return v


def non_negative(
    name: str, value: object, error: type[Exception] = RoadgenError, unit: str = ""
) -> float:
    """Return ``value`` as a float, or raise ``error`` if it is not a finite real number >= 0
    (``unit`` ends the range in the message)."""
    v = _finite(name, value, error)
    if v < 0.0:
        raise error(f"{name}={value!r} is out of range: allowed [0, inf){_unit(unit)}")
    return v


def choice(
    name: str, value: object, allowed: tuple[str, ...], error: type[Exception] = RoadgenError
) -> str:
    """Return ``value`` if it is one of the strings ``allowed``, else raise ``error``."""
    if not isinstance(value, str) or value not in allowed:
        raise error(f"{name}={value!r} is not allowed: choose one of {allowed}")
    return value


def pair(
    name: str, value: object, what: str, error: type[Exception] = RoadgenError
) -> tuple[float, float]:
    """Return ``value`` as two floats if it is a tuple, list or array of two real numbers (NaN
    and inf pass); else raise ``error`` saying it must be a pair ``what``."""
    items = tuple(value) if isinstance(value, (tuple, list, np.ndarray)) else ()
    if len(items) != 2:
        raise error(f"{name}={value!r} must be a pair {what}")
    lo, hi = (real(f"{name}[{i}]", b, error) for i, b in enumerate(items))
    return lo, hi


def band(
    name: str, value: tuple[float, float], nyquist: float, error: type[Exception] = RoadgenError
) -> tuple[float, float]:
    """Return a band (n_min, n_max) in cycles/m as floats, or raise ``error`` unless it is a
    pair of real numbers with 0 < n_min < n_max <= nyquist."""
    lo, hi = pair(name, value, "(n_min, n_max) in cycles/m", error)
    if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 < lo < hi <= nyquist):
        top = distinct_texts(hi, nyquist)[1]
        raise error(
            f"{name}={value!r} is out of range: need 0 < n_min < n_max <= {top} "
            "cycles/m (the Nyquist frequency 1/(2 dx_m) of the grid)"
        )
    return lo, hi


def positions(
    name: str, s: float | np.floating | np.ndarray | Sequence[float], length_m: float
) -> np.ndarray:
    """Return ``s`` as a float array, or raise if any position is NaN or outside [0, length_m]."""
    arr = real_array(name, s)
    tol = 1e-9 * max(length_m, 1.0)
    bad = ~np.isfinite(arr) | (arr < -tol) | (arr > length_m + tol)
    if np.any(bad):
        first = float(arr[bad].flat[0])
        end = distinct_texts(first, length_m)[1]
        raise RoadgenError(f"{name} contains {first!r}: allowed positions are [0, {end}] m")
    return np.clip(arr, 0.0, length_m)


def heights(
    name: str, road: object, error: type[Exception] = RoadgenError, min_points: int = 2
) -> tuple[np.ndarray, float]:
    """Return the heights z (N,) m and grid step dx_m of ``road`` (anything with ``z`` and
    ``dx_m``: a Profile, a Track), or raise ``error`` unless z is a finite real (N,) array,
    N >= ``min_points``, and dx_m a grid step in [MIN_DX_M, MAX_DX_M] m (``vehicle``'s road
    input uses it with VehicleError and 3 points)."""
    try:
        z, dx = road.z, road.dx_m
    except AttributeError:
        raise error(
            f"{name}={type(road).__name__} must have heights z (N,) m and a grid step dx_m "
            "(a roadgen Profile or Track)"
        ) from None
    arr = real_array(f"{name}.z", z, error)
    if arr.ndim != 1 or arr.size < min_points:
        raise error(f"{name}.z has shape {arr.shape}: need (N,) heights with N >= {min_points}")
    if not np.all(np.isfinite(arr)):
        raise error(f"{name}.z contains NaN or inf: allowed finite heights in m")
    return arr, grid_step(f"{name}.dx_m", dx, error)


def _finite(name: str, value: object, error: type[Exception]) -> float:
    v = real(name, value, error)
    if not math.isfinite(v):
        raise error(f"{name}={value!r} must be finite")
    return v


def _unit(unit: str) -> str:
    return f" {unit}" if unit else ""
