"""Checks shared by vehicle's functions: seeds and the memory limit.

Resource limit: ``MAX_MEMORY_BYTES`` (module attribute, read at call time). A drive is
integrated only when the memory of its time grid (about ``BYTES_PER_STEP`` per solver step) and
a design only when its table fit below it; otherwise VehicleError states the estimate and the
limit. A program that has the memory raises it: ``vehicle.checks.MAX_MEMORY_BYTES = 16 *
1024**3``. The road itself is limited by ``roadgen.checks.MAX_MEMORY_BYTES``.
"""

from __future__ import annotations

from roadgen import checks as roadgen_checks
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
