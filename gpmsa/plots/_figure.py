"""A bare matplotlib Figure (no pyplot state, no GUI backend), the histograms' bin check, and
the axes' labels."""

from __future__ import annotations

from gpmsa.limits import BYTES_PER_HISTOGRAM_BIN, check_memory
from gpmsa.model.data import check_count


def figure(width: float, height: float):
    """A constrained-layout Figure of the given size in inches (matplotlib imported here)."""
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), layout="constrained")


def check_bins(bins, n_hist: int, what: str) -> int:
    """``bins`` as an int >= 1 whose ``n_hist`` histograms fit ``gpmsa.limits.MAX_MEMORY_BYTES``
    (GPMSAError, or ResourceLimitError stating the limit, otherwise)."""
    bins = check_count(bins, "bins")
    check_memory(
        BYTES_PER_HISTOGRAM_BIN * bins * n_hist, f"{what}: {n_hist} histogram(s) of {bins} bins"
    )
    return bins


def axis_label(name: str, unit: str) -> str:
    """``name (unit)``, every figure's label of a quantity, or the name alone without a unit."""
    return f"{name} ({unit})" if unit else name
