"""A bare matplotlib Figure (no pyplot state, no GUI backend)."""

from __future__ import annotations


def figure(width: float, height: float):
    """A constrained-layout Figure of the given size in inches (matplotlib imported here)."""
    from matplotlib.figure import Figure

    return Figure(figsize=(width, height), layout="constrained")
