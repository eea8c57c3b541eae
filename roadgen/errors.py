"""Exceptions raised by roadgen, and the text of the numbers in their messages."""

import math


class RoadgenError(ValueError):
    """Invalid input to a roadgen function (a ValueError subclass)."""


def distinct_texts(*values: float, digits: int = 6) -> tuple[str, ...]:
    """``values`` (a value and the bounds it is checked against, say) as text for a message:
    ``digits`` significant digits; where two distinct values would read alike so, each by its
    shortest round-trip repr (exact), so that a value 1e-9 past a bound of 20 does not read
    "20" beside "20" (``vehicle`` uses it too)."""
    floats = [float(v) for v in values]
    finite = {v for v in floats if math.isfinite(v)}
    if len({f"{v:.{digits}g}" for v in finite}) == len(finite):  # (the usual case)
        return tuple(f"{v:.{digits}g}" for v in floats)
    return tuple(repr(v) for v in floats)
