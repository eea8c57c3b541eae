"""Checks shared by vehicle's functions: seeds and the memory limit.

Resource limit: ``MAX_MEMORY_BYTES`` (module attribute, read at call time). A drive is
integrated only when the memory of its time grid (about ``BYTES_PER_STEP`` per solver step) and
a design only when its table fit below it; otherwise VehicleError states the estimate and the
limit. A program that has the memory raises it: ``vehicle.checks.MAX_MEMORY_BYTES = 16 *
1024**3``. The road itself is limited by ``roadgen.checks.MAX_MEMORY_BYTES``.
"""

from __future__ import annotations

import numpy as np

from vehicle.errors import VehicleError

MAX_MEMORY_BYTES = 4 * 1024**3
"""Largest memory (bytes) one call may need; change it by assignment."""
BYTES_PER_STEP = 96
"""Memory per solver step of a drive: the position and speed grids, their block copies, the
road heights and slopes under both tyres, and the sampled states (one row per substeps)."""
MAX_SEED = 2**128


def memory(nbytes: float, what: str) -> None:
    """Raise VehicleError when ``nbytes`` (an estimate) exceeds ``MAX_MEMORY_BYTES``."""
    if nbytes > MAX_MEMORY_BYTES:
        raise VehicleError(
            f"{what} needs about {nbytes / 1024**3:.3g} GiB of memory, above the limit "
            f"vehicle.checks.MAX_MEMORY_BYTES = {MAX_MEMORY_BYTES / 1024**3:.3g} GiB; use "
            "smaller settings, or raise the limit (vehicle.checks.MAX_MEMORY_BYTES = ...) if "
            "the machine has the memory"
        )


def seed(name: str, value, generator: bool = True):
    """Return ``value`` if it is None, an integer in [0, 2**128) or (``generator``) a numpy
    Generator; else raise VehicleError (numpy refuses a negative seed only deep inside
    SeedSequence, as a bare ValueError)."""
    if value is None or (generator and isinstance(value, np.random.Generator)):
        return value
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        kinds = "None, an integer or a numpy Generator" if generator else "None or an integer"
        raise VehicleError(f"{name}={value!r} must be {kinds} (got {type(value).__name__})")
    if not 0 <= int(value) < MAX_SEED:
        raise VehicleError(f"{name}={int(value)} is out of range: allowed integers in [0, 2**128)")
    return int(value)
