"""Checks shared by vehicle's functions: roadgen's checks (``roadgen.checks``) raising VehicleError
(numbers, integers, flags, arrays, choices, bands, seeds) and the memory limit.

Resource limit: ``MAX_MEMORY_BYTES`` (module attribute, read at call time). A drive is
integrated only when the memory of its time grid (about ``BYTES_PER_STEP`` per solver step) and
of a speed schedule of position (``kinematics.BYTES_PER_POSITION`` per mm), and a design only
when its table, fit below it; otherwise VehicleError states the estimate and the
limit. A program that has the memory raises it: ``vehicle.checks.MAX_MEMORY_BYTES = 16 *
1024**3``. The road itself is limited by ``roadgen.checks.MAX_MEMORY_BYTES``.
"""

from __future__ import annotations

import math

import numpy as np

from roadgen import checks as roadgen_checks
from roadgen.errors import distinct_texts
from vehicle.errors import VehicleError

MAX_MEMORY_BYTES = 4 * 1024**3
"""Largest memory (bytes) one call may need; change it by assignment."""
BYTES_PER_STEP = 96
"""Memory per solver step of a drive: the position and speed grids, their block copies, the
road heights and slopes under both tyres, and the sampled states (one row per substeps)."""


def memory(nbytes: float, what: str) -> None:
    """Raise VehicleError when ``nbytes`` (an estimate) exceeds ``MAX_MEMORY_BYTES``."""
    roadgen_checks.memory_limit(
        nbytes, what, MAX_MEMORY_BYTES, "vehicle.checks.MAX_MEMORY_BYTES",
        "use smaller settings", VehicleError,
    )  # fmt: skip


def seed(name: str, value, generator: bool = True):
    """Return ``value`` if it is None, an integer in [0, 2**128) or (``generator``) a numpy
    Generator; else raise VehicleError (roadgen's check with vehicle's error)."""
    return roadgen_checks.seed(name, value, generator, VehicleError)


def real(name: str, value: object) -> float:
    """``value`` as a float if it is a real number (not a bool, string or complex), else
    VehicleError; NaN and inf pass."""
    return roadgen_checks.real(name, value, VehicleError)


def integer(name: str, value: object, minimum: int) -> int:
    """``value`` as an int if it is a Python or numpy integer (not a bool) >= ``minimum``, else
    VehicleError."""
    return roadgen_checks.integer(name, value, minimum, VehicleError)


def flag(name: str, value: object) -> bool:
    """``value`` as a bool if it is True or False, else VehicleError."""
    return roadgen_checks.flag(name, value, VehicleError)


def real_array(name: str, value: object) -> np.ndarray:
    """``value`` as a new float array if it holds real numbers, else VehicleError
    (``roadgen.checks.real_array``: bools are refused, also inside a list)."""
    return roadgen_checks.real_array(name, value, VehicleError)


def positive(name: str, value: object, unit: str = "") -> float:
    """``value`` as a float if it is a finite real number > 0, else VehicleError."""
    return roadgen_checks.positive(name, value, VehicleError, unit)


def non_negative(name: str, value: object, unit: str = "") -> float:
    """``value`` as a float if it is a finite real number >= 0, else VehicleError."""
    return roadgen_checks.non_negative(name, value, VehicleError, unit)


def grid_step(name: str, value: object, length_m: float, length_name: str) -> float:
    """``value`` as a float if it is a road's grid step: in [``roadgen.checks.MIN_DX_M``,
    ``MAX_DX_M``] m and leaving a road of ``length_m`` (the argument ``length_name``) at least 2
    whole steps (at most length_m / 1.5, as ``roadgen.profile.grid_points`` rounds), else
    VehicleError stating that range."""
    v = real(name, value)
    if not math.isfinite(v):
        raise VehicleError(f"{name}={value!r} must be finite")
    low, high = roadgen_checks.MIN_DX_M, roadgen_checks.MAX_DX_M
    if not (low <= v <= high and round(length_m / v) >= 2):
        most = distinct_texts(v, min(high, length_m / 1.5))[1]
        raise VehicleError(
            f"{name}={value!r} is out of range: allowed [{low:g}, {most}] "
            f"m (a road's grid step, at most {length_name} / 1.5: each road holds at least 2 "
            "whole steps)"
        )
    return v


def choice(name: str, value: object, allowed: tuple[str, ...]) -> str:
    """``value`` if it is one of the strings ``allowed``, else VehicleError."""
    return roadgen_checks.choice(name, value, allowed, VehicleError)


def pair(name: str, value: object, what: str) -> tuple[float, float]:
    """``value`` as two floats if it is a pair of real numbers, else VehicleError."""
    return roadgen_checks.pair(name, value, what, VehicleError)


def band(name: str, value: object, nyquist: float) -> tuple[float, float]:
    """A band (n_min, n_max) cycles/m with 0 < n_min < n_max <= nyquist, else VehicleError."""
    return roadgen_checks.band(name, value, nyquist, VehicleError)
