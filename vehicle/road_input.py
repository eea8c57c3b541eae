"""The road as the tyres see it: height u(s) and slope du/ds, linearly interpolated."""

from __future__ import annotations

import numpy as np

import roadgen
from roadgen import checks as roadgen_checks
from roadgen.errors import distinct_texts
from vehicle.errors import VehicleError


class RoadInput:
    """Height and slope of a uniformly sampled road (a roadgen Profile or Track).

    Beyond its ends the road continues flat at its first / last height (so a vehicle may start
    with its rear axle behind the road's start). The slope du/ds is computed once by central
    finite differences (``numpy.gradient``).

    Args:
        road: object with ``z`` (N,) heights in m on a uniform grid of spacing ``dx_m`` from 0.
        wheel_radius_m: if given, the road is first enveloped by a rigid wheel of this radius
            (``roadgen.wheel_envelope``): what the tyre's contact point follows. VehicleError
            for a road shorter than the radius.
    """

    def __init__(self, road, wheel_radius_m: float | None = None) -> None:
        if wheel_radius_m is not None:
            if not isinstance(road, roadgen.Road):
                raise VehicleError(
                    f"road={type(road).__name__} cannot be enveloped: need a roadgen Profile or "
                    "Track (or envelope=False)"
                )
            if wheel_radius_m > road.length_m:  # roadgen's error would name its own radius_m
                length = distinct_texts(wheel_radius_m, road.length_m)[1]
                raise VehicleError(
                    f"road length {length} m is shorter than the wheel radius "
                    f"wheel_radius_m={wheel_radius_m!r} m: it cannot be enveloped (use a longer "
                    "road, or envelope=False)"
                )
            road = roadgen.wheel_envelope(road, wheel_radius_m)
        z, dx = roadgen_checks.heights("road", road, VehicleError, min_points=3)
        self.dx_m = dx
        self.length_m = dx * (z.size - 1)
        self._z = z
        self._x = dx * np.arange(z.size)
        self._slope = np.gradient(z, dx)

    def heights(self, s: np.ndarray) -> np.ndarray:
        """Heights (m) at positions ``s`` (m), any shape; flat beyond the ends."""
        return np.interp(s, self._x, self._z)

    def slopes(self, s: np.ndarray) -> np.ndarray:
        """Slopes du/ds (-) at positions ``s`` (m), any shape; 0 beyond the ends."""
        return np.interp(s, self._x, self._slope, left=0.0, right=0.0)
