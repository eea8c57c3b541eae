"""ISO 8608 facts: the reference frequency, the displacement PSD model and the road classes.

ISO 8608 describes a road by the one-sided PSD of its vertical displacement,
``Gd(n) = Gd(n0) (n / n0)^-w`` with ``n`` the spatial frequency (cycles/m), ``n0 = 0.1``
cycles/m and waviness ``w = 2``. Following the paper, ``GD = Gd(n0) * 1e6`` (units 1e-6 m^3).
"""

from __future__ import annotations

import bisect
import math

import numpy as np

from roadgen import checks
from roadgen.errors import RoadgenError

N0 = 0.1
"""Reference spatial frequency n0 of ISO 8608, cycles/m."""

GD_SCALE = 1e-6
"""Gd(n0) in m^3 per unit of GD."""

MAX_WAVINESS = 5.0
"""Largest waviness w accepted (ISO 8608: 2; measured roads lie between about 1.5 and 3.5).
Beyond it ``estimate_gd``'s end-matched fit fails (the leakage of the end match, falling as n^-2,
swamps the road's PSD at 1 cycle/m: +18% at w = 6 on 150 m) and Gd overflows sooner."""

CLASS_LOWER_BOUNDS: tuple[tuple[str, float], ...] = (
    ("A", 0.0),
    ("B", 32.0),
    ("C", 128.0),
    ("D", 512.0),
    ("E", 2048.0),
    ("F", 8192.0),
    ("G", 32768.0),
    ("H", 131072.0),
)
"""ISO 8608 road classes and the lower GD bound of each (each class spans a factor of 4)."""


def gd_spectrum(n: np.ndarray, gd: float, waviness: float = 2.0) -> np.ndarray:
    """One-sided displacement PSD Gd(n) in m^3 for spatial frequencies ``n`` (cycles/m, > 0, any
    shape), a road of ``gd`` (> 0, units 1e-6 m^3) and ``waviness`` w in (0, MAX_WAVINESS].

    Raises RoadgenError for a frequency that is not finite and > 0, so low that Gd(n)
    overflows the float range (below 1.6e-157 cycles/m for GD 450, w = 2) or so high that it
    underflows, a gd below ``checks.MIN_GD`` or a bad waviness.
    """
    arr = checks.real_array("n", n)
    bad = ~np.isfinite(arr) | (arr <= 0.0)
    if np.any(bad):
        first = float(arr[bad].flat[0])
        raise RoadgenError(f"n contains {first!r}: allowed frequencies in (0, inf) cycles/m")
    g = checks.gd("gd", gd)
    w = check_waviness("waviness", waviness)
    with np.errstate(over="ignore", divide="ignore", under="ignore"):
        out = g * GD_SCALE * (arr / N0) ** (-w)
    if np.any(out < np.finfo(float).tiny):
        raise RoadgenError(
            f"n contains {float(np.max(arr))!r}: Gd(n) underflows for gd={g:g}, waviness={w:g}; "
            "allowed frequencies where Gd(n) > 2.2e-308 m^3"
        )
    if not np.all(np.isfinite(out)):
        # (Python floats: a subnormal quotient, no FloatingPointError under np.seterr)
        n_min = N0 * (g * GD_SCALE / float(np.finfo(float).max)) ** (1.0 / w)
        raise RoadgenError(
            f"n contains {float(np.min(arr))!r}: Gd(n) overflows for gd={g:g}, waviness={w:g}; "
            f"allowed frequencies above about {n_min:.3g} cycles/m"
        )
    return out


def check_waviness(name: str, value: object) -> float:
    """Return ``value`` as a float, or raise RoadgenError unless it is a real number in
    (0, MAX_WAVINESS]."""
    w = checks.real(name, value)
    if not math.isnan(w) and not 0.0 < w <= MAX_WAVINESS:
        raise RoadgenError(
            f"{name}={value!r} is out of range: allowed (0, {MAX_WAVINESS:g}] (ISO 8608: 2)"
        )
    return checks.positive(name, value)


def road_class(gd: float) -> str:
    """ISO 8608 road class ("A".."H") of a road with the given GD (units 1e-6 m^3, > 0).

    Classes (lower bound inclusive): A < 32, B 32-128, C 128-512, D 512-2048, E 2048-8192,
    F 8192-32768, G 32768-131072, H >= 131072. The paper's Table 1 prints B's upper limit as 28;
    that is a typo for 128 (the bounds grow by a factor of 4 per class).
    """
    g = checks.positive("gd", gd)
    bounds = [b for _, b in CLASS_LOWER_BOUNDS]
    return CLASS_LOWER_BOUNDS[bisect.bisect_right(bounds, g) - 1][0]
