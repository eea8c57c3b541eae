"""Checks of raw sensor samples before the BCR uses them: what a healthy accelerometer never does.

A real accelerometer on a moving vehicle gives values that change from sample to sample, take
many distinct values and never sit at the ends of the sensor's range. Each check returns a reason
(a sentence for a person) or "" when the samples pass.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from control.errors import ControlError


@dataclass(frozen=True)
class SensorLimits:
    """Thresholds of the signal checks (per block of samples).

    Attributes:
        max_repeats: longest run of identical consecutive accelerations allowed (a stuck sensor
            repeats its last value).
        min_distinct: fewest distinct acceleration values allowed in a block (a coarsely
            quantised or clipped signal takes few).
        max_same: most samples allowed at both the block's minimum and its maximum (a clipped
            signal piles up at both ends of its range; a wheel in the air gives plateaus near
            -g, at one end only).
        range_mps2: the sensor's measurement range, m/s^2 (|a| at or beyond it is clipped);
            None: unknown.
        max_level_jump: largest ratio allowed between the variances of the samples before and
            after any split point in the middle half of the block (a gain that drops or jumps
            within the block; 22,000 clean Jackal blocks of 125 samples, with and without
            noise, stayed below 29, `docs/closed-loop.md`).
    """

    max_repeats: int = 8
    min_distinct: int = 24
    max_same: int = 4
    range_mps2: float | None = None
    max_level_jump: float = 40.0

    def __post_init__(self) -> None:
        for name in ("max_repeats", "min_distinct", "max_same"):
            value = getattr(self, name)
            if not (isinstance(value, int | np.integer) and value >= 1):
                raise ControlError(f"{name} must be an integer >= 1, got {value}")
        if not (np.isfinite(self.max_level_jump) and self.max_level_jump > 1):
            raise ControlError(f"max_level_jump must be finite and > 1, got {self.max_level_jump}")
        if self.range_mps2 is not None and not (
            np.isfinite(self.range_mps2) and self.range_mps2 > 0
        ):
            raise ControlError(f"range_mps2 must be None or finite and > 0, got {self.range_mps2}")


def longest_repeat(a: np.ndarray) -> int:
    """Length of the longest run of identical consecutive values of ``a``."""
    if a.size == 0:
        return 0
    change = np.flatnonzero(np.diff(a) != 0)
    edges = np.concatenate([[-1], change, [a.size - 1]])
    return int(np.max(np.diff(edges)))


def signal_fault(accel: np.ndarray, limits: SensorLimits) -> str:
    """Why a block of accelerations (finite values, m/s^2) cannot come from a healthy sensor,
    or "" (stuck, quantised, clipped, a level that jumps within the block)."""
    a = np.asarray(accel, dtype=float)
    if a.size < 2:
        return ""
    run = longest_repeat(a)
    if run > limits.max_repeats:
        return f"stuck sensor: {run} identical consecutive samples (allowed {limits.max_repeats})"
    distinct = np.unique(a).size
    need = min(limits.min_distinct, a.size // 2)
    if distinct < need:
        return f"quantised or clipped signal: {distinct} distinct values in {a.size} samples"
    if limits.range_mps2 is not None and np.any(np.abs(a) >= limits.range_mps2):
        return f"clipped signal: |a| reaches the sensor's range {limits.range_mps2:g} m/s^2"
    values, counts = _near_equal_groups(a)
    if counts[0] > limits.max_same and counts[-1] > limits.max_same:
        return (
            f"clipped signal: {counts[0]} samples at its minimum {values[0]:.4g} m/s^2 and "
            f"{counts[-1]} at its maximum {values[-1]:.4g} m/s^2 (allowed {limits.max_same})"
        )
    ratio, at = level_jump(a)
    if ratio > limits.max_level_jump:
        return (
            f"signal level jumps within the block: the variance changes by a factor "
            f"{ratio:.3g} at sample {at} (allowed {limits.max_level_jump:g})"
        )
    return ""


def _near_equal_groups(a: np.ndarray, rel: float = 1e-9) -> tuple[np.ndarray, np.ndarray]:
    """(a value, the count) of each group of values equal within rel * max|a| (free-fall
    samples read -g up to round-off)."""
    x = np.sort(a)
    tol = rel * (float(np.max(np.abs(x))) or 1.0)
    starts = np.concatenate([[0], np.flatnonzero(np.diff(x) > tol) + 1])
    return x[starts], np.diff(np.concatenate([starts, [x.size]]))


def level_jump(a: np.ndarray) -> tuple[float, int]:
    """(largest ratio of the variances before and after a split point, that point) over the
    split points in the middle half of ``a`` (about its mean); (1, 0) for fewer than 8 samples."""
    n = a.size
    if n < 8:
        return 1.0, 0
    sq = np.cumsum((a - a.mean()) ** 2)
    k = np.arange(n // 4, n - n // 4)
    before = sq[k - 1] / k
    after = (sq[-1] - sq[k - 1]) / (n - k)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.maximum(before / after, after / before)
    ratio = np.where(np.isnan(ratio), 1.0, ratio)
    i = int(np.argmax(ratio))
    return float(ratio[i]), int(k[i])


def stream_fault(
    t: np.ndarray, position: np.ndarray, accel: np.ndarray, speed: np.ndarray, t_prev: float,
    rate_hz: float,
) -> tuple[np.ndarray, np.ndarray, str]:  # fmt: skip
    """Samples that break the stream: (drop (n,), restart (n,), reason or "").

    ``drop`` marks samples to discard: a value that is not finite, or a time stamp that repeats
    or goes backwards (a step below half a period from the previous sample; ``t_prev``: the
    time of the sample before the first, NaN if none). ``restart`` marks samples after a gap (a
    step above 1.5 periods: dropped samples): they are kept but begin a new contiguous run.
    """
    bad_value = ~(np.isfinite(t) & np.isfinite(position) & np.isfinite(accel) & np.isfinite(speed))
    dt = 1.0 / rate_hz
    step = t - np.concatenate([[t_prev], t[:-1]])
    with np.errstate(invalid="ignore"):
        backwards = step < 0.5 * dt
        gap = step > 1.5 * dt
    what = []
    if bad_value.any():
        names = [
            name
            for name, a in (("t", t), ("position", position), ("accel", accel), ("speed", speed))
            if not np.all(np.isfinite(a))
        ]
        what.append(f"{int(bad_value.sum())} sample(s) with non-finite {'/'.join(names)}")
    if backwards.any():
        what.append(f"{int(backwards.sum())} repeated or backwards time stamp(s)")
    if gap.any():
        worst = float(np.max(step[gap]))
        what.append(f"a gap of {worst:.4g} s (about {round(worst / dt) - 1} dropped samples)")
    return bad_value | backwards, gap & ~bad_value, " and ".join(what)
