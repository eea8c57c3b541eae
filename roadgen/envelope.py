"""Geometric enveloping: the path of a rigid wheel's lowest point rolling over a profile."""

from __future__ import annotations

import dataclasses
from typing import TypeVar

import numpy as np

from roadgen import checks
from roadgen.errors import RoadgenError, distinct_texts
from roadgen.road import Road, check_road

R = TypeVar("R", bound=Road)


MAX_ENVELOPE_WORK = 2e10
"""Most (grid point, neighbour) pairs one ``wheel_envelope`` call visits (~10 s)."""


def wheel_envelope(road: R, radius_m: float) -> R:
    """The road as a rigid wheel of radius ``radius_m`` (m) sees it; same type, z replaced.

    z_env[i] = max over |x_j - x_i| <= r of z[j] + sqrt(r^2 - (x_j - x_i)^2) - r: the height of the
    wheel's lowest point when the circle above x_i rests on the profile (a morphological dilation
    by a disc). Properties: z_env >= z; equal on a flat road; dips narrower than the wheel are
    bridged; it grows with r and tends to z as r -> 0 (r < dx_m gives z back). Beyond the ends
    the road is not known and gives no support. Cost O(N r / dx): one vectorised max per
    neighbour offset.

    Raises RoadgenError for a radius that is not finite and > 0, larger than the road's length,
    or whose cost, N x r / dx_m neighbours, exceeds MAX_ENVELOPE_WORK.
    """
    check_road("road", road)
    r = checks.positive("radius_m", radius_m)
    if r > road.length_m:
        raise RoadgenError(
            f"radius_m={radius_m!r} is out of range: allowed (0, "
            f"{distinct_texts(r, road.length_m)[1]}] m (the "
            "road's length; a wheel in m, not mm?)"
        )
    z = road.z
    n = z.size
    reach = min(int(np.floor(r / road.dx_m * (1.0 + 1e-12))), n - 1)
    if float(reach) * n > MAX_ENVELOPE_WORK:
        work, most = distinct_texts(float(reach) * n, MAX_ENVELOPE_WORK, digits=3)
        raise RoadgenError(
            f"radius_m={radius_m!r} reaches {reach} grid steps on each side of {n} points: "
            f"{work} comparisons, above MAX_ENVELOPE_WORK = {most}; use a shorter road or a "
            "coarser grid"
        )
    env = z.copy()
    for m in range(1, reach + 1):
        d = m * road.dx_m
        sag = r - np.sqrt(max(r * r - d * d, 0.0))  # r <= length_m: r * r cannot overflow
        np.maximum(env[:-m], z[m:] - sag, out=env[:-m])
        np.maximum(env[m:], z[:-m] - sag, out=env[m:])
    return dataclasses.replace(road, z=env)
