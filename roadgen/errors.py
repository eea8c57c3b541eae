"""Exceptions raised by roadgen, and the text of the numbers in their messages."""

import math
from decimal import ROUND_CEILING, ROUND_FLOOR, Decimal


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


def bound_text(value: float, up: bool, digits: int = 6) -> str:
    """``value`` as text for a message's advice, ``digits`` significant digits rounded up
    (``up``: a least value to give) or down (a most), so that the number a user copies from the
    text still meets the bound (``length_m >= 66.6607`` for a need of 66.66066, not 66.6607
    rounded from 66.66074); rounded to nearest where that number meets it too (``n_min >= 0.1``
    for the float 0.1, not 0.100001)."""
    v = float(value)
    text = f"{v:.{digits}g}"
    if not math.isfinite(v) or (float(text) >= v if up else float(text) <= v):
        return text
    exact = Decimal(v)
    step = Decimal(1).scaleb(exact.adjusted() - digits + 1)
    rounded = exact.quantize(step, rounding=ROUND_CEILING if up else ROUND_FLOOR)
    return f"{float(rounded):.{digits}g}"
