"""Latin-hypercube designs over speed and road roughness (the paper's 198-run LHS)."""

from __future__ import annotations

import math

import numpy as np
from scipy.stats import qmc

from roadgen.errors import distinct_texts
from vehicle import checks
from vehicle.errors import VehicleError
from vehicle.models import Model


def _range(name: str, value: tuple[float, float]) -> tuple[float, float]:
    lo, hi = checks.pair(name, value, "(low, high)")
    if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo < hi):
        raise VehicleError(f"{name}={value!r} is out of range: need 0 < low < high, finite")
    return lo, hi


def lhs_design(
    n: int = 198,
    v_range: tuple[float, float] = (0.5, 2.0),
    gd_range: tuple[float, float] = (200.0, 600.0),
    seed: int | np.integer | np.random.Generator | None = None,
) -> np.ndarray:
    """A Latin-hypercube design (scipy.stats.qmc.LatinHypercube) of ``n`` points.

    Returns an array (n, 2): column 0 speed v (m/s) uniform on ``v_range``, column 1 GD
    (1e-6 m^3) uniform on ``gd_range`` (the paper's priors, eqs. 3-4).

    Raises VehicleError for an n that is not an integer >= 1, a range that is not a pair of real
    numbers 0 < low < high, or a bad seed.
    """
    n = checks.integer("n", n, 1)
    checks.memory(64.0 * n, f"a design of n={n} points")
    seed = checks.seed("seed", seed)
    lo_v, hi_v = _range("v_range", v_range)
    lo_g, hi_g = _range("gd_range", gd_range)
    unit = qmc.LatinHypercube(d=2, rng=np.random.default_rng(seed)).random(n)
    return qmc.scale(unit, [lo_v, lo_g], [hi_v, hi_g])


def check_design(design: np.ndarray, model: Model) -> np.ndarray:
    """Return ``design`` as a float (n, 2) array [v, GD], or raise VehicleError if a point lies
    outside the model's validity: v in (0, max_speed_mps], GD > 0, all finite."""
    arr = checks.real_array("design", design)
    if arr.ndim != 2 or arr.shape[1] != 2 or arr.shape[0] < 1:
        raise VehicleError(f"design has shape {arr.shape}: need (n, 2) columns [v, GD], n >= 1")
    v, gd = arr[:, 0], arr[:, 1]
    bad_v = ~np.isfinite(v) | (v <= 0) | (v > model.max_speed_mps)
    if np.any(bad_v):
        i = int(np.argmax(bad_v))
        most = distinct_texts(v[i], model.max_speed_mps)[1]
        raise VehicleError(
            f"design[{i}] has v={float(v[i])!r} m/s: allowed (0, {most}] m/s for {model.name}"
        )
    bad_g = ~np.isfinite(gd) | (gd <= 0)
    if np.any(bad_g):
        i = int(np.argmax(bad_g))
        raise VehicleError(f"design[{i}] has GD={float(gd[i])!r}: allowed (0, inf) (1e-6 m^3)")
    return arr
