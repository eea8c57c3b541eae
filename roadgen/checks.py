"""Input checks shared by roadgen's functions; each raises RoadgenError naming the argument.

Resource limit: ``MAX_MEMORY_BYTES`` (module attribute, read at call time). A road is made only
when the memory its synthesis needs (about ``BYTES_PER_POINT`` per grid point) is below it;
otherwise RoadgenError states the estimate and the limit. A program that has the memory raises
it: ``roadgen.checks.MAX_MEMORY_BYTES = 16 * 1024**3``.
"""

from __future__ import annotations

import math

import numpy as np

from roadgen.errors import RoadgenError

MAX_MEMORY_BYTES = 4 * 1024**3
"""Largest memory (bytes) one call may need; change it by assignment."""
BYTES_PER_POINT = 96
"""Memory a road's synthesis needs per grid point: x, z and the unit road (8 bytes each), the
half-length complex spectrum with its phases and amplitudes, the inverse FFT's work space, the
taper and the amplitude profile."""
MAX_SEED = 2**128


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
        raise error(
            f"{what} needs about {nbytes / 1024**3:.3g} GiB of memory, above the limit "
            f"{setting} = {limit / 1024**3:.3g} GiB; {advice}, or raise the limit ({setting} "
            "= ...) if the machine has the memory"
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


def positive(name: str, value: float) -> float:
    """Return ``value`` as a float, or raise if it is not a finite number > 0."""
    v = _finite(name, value)
    if v <= 0.0:
        raise RoadgenError(f"{name}={value!r} is out of range: allowed (0, inf)")
    return v


def non_negative(name: str, value: float) -> float:
    """Return ``value`` as a float, or raise if it is not a finite number >= 0."""
    v = _finite(name, value)
    if v < 0.0:
        raise RoadgenError(f"{name}={value!r} is out of range: allowed [0, inf)")
    return v


def choice(name: str, value: str, allowed: tuple[str, ...]) -> str:
    """Return ``value`` if it is one of ``allowed``, else raise."""
    if value not in allowed:
        raise RoadgenError(f"{name}={value!r} is not allowed: choose one of {allowed}")
    return value


def band(name: str, value: tuple[float, float], nyquist: float) -> tuple[float, float]:
    """Check a band (n_min, n_max) in cycles/m: 0 < n_min < n_max <= nyquist."""
    try:
        lo, hi = (float(b) for b in value)
    except (TypeError, ValueError) as exc:
        raise RoadgenError(f"{name}={value!r} must be a pair (n_min, n_max) in cycles/m") from exc
    if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 < lo < hi <= nyquist):
        raise RoadgenError(
            f"{name}={value!r} is out of range: need 0 < n_min < n_max <= {nyquist:.6g} "
            "cycles/m (the Nyquist frequency 1/(2 dx_m) of the grid)"
        )
    return lo, hi


def positions(name: str, s: np.ndarray | float, length_m: float) -> np.ndarray:
    """Return ``s`` as a float array, or raise if any position is NaN or outside [0, length_m]."""
    arr = np.asarray(s, dtype=float)
    tol = 1e-9 * max(length_m, 1.0)
    bad = ~np.isfinite(arr) | (arr < -tol) | (arr > length_m + tol)
    if np.any(bad):
        first = arr[bad].flat[0]
        raise RoadgenError(
            f"{name} contains {first!r}: allowed positions are [0, {length_m:.6g}] m"
        )
    return np.clip(arr, 0.0, length_m)


def _finite(name: str, value: float) -> float:
    try:
        v = float(value)
    except (TypeError, ValueError) as exc:
        raise RoadgenError(f"{name}={value!r} must be a real number") from exc
    if not math.isfinite(v):
        raise RoadgenError(f"{name}={value!r} must be finite")
    return v
