"""Resource limits of gpmsa: one place, read at call time, changed by assignment.

Every call that could allocate a lot (a long MCMC, a fine calibration grid, a big emulator, an
emulator file) estimates the memory it needs *before* allocating and refuses with
``gpmsa.ResourceLimitError`` (a ``GPMSAError``) stating the estimate, the limit and how to
change it, instead of being killed by the out-of-memory killer. The limits are plain module
attributes, looked up when a function runs, so a program that knows it has the memory raises them
once::

    import gpmsa
    gpmsa.limits.MAX_MEMORY_BYTES = 16 * 1024**3      # 16 GiB per call

The file limits apply to reading and writing alike: ``Emulator.save`` refuses (before writing)
any file that ``gpmsa.load`` would refuse under the same limits.
"""

from __future__ import annotations

from gpmsa.errors import ResourceLimitError

GIB = 1024**3
MIB = 1024**2

MAX_MEMORY_BYTES = 4 * GIB
"""Largest estimated working memory of one call (fit, calibrate, Calibrator, predict, ...)."""

BYTES_PER_HISTOGRAM_BIN = 10_000
"""matplotlib's memory per histogram bar (one Rectangle patch, about 9 KB measured): what a
plot's ``bins=`` is charged against ``MAX_MEMORY_BYTES``."""

MAX_OBS_VALUES = 128
"""Largest size d = n_rows * p_u of an observation's reduced data in one calibration. The exact
likelihood needs a d x d eigendecomposition per theta node (grid) or per proposal (MCMC), so its
cost grows as d^3: one Calibrator update of a scalar output took 0.27 s for 64 rows, 1.4 s for
128 and 7.1 s for 256 here (the issue: 11.8 s for 400). Split long records into windows (their
``Calibrator.log_likelihood_grid`` values add) or raise this limit."""

MAX_INDEX_SIMPLICES = 2_000_000
"""Most simplices an output index of three or more columns may triangulate into at worst,
l^ceil(d/2) (the upper bound theorem; two columns: at most 2 l, no limit): 3 or 4 columns up to
1,414 points, 5 or 6 up to 125 (80 points in 10 columns: 1.2 million simplices, 50 s and 1 GB).
A regular grid in three columns triangulates into ~6 l: raise this for one of more points."""

# --- the emulator file (gpmsa.io.container) -----------------------------------------------------
MAX_FILE_BYTES = 2 * GIB
"""Largest emulator file on disk."""
MAX_ARRAY_BYTES = 1 * GIB
"""Largest total size of the arrays of an emulator file once decompressed (their .npy members)."""
MAX_MANIFEST_BYTES = 16 * MIB
"""Largest manifest.json (names, settings, metadata, diagnostics) of an emulator file."""
MAX_MEMBERS = 512
"""Most members (arrays plus the manifest) of an emulator file."""
MAX_RATIO = 200
"""Largest uncompressed/compressed size ratio of a compressed member (zip-bomb guard); the
writer stores a member that deflates better than this uncompressed instead."""


def _size(nbytes: float) -> str:
    for unit, scale in (("PiB", 1024**5), ("TiB", 1024**4), ("GiB", GIB), ("MiB", MIB)):
        if nbytes >= scale:
            return f"{nbytes / scale:.3g} {unit}"
    return f"{nbytes:.0f} bytes"


def check_memory(nbytes: float, what: str) -> None:
    """Raise ResourceLimitError when ``nbytes`` (an estimate) exceeds ``MAX_MEMORY_BYTES``.

    ``what`` says what needs the memory and why (e.g. "Calibrator: a 10000000-node grid x 198
    runs"); the message adds the estimate, the limit and how to raise it.
    """
    limit = MAX_MEMORY_BYTES
    if isinstance(limit, bool) or not isinstance(limit, int | float) or not limit > 0:
        raise ResourceLimitError(
            f"gpmsa.limits.MAX_MEMORY_BYTES must be a number of bytes > 0 (inf: no limit), got "
            f"{limit!r}"
        )
    if nbytes > limit:
        raise ResourceLimitError(
            f"{what} needs about {_size(nbytes)} of memory, above the limit "
            f"gpmsa.limits.MAX_MEMORY_BYTES = {_size(MAX_MEMORY_BYTES)}; use smaller settings, "
            "or raise the limit (gpmsa.limits.MAX_MEMORY_BYTES = ...) if the machine has it"
        )
