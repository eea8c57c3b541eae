"""The fields and methods that every road (Profile, Track) shares: a uniform grid of heights."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import overload

import numpy as np

from roadgen import checks
from roadgen.errors import RoadgenError


@dataclass(frozen=True, eq=False)
class Road:
    """Heights ``z`` (N,) m at positions ``x`` (N,) m = 0, dx_m, ..., (N - 1) dx_m.

    The arrays are stored read-only. Subclasses add what the road was made from.
    """

    x: np.ndarray
    z: np.ndarray
    dx_m: float

    def __post_init__(self) -> None:
        dx = checks.grid_step("dx_m", self.dx_m)
        x = checks.real_array("x", self.x)
        z = checks.real_array("z", self.z)
        if x.ndim != 1 or z.shape != x.shape or x.size < 2:
            raise RoadgenError(
                f"x and z must be 1-D arrays of the same length >= 2, got shapes {x.shape} "
                f"and {z.shape}"
            )
        if not (np.all(np.isfinite(x)) and np.all(np.isfinite(z))):
            raise RoadgenError("x and z must be finite (found NaN or inf)")
        grid = np.arange(x.size) * dx
        if np.max(np.abs(x - grid)) > 1e-6 * dx:
            raise RoadgenError(f"x must be the uniform grid 0, dx_m, 2 dx_m, ... with dx_m={dx}")
        x.setflags(write=False)
        z.setflags(write=False)
        object.__setattr__(self, "x", x)
        object.__setattr__(self, "z", z)
        object.__setattr__(self, "dx_m", dx)

    @property
    def length_m(self) -> float:
        """Length of the road, x[-1], m."""
        return float(self.x[-1])

    @overload
    def height_at(self, s: float | np.floating) -> float: ...
    @overload
    def height_at(self, s: np.ndarray | Sequence[float]) -> np.ndarray: ...
    def height_at(
        self, s: float | np.floating | np.ndarray | Sequence[float]
    ) -> float | np.ndarray:
        """Height (m) at positions ``s`` (m, any shape, in [0, length_m]), linearly interpolated.

        Returns an array of the shape of ``s`` (a float for a scalar). Raises RoadgenError for a
        position outside the road or NaN.
        """
        arr = checks.positions("s", s, self.length_m)
        out = np.interp(arr, self.x, self.z)
        return float(out) if out.ndim == 0 else out


def check_road(name: str, value: object) -> Road:
    """Return ``value`` if it is a roadgen Road (a Profile, a Track), else raise RoadgenError."""
    if not isinstance(value, Road):
        raise RoadgenError(
            f"{name}={type(value).__name__} is not allowed: need a roadgen Road (a Profile or "
            "Track)"
        )
    return value
