"""Longitudinal motion of the front axle: position s(t) and speed v(t) on a uniform time grid.

The vehicle body stays at x = 0 in the Exudyn model; the tyres read the road at s(t) (front) and
s(t) - wheelbase (rear). ``Drive`` holds that grid; the Exudyn models tabulate the road under
each tyre on it.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from scipy.integrate import cumulative_trapezoid

from roadgen.errors import distinct_texts
from vehicle import checks
from vehicle.errors import VehicleError

MAX_DRIVE_S = 3600.0
"""Longest drive (s) that ``schedule_grid``, hence ``simulate``, integrates (module attribute,
read at call time)."""

BYTES_PER_POSITION = 48
"""Memory per point of a position schedule's 1 mm grid (measured): the positions, the speeds,
their inverse and the cumulative time."""

SpeedSchedule = float | Callable | tuple
"""A constant speed (m/s); a callable of time (s) or of position (m); or a pair of arrays
(points, speeds) interpolated linearly and held constant beyond the ends."""


class Drive:
    """Front-axle position and speed on the grid t0 + k h (k = 0..N), linearly interpolated."""

    def __init__(self, t0: float, h: float, s: np.ndarray, v: np.ndarray) -> None:
        self.set(t0, h, s, v)

    def set(self, t0: float, h: float, s: np.ndarray, v: np.ndarray) -> None:
        """Replace the grid: ``s``, ``v`` of shape (N + 1,) at times t0 + k h."""
        self.t0 = float(t0)
        self.h = float(h)
        self.s = np.asarray(s, dtype=float)
        self.v = np.asarray(v, dtype=float)

    def positions(self, t: np.ndarray) -> np.ndarray:
        """Positions (m) at times ``t`` (s), vectorised."""
        return np.interp(t, self.t0 + self.h * np.arange(self.s.size), self.s)

    def speeds(self, t: np.ndarray) -> np.ndarray:
        """Speeds (m/s) at times ``t`` (s), vectorised."""
        return np.interp(t, self.t0 + self.h * np.arange(self.v.size), self.v)


def _too_long(seconds: float, max_duration_s: float) -> str:
    """The message for a drive of ``seconds`` s, longer than ``max_duration_s`` s."""
    took = distinct_texts(seconds, max_duration_s, digits=4)[0]
    return f"the drive takes {took} s: allowed <= {distinct_texts(seconds, max_duration_s)[1]} s"


def check_speed(
    name: str, v: np.ndarray | float, max_speed: float, allow_stop: bool = False
) -> np.ndarray:
    """Return speeds as an array or raise VehicleError unless all are finite and in (0, max]
    ([0, max] with ``allow_stop``: a commanded standstill)."""
    arr = np.asarray(v, dtype=float)
    low = (arr < 0.0) if allow_stop else (arr <= 0.0)
    bad = ~np.isfinite(arr) | low | (arr > max_speed * (1 + 1e-12))
    if np.any(bad):
        bracket = "[0" if allow_stop else "(0"
        first = float(arr[bad].flat[0])
        raise VehicleError(
            f"{name}={first!r} m/s is out of range: allowed "
            f"{bracket}, {distinct_texts(first, max_speed)[1]}] m/s (finite, at most the model's "
            "max_speed_mps)"
        )
    return arr


def _as_function(speed: SpeedSchedule) -> Callable[[np.ndarray], np.ndarray]:
    if callable(speed):

        def evaluate(x: np.ndarray) -> np.ndarray:
            try:  # a copy: a callable that edits its input cannot edit the schedule's grid
                out = checks.real_array("speed(...)", speed(x.copy()))
            except (TypeError, ValueError):  # a scalar function (VehicleError is a ValueError)
                out = None
            if out is None or out.shape != x.shape:
                out = np.array([checks.real(f"speed({xi:.6g})", speed(xi)) for xi in x])
            return out

        return evaluate
    if isinstance(speed, tuple):
        if len(speed) != 2:
            raise VehicleError(f"speed is a tuple of {len(speed)} items: need (points, speeds)")
        pts = checks.real_array("speed points", speed[0])
        vals = checks.real_array("speed values", speed[1])
        if pts.ndim != 1 or pts.shape != vals.shape or pts.size < 1:
            raise VehicleError(
                f"speed=(points {pts.shape}, speeds {vals.shape}): need two (K,) arrays, K >= 1"
            )
        if not (np.all(np.isfinite(pts)) and np.all(np.diff(pts) > 0)):
            raise VehicleError("speed points must be finite and strictly increasing")
        return lambda x: np.interp(x, pts, vals)
    try:
        value = checks.real("speed", speed)
    except VehicleError:
        raise VehicleError(
            f"speed={speed!r} must be a number (m/s), a callable or a (points, speeds) pair "
            f"(got {type(speed).__name__})"
        ) from None
    return lambda x: np.full(np.shape(x), value)


def schedule_grid(
    speed: SpeedSchedule,
    speed_of: str,
    start_m: float,
    end_m: float,
    h: float,
    max_speed: float,
    max_duration_s: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Front-axle (s, v) at t = k h from s = start_m until s reaches end_m (inclusive).

    Args:
        speed: see ``SpeedSchedule``; a callable/array is read as a function of time when
            ``speed_of="time"`` and of the front-axle position when ``speed_of="position"``.
        h: grid step, s. max_duration_s: give up (VehicleError) if the drive would be longer
            (default ``MAX_DRIVE_S``).
    Returns:
        s, v: arrays (N + 1,) with s[-1] >= end_m.
    """
    checks.choice("speed_of", speed_of, ("time", "position"))
    max_duration_s = MAX_DRIVE_S if max_duration_s is None else max_duration_s
    fun = _as_function(speed)
    if speed_of == "position":
        n_s = max(2, math.ceil((end_m - start_m) / 1e-3) + 1)
        checks.memory(
            BYTES_PER_POSITION * n_s,
            f"a speed schedule of position tabulated every mm from {start_m:.6g} m to "
            f"{end_m:.6g} m ({n_s} points)",
        )
        s_grid = np.linspace(start_m, end_m, n_s)
        v_grid = check_speed("speed", fun(s_grid), max_speed)
        t_of_s = cumulative_trapezoid(1.0 / v_grid, s_grid, initial=0.0)
        if t_of_s[-1] > max_duration_s:
            raise VehicleError(_too_long(t_of_s[-1], max_duration_s))
        n = math.ceil(t_of_s[-1] / h)
        checks.memory(checks.BYTES_PER_STEP * (n + 1), f"a drive of {n + 1} solver steps")
        t = h * np.arange(n + 1)
        s = np.interp(t, t_of_s, s_grid)
        return s, fun(s)
    if not (callable(speed) or isinstance(speed, tuple)):  # a constant: the length is known
        v0 = float(check_speed("speed", fun(0.0), max_speed))
        if (end_m - start_m) / v0 > max_duration_s:  # exact here, not up to a block beyond
            raise VehicleError(_too_long((end_m - start_m) / v0, max_duration_s))
        n_est = (end_m - start_m) / (v0 * h) + 1
        checks.memory(checks.BYTES_PER_STEP * n_est, f"a drive of {n_est:.4g} solver steps")
    s_parts, v_parts, s_now, k0 = [], [], start_m, 0
    block = 4096
    while True:
        checks.memory(checks.BYTES_PER_STEP * (k0 + block), f"a drive of over {k0} solver steps")
        t = h * np.arange(k0, k0 + block + 1)
        v = fun(t)
        s = s_now + cumulative_trapezoid(v, t, initial=0.0)
        done = np.nonzero(s >= end_m)[0]
        stop = int(done[0]) if done.size else block
        check_speed("speed", v[: stop + 1], max_speed)  # only the part actually driven
        s_parts.append(s[: stop + 1] if not s_parts else s[1 : stop + 1])
        v_parts.append(v[: stop + 1] if not v_parts else v[1 : stop + 1])
        if done.size:
            return np.concatenate(s_parts), np.concatenate(v_parts)
        s_now, k0 = float(s[-1]), k0 + block
        if k0 * h > max_duration_s:
            raise VehicleError(f"the drive takes more than {max_duration_s:g} s: allowed less")


def ramp_grid(
    s0: float, v0: float, v_set: float, max_accel: float, h: float, n_steps: int
) -> tuple[np.ndarray, np.ndarray]:
    """(s, v) at t = k h, k = 0..n_steps, for a speed ramping from v0 to v_set at <= max_accel."""
    t = h * np.arange(n_steps + 1)
    dv = v_set - v0
    t_ramp = abs(dv) / max_accel
    a = math.copysign(max_accel, dv) if dv else 0.0
    v = np.where(t < t_ramp, v0 + a * t, v_set)
    s_ramp = v0 * t + 0.5 * a * t * t
    s_after = v0 * t_ramp + 0.5 * a * t_ramp * t_ramp + v_set * (t - t_ramp)
    s = s0 + np.where(t < t_ramp, s_ramp, s_after)
    return s, v
