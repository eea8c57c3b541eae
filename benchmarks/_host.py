"""The host's load, which every benchmark prints beside its timings."""

from __future__ import annotations

import os


def load_average() -> tuple[float, float, float]:
    """``os.getloadavg()`` (runnable processes averaged over 1, 5 and 15 min), or three NaNs
    where the OS keeps none (Windows has no ``getloadavg``)."""
    try:
        return os.getloadavg()
    except (AttributeError, OSError):
        return (float("nan"),) * 3
