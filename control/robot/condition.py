"""From recorded messages to the BCR's sample stream: checks, resampling, odometry (numpy, scipy).

- `check_stream`: what is wrong with a topic's time stamps (repeated, backwards, gaps).
- `to_rate`: the IMU's accelerations at the emulator's rate. An IMU within ``tolerance`` of that
  rate is used as recorded, sample for sample (the BCR judges its stamps). A faster IMU is
  resampled: each contiguous run of samples is interpolated linearly onto a uniform grid at its
  own rate (this removes stamp jitter), then `scipy.signal.resample_poly` (a Kaiser-window FIR
  applied without delay, the filter of ``method``) takes it to the emulator's rate:

  - ``"sample"`` (default): band-limited interpolation, the filter's cut-off at 0.45 times the
    IMU's rate (just below its Nyquist frequency): the result is what a sensor sampling the
    IMU's signal at the emulator's rate would give. That is the simulator's sensor model, which
    the emulator was trained on: it samples the acceleration at 120 Hz with no anti-aliasing
    filter, so what lies above 60 Hz folds into the top band (in the Jackal simulation about a
    fifth of the 45-60 Hz band's power).
  - ``"lowpass"``: an anti-aliasing low-pass with its cut-off at the emulator's Nyquist frequency
    (resample_poly's default filter): removes what lies above 60 Hz (e.g. motor vibration the
    emulator never saw) but also the aliased power the emulator expects in its top band, which
    biases GD low (`docs/robot.md`).

  Repeated or backwards stamps and non-finite values are left out and end a run; a gap longer
  than 1.5 output periods ends a run. At each end of a run the samples the filter's start-up
  touches are cut, and where a run ended on a bad sample a marker is put in the stream (the
  last sample again, or a NaN), so the BCR reports the fault as it would at its own rate.
- `static_level_marks`: the static-level check (a scale fault) of the signal before a high-pass.
- `path_length`, `integrated_speed`, `odometry_at`: position along the path and speed at the
  IMU's sample times.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction

import numpy as np
from scipy.stats import median_abs_deviation

from control.errors import BagError, ControlError
from control.sensor_checks import SensorLimits, static_level, static_span_level
from control.validation import is_choice
from vehicle.models import GRAVITY

GAP_PERIODS = 1.5  # a step above this many periods is a gap (as control.sensor_checks)
METHODS = ("sample", "lowpass")
MAX_LOWPASS_TAPS = 200_001
"""Longest "lowpass" filter made (an input up to ~1 MHz at 120 Hz out); stamps far closer than
any IMU's would ask for millions of taps and gigabytes."""


@dataclass(frozen=True)
class StreamReport:
    """The time stamps of one topic as recorded.

    Attributes:
        topic: the topic.
        time_base: "header" (the messages' header stamps) or "log" (the receive times).
        messages: number of messages.
        rate_hz: nominal rate (1 / `nominal_period`: the median positive step, the mean
            step for heavy jitter), Hz; NaN for fewer than two distinct stamps (``null`` in
            ``replay.json``).
        repeated: stamps equal to the one before.
        backwards: stamps before an earlier one.
        gaps: steps between successive distinct stamps (in time order) longer than 1.5
            nominal periods (lost messages).
        largest_gap_s: the longest step, s (0 without gaps).
        non_finite: messages with a value that is not finite.
        note: anything else a reader should know ("" if nothing).
    """

    topic: str
    time_base: str
    messages: int
    rate_hz: float
    repeated: int
    backwards: int
    gaps: int
    largest_gap_s: float
    non_finite: int
    note: str = ""

    @property
    def clean(self) -> bool:
        """No repeated or backwards stamps, no gaps, no non-finite values."""
        return not (self.repeated or self.backwards or self.gaps or self.non_finite)

    def faults(self) -> str:
        """The stamp faults for a person ("no stamp faults" where none)."""
        faults = [
            f"{n} {what}"
            for n, what in (
                (self.repeated, "repeated stamp(s)"),
                (self.backwards, "backwards stamp(s)"),
                (self.gaps, f"gap(s) (longest {self.largest_gap_s:.3g} s)"),
                (self.non_finite, "non-finite value(s)"),
            )
            if n
        ]
        return ", ".join(faults) or "no stamp faults"

    def describe(self) -> str:
        """One line for a person."""
        rate = f"at {self.rate_hz:.4g} Hz" if np.isfinite(self.rate_hz) else "without a rate"
        text = f"{self.topic}: {self.messages} messages {rate} ({self.time_base} stamps); "
        text += self.faults()
        return text + (f"; {self.note}" if self.note else "")


@dataclass(frozen=True)
class Resampling:
    """How the IMU's samples were brought to the BCR's rate.

    Attributes:
        rate_in_hz: the IMU's nominal rate, Hz. rate_out_hz: the BCR's, Hz.
        resampled: False when the samples were used as recorded.
        method: "sample" or "lowpass" (see the module docstring); "" when not resampled.
        up, down: resample_poly's factors (1, 1 when not resampled).
        taps: length of the FIR filter (0 when not resampled).
        filter: what was done, for a person.
        runs: contiguous runs resampled one by one (0 when not resampled).
        dropped: samples left out before resampling (repeated or backwards stamps, non-finite).
        trimmed_per_edge: output samples cut at each end of each run.
    """

    rate_in_hz: float
    rate_out_hz: float
    resampled: bool
    method: str = ""
    up: int = 1
    down: int = 1
    taps: int = 0
    filter: str = ""
    runs: int = 0
    dropped: int = 0
    trimmed_per_edge: int = 0


HEAVY_JITTER_STEPS = 0.35
"""Robust sd (`robust_sd`) of the positive steps, in median steps, above which `nominal_period`
takes the stamps' mean step instead of the median: Gaussian stamp jitter of sd 0.24 period
(2 ms at 120 Hz) spreads the steps by about this much. Below it the median step lies within
0.3 % of the rate (0.1 % at the 1 ms a driver typically adds; the re-stamping's limit, 1/6
period, spreads them by 0.24); above it the median drifts (4 ms at 120 Hz: 124.6 Hz with the
stamps in order, 113 Hz without), while the mean step stays the clock's."""
SPLIT_STEPS = 16.0
"""Steps longer than this many median steps (pauses), or back by as much (clock steps), are left
out of the mean step of `nominal_period` (as `clock.RESTAMP_SPLIT_PERIODS`)."""


def robust_sd(x: np.ndarray) -> float:
    """The sd of ``x`` by its median absolute deviation about the median, scaled to a normal's
    (1.4826 MAD; `scipy.stats.median_abs_deviation`): jitter's spread, blind to a few outliers."""
    return float(median_abs_deviation(x, scale="normal"))


def nominal_period(t: np.ndarray) -> float:
    """Median of the positive steps of ``t`` (NaN with fewer than two distinct times); for
    stamps that jitter heavily (their steps' robust sd above HEAVY_JITTER_STEPS median steps)
    the mean of the non-zero steps within SPLIT_STEPS median steps (a run's span over its
    messages, left out: pauses, clock steps and repeated stamps), which jitter does not bias
    (the median of steps of stamps jittering by sd 4 ms at 120 Hz reads 124.6 Hz). A dropped
    message biases it, by the fraction dropped."""
    step = np.diff(np.asarray(t, dtype=float))
    step = step[np.isfinite(step)]
    pos = step[step > 0]
    if not pos.size:
        return np.nan
    period = float(np.median(pos))
    if robust_sd(pos) <= HEAVY_JITTER_STEPS * period:
        return period
    run = step[(step != 0) & (np.abs(step) <= SPLIT_STEPS * period)]
    mean = float(np.sum(run)) / run.size
    return mean if mean > 0 else period


def check_stream(
    topic: str, t: np.ndarray, finite: np.ndarray, time_base: str, note: str = ""
) -> StreamReport:
    """`StreamReport` of a topic with times ``t`` (s, in recorded order) and per-message
    ``finite`` flags (all values of the message finite)."""
    t = np.asarray(t, dtype=float)
    period = nominal_period(t)
    step = np.diff(t)
    before = np.maximum.accumulate(t)[:-1] if t.size else t
    backwards = int(np.count_nonzero(t[1:] < before))
    repeated = int(np.count_nonzero(step == 0))
    distinct = np.diff(np.unique(t[np.isfinite(t)]))  # a misordered message loses no slot
    gap = distinct > GAP_PERIODS * period if np.isfinite(period) else np.zeros(0, bool)
    return StreamReport(
        topic=topic,
        time_base=time_base,
        messages=int(t.size),
        rate_hz=1.0 / period if np.isfinite(period) else np.nan,
        repeated=repeated,
        backwards=backwards,
        gaps=int(np.count_nonzero(gap)),
        largest_gap_s=float(np.max(distinct[gap])) if gap.any() else 0.0,
        non_finite=int(np.count_nonzero(~np.asarray(finite, dtype=bool))),
        note=note,
    )


def increasing(t: np.ndarray) -> np.ndarray:
    """Mask of the samples whose time is later than every earlier sample's (finite times)."""
    t = np.asarray(t, dtype=float)
    keep = np.isfinite(t)
    if not t.size:
        return keep
    latest = np.maximum.accumulate(np.where(keep, t, -np.inf))
    keep[1:] &= t[1:] > latest[:-1]
    return keep


def _imu(topic: str | None) -> str:
    """The IMU's topic for a message ("the IMU topic '/imu/data'")."""
    return "the IMU topic" if topic is None else f"the IMU topic {topic!r}"


def _ratio(rate_in: float, rate_out: float) -> tuple[int, int]:
    """(up, down), up / down nearest rate_out / rate_in (< 1) with down at most 100, or at
    most the whole number above rate_in / rate_out where that is more (never up = 0)."""
    most = max(100, math.ceil(rate_in / rate_out))
    frac = Fraction(rate_out / rate_in).limit_denominator(most)
    return frac.numerator, frac.denominator


def resampling_filter(
    rate_in: float, rate_out: float, method: str, topic: str | None = None
) -> tuple[int, int, np.ndarray]:
    """(up, down, FIR coefficients at the upsampled rate) of `to_rate`'s ``method``:
    "sample": cut-off 0.45 rate_in, transition 0.1 rate_in wide, 60 dB (`scipy.signal.kaiserord`);
    "lowpass": resample_poly's own design (cut-off rate_out / 2, 20 max(up, down) + 1 taps,
    Kaiser beta 5). ``topic``: the IMU's topic, named in a `BagError`."""
    from scipy.signal import firwin, kaiserord  # here, not at import (tests/test_import_cost.py)

    if not is_choice(method, METHODS):
        raise ControlError(f"method must be one of {METHODS}, got {method!r}")
    up, down = _ratio(rate_in, rate_out)
    fs = rate_out * down  # = (rate_out * down / up) * up
    if method == "lowpass":
        half_len = 10 * max(up, down)
        if 2 * half_len + 1 > MAX_LOWPASS_TAPS:
            raise BagError(
                f"the stamps of {_imu(topic)} say {rate_in:.4g} Hz: resampling that to "
                f"{rate_out:g} Hz with 'lowpass' needs a filter of {2 * half_len + 1} taps, above "
                f"MAX_LOWPASS_TAPS = {MAX_LOWPASS_TAPS}; check the IMU's time stamps (or use "
                "resample 'sample')"
            )
        return up, down, firwin(2 * half_len + 1, 1.0 / max(up, down), window=("kaiser", 5.0))
    grid = fs / up
    taps, beta = kaiserord(60.0, 0.1 * grid / (fs / 2))
    return up, down, firwin(taps | 1, 0.45 * grid, window=("kaiser", beta), fs=fs)


def _rate_text(rate: float, other: float) -> str:
    """``rate`` (Hz) to 4 significant digits, or to as many more (up to 12) as tell it apart from
    ``other`` at the same precision (119.98 Hz is not "120 Hz", slower than 120 Hz)."""
    for digits in range(4, 13):
        if f"{rate:.{digits}g}" != f"{other:.{digits}g}":
            return f"{rate:.{digits}g}"
    return f"{rate:.12g}"


def to_rate(
    t: np.ndarray, a: np.ndarray, rate_hz: float, tolerance: float = 0.02,
    method: str = "sample", topic: str | None = None,
) -> tuple[np.ndarray, np.ndarray, Resampling]:  # fmt: skip
    """The samples (t s, a) at ``rate_hz`` (see the module docstring).

    Args:
        t: (n,) sample times, s, as recorded (may repeat, go backwards or jump).
        a: (n,) values (may be non-finite).
        rate_hz: the output rate, Hz (the emulator's).
        tolerance: relative difference of the nominal rate from ``rate_hz`` within which the
            samples are used as recorded.
        method: "sample" or "lowpass" (see the module docstring).
        topic: the IMU's topic, named in a `BagError`.

    Returns:
        (t, a, `Resampling`). Raises `BagError` for an input with fewer than two distinct
        stamps, slower than ``rate_hz`` or, for "lowpass", with stamps too close together.
    """
    from scipy import signal  # (as in `resampling_filter`)

    t, a = np.asarray(t, dtype=float), np.asarray(a, dtype=float)
    period = nominal_period(t)
    if not np.isfinite(period):
        raise BagError(f"{_imu(topic)} has fewer than two distinct time stamps")
    rate_in = 1.0 / period
    if abs(rate_in / rate_hz - 1.0) <= tolerance:
        text = f"none: the IMU's {rate_in:.4g} Hz is the emulator's {rate_hz:g} Hz"
        return t, a, Resampling(rate_in, rate_hz, False, filter=text)
    if rate_in < rate_hz:
        raise BagError(
            f"{_imu(topic)} runs at {_rate_text(rate_in, rate_hz)} Hz, slower than the "
            f"emulator's {rate_hz:g} Hz: its samples hold nothing above "
            f"{_rate_text(rate_in / 2, rate_hz / 2)} Hz, and the emulator's "
            f"feature needs up to {rate_hz / 2:g} Hz (record the IMU at >= {rate_hz:g} Hz)"
        )
    up, down, fir = resampling_filter(rate_in, rate_hz, method, topic)
    grid_rate = rate_hz * down / up
    trim = math.ceil((fir.size - 1) / 2 / down)
    finite = np.isfinite(a)
    keep = increasing(t) & finite
    # a run ends before a left-out sample and before a gap of more than 1.5 output periods
    kept = np.flatnonzero(keep)
    dropped_before = np.diff(np.concatenate([[-1], kept])) > 1
    bad_nan = np.zeros(kept.size, dtype=bool)
    for j in np.flatnonzero(dropped_before):
        lo = kept[j - 1] + 1 if j else 0
        bad_nan[j] = not finite[lo : kept[j]].all()
    step = np.diff(t[kept], prepend=-np.inf)
    start = dropped_before | (step > GAP_PERIODS / rate_hz)
    start[:1] = True  # (no sample kept: no run)
    bounds = np.concatenate([np.flatnonzero(start), [kept.size]])
    out_t, out_a, runs = [], [], 0
    for lo, hi in zip(bounds[:-1], bounds[1:], strict=True):
        tr, ar = t[kept[lo:hi]], a[kept[lo:hi]]
        if out_t and lo and dropped_before[lo]:  # a marker: the BCR reports the fault
            last_t, last_a = float(out_t[-1][-1]), float(out_a[-1][-1])
            if bad_nan[lo]:
                out_t.append(np.array([last_t + 1.0 / rate_hz]))
                out_a.append(np.array([np.nan]))
            else:
                out_t.append(np.array([last_t]))
                out_a.append(np.array([last_a]))
        m = int(np.floor((tr[-1] - tr[0]) * grid_rate + 1e-9)) + 1
        if m * up // down <= 2 * trim:
            continue  # too short to give a sample clear of the filter's start-up
        grid = tr[0] + np.arange(m) / grid_rate
        x = np.interp(grid, tr, ar)
        mean = float(np.mean(x))
        y = signal.resample_poly(x - mean, up, down, window=fir) + mean
        ty = tr[0] + np.arange(y.size) / rate_hz
        inside = ty <= tr[-1] + 1e-12
        cut = slice(trim, max(int(np.count_nonzero(inside)) - trim, trim))
        y, ty = y[inside][cut], ty[inside][cut]
        if y.size:
            out_t.append(ty)
            out_a.append(y)
            runs += 1
    what = (
        f"band-limited interpolation (cut-off {0.45 * grid_rate:.4g} Hz: samples at "
        f"{rate_hz:g} Hz of the IMU's signal, as the simulator's sensor takes them)"
        if method == "sample"
        else f"anti-aliasing low-pass (cut-off {rate_hz / 2:g} Hz)"
    )
    text = (
        f"the IMU's {rate_in:.4g} Hz to {rate_hz:g} Hz: linear interpolation onto a uniform "
        f"{grid_rate:.6g} Hz grid per contiguous run (removes stamp jitter), then "
        f"scipy.signal.resample_poly(up={up}, down={down}) with a {fir.size}-tap Kaiser-window "
        f"FIR, zero-phase: {what}; {trim} samples cut at each end of each run"
    )
    info = Resampling(
        rate_in, rate_hz, True, method, up, down, fir.size, text, runs,
        int(t.size - kept.size), trim,
    )  # fmt: skip
    if not out_t:
        return np.empty(0), np.empty(0), info
    return np.concatenate(out_t), np.concatenate(out_a), info


GRAVITY_BAND = (0.5, 1.5)
"""An IMU whose mean acceleration over the recording has a norm within these multiples of g
reads gravity (`gravity_direction`); below, gravity was removed and its direction is unknown."""
MAX_TILT_DEG = 10.0
"""Largest angle between the axis read as up and gravity's direction without a warning: the
vertical then reads scaled by cos(10 deg) = 0.985 at worst (docs/robot.md: keep the scale
within a few per cent)."""


def gravity_direction(
    accel: np.ndarray, axis: str, sign: float, topic: str, flight_mps2: float | None,
    gravity: str, static_mps2: float | None = None,
) -> str:  # fmt: skip
    """What the IMU's gravity says against the settings, for a warning ("" where nothing).

    ``accel``: (n, 3) accelerations as recorded, m/s^2; ``axis``, ``sign``: the axis read as
    up and its sign; ``flight_mps2``: the reading the BCR's sensor checks take for a wheel in
    the air (`control.sensor_checks.flight_reading`; None: no such exemption); ``gravity``:
    the replay's "keep" or "highpass". Where the mean acceleration's norm lies within
    `GRAVITY_BAND` g, it is gravity's reaction, pointing up: an axis pointing down, gravity
    along another axis, an axis more than `MAX_TILT_DEG` from it, or gravity kept where the
    sensor checks expect flights at -g, are named with their remedy; so is a ``static_mps2``
    (the static-level check's level) given for a recording whose IMU reads no gravity (every
    block would be a scale fault)."""
    rows = np.asarray(accel, dtype=float)
    rows = rows[np.all(np.isfinite(rows), axis=1)]
    if not rows.size:
        return ""
    mean = rows.mean(axis=0)
    norm = float(np.linalg.norm(mean))
    if not GRAVITY_BAND[0] * GRAVITY <= norm <= GRAVITY_BAND[1] * GRAVITY:
        if static_mps2 is None:
            return ""
        return (
            f"static_mps2 = {static_mps2:g} m/s^2, but the IMU topic {topic!r} reads no gravity "
            f"(its mean acceleration's norm is {norm:.3g} m/s^2 over the recording): every "
            "block will read as a scale fault (sensor_fault); the static-level check needs an "
            "IMU that reports gravity: drop static_mps2 (--static-mps2) for one that removes "
            "it, or for a recording simulated without it"
        )
    i = "xyz".index(axis)
    up = sign * float(mean[i])
    angle = float(np.degrees(np.arccos(np.clip(up / norm, -1.0, 1.0))))
    seen = (
        f"the IMU topic {topic!r} reads gravity (its mean acceleration ("
        + ", ".join(f"{v:.2f}" for v in mean)
        + ") m/s^2 over the recording); "
    )
    if angle <= MAX_TILT_DEG:
        if gravity == "keep" and flight_mps2 is not None:
            return seen + (
                f"it is kept in the {axis} axis (+{up:.2f} m/s^2), but the emulator records no "
                f"noise sd, and the BCR's sensor checks expect a wheel in the air at "
                f"{flight_mps2:.2f} m/s^2, as gravity removed puts it: with gravity in, a quiet "
                "sensor's flights read as a dead or quantised sensor (sensor_fault); replay "
                "with gravity='highpass' (--gravity highpass)"
            )
        return ""
    j = int(np.argmax(np.abs(mean)))
    sj = 1 if mean[j] > 0 else -1
    if j == i and sj != sign:
        return seen + (
            f"the {axis} axis times imu_sign {sign:+g} points down, not up ({up:.2f} m/s^2 "
            f"along it): a flipped axis reads the landings' peaks as flights (rougher ground, "
            f"implausible blocks, sensor faults); replay with imu_sign={-sign:+g} "
            f"(--sign {-sign:g})"
        )
    if j != i:
        return seen + (
            f"gravity lies along its {'xyz'[j]} axis, {angle:.0f} degrees from the {axis} axis "
            f"read as up: replay with imu_axis={'xyz'[j]!r}, imu_sign={sj:+d} (--axis "
            f"{'xyz'[j]} --sign {sj})"
        )
    return seen + (
        f"the {axis} axis read as up lies {angle:.0f} degrees from it (a tilted mount, or a "
        f"drive up a slope): it reads the vertical acceleration scaled by about "
        f"{np.cos(np.radians(angle)):.2f}, as ground smoother than it is; mount the IMU with "
        "an axis vertical, or rotate its accelerations into the robot's frame before the replay"
    )


def highpass(t: np.ndarray, a: np.ndarray, rate_hz: float, cutoff_hz: float) -> np.ndarray:
    """``a`` through a zero-phase 2nd-order Butterworth high-pass (`scipy.signal.sosfiltfilt`),
    run by run (a run ends at a non-finite value or a step outside [0.5, 1.5] periods; a run
    too short for the filter has its mean removed instead)."""
    t, a = np.asarray(t, dtype=float), np.asarray(a, dtype=float)
    out = a.copy()
    if a.size == 0:
        return out
    from scipy.signal import butter, sosfiltfilt  # (as in `resampling_filter`)

    sos = butter(2, cutoff_hz, btype="highpass", fs=rate_hz, output="sos")
    pad = 3 * (2 * len(sos) + 1)
    good = np.isfinite(a) & np.isfinite(t)
    step = np.diff(t, prepend=np.nan) * rate_hz
    start = ~good | ~((step >= 0.5) & (step <= GAP_PERIODS))
    start[0] = True
    bounds = np.concatenate([np.flatnonzero(start), [a.size]])
    for lo, hi in zip(bounds[:-1], bounds[1:], strict=True):
        lo += 0 if good[lo] else 1
        if hi - lo <= 0:
            continue
        seg = a[lo:hi]
        out[lo:hi] = sosfiltfilt(sos, seg) if hi - lo > pad else seg - seg.mean()
    return out


def static_level_marks(
    a: np.ndarray, limits: SensorLimits, every: int, block: int, t: np.ndarray, rate_hz: float,
    kept: np.ndarray | None = None,
) -> dict[int, str]:  # fmt: skip
    """The static-level check (`control.sensor_checks.static_level`) of the raw samples ``a``
    (m/s^2, before a high-pass removes their static level; times ``t``, s, at ``rate_hz``) at
    each update of a BCR fed them ``every`` samples at a time from the first: {the update's
    newest sample: the reason} for each update whose block (its newest ``block`` samples, all
    finite: a non-finite one is a fault the BCR reports itself) has a mean off
    ``limits.static_mps2``, or, with ``limits.static_span``, whose newest ``static_span``
    samples, finite and contiguous (steps within [0.5, ``GAP_PERIODS``] periods; one stamped
    backwards is left out, as the BCR's long span leaves it: `static_span_level`), have one
    off it by more than ``static_span_tolerance``. ``kept``: (n,) bool, False for a sample the
    BCR drops for its other values (no position or speed: an odometry gap; a speed beyond
    ``MAX_SPEED_MPS``), which breaks the block and the span as a non-finite ``a`` does (None:
    every sample has them)."""
    a = np.asarray(a, dtype=float)
    finite = np.isfinite(a) if kept is None else np.isfinite(a) & kept
    count = np.concatenate([[0], np.cumsum(finite)])
    updates = np.arange(every, a.size + 1, every)  # each update's end (exclusive)
    ends = updates[updates >= block]
    full = count[ends] - count[ends - block] == block
    marks = {}
    blocks = np.lib.stride_tricks.sliding_window_view(a, min(block, a.size))
    with np.errstate(over="ignore", invalid="ignore"):  # (a wild value's sum: a fault anyway)
        for end in ends[full]:
            # each block summed on its own, as the BCR sums it (a running sum over the recording
            # would carry one wild value's rounding into every later block)
            why = static_level(float(blocks[end - block].sum() / block), block, limits)
            if why:
                marks[int(end - 1)] = why + " (the signal before the high-pass)"
    span = limits.static_span
    if span and a.size >= span:
        step = np.diff(t, prepend=np.nan) * rate_hz
        dropped = ~finite | ~np.isfinite(t) | (step < 0.5)  # (stamped backwards: the BCR drops it)
        start = dropped | ~(step <= GAP_PERIODS)
        run = np.cumsum(start)  # (a run's first sample may be its start: kept, after a gap)
        ends = updates[updates >= span]
        whole = (run[ends - 1] == run[ends - span]) & ~dropped[ends - span]
        windows = np.lib.stride_tricks.sliding_window_view(a, span)
        with np.errstate(over="ignore", invalid="ignore"):
            for end in ends[whole]:
                # each span summed on its own (a running sum would carry a wild value's rounding)
                why = static_span_level(float(windows[end - span].sum() / span), limits)
                if why and int(end - 1) not in marks:
                    marks[int(end - 1)] = why + " (the signal before the high-pass)"
    return marks


def _norm(d: np.ndarray) -> np.ndarray:
    """Row lengths of (n, 3) ``d`` (hypot: exact for a vector along one axis)."""
    return np.hypot(np.hypot(d[:, 0], d[:, 1]), d[:, 2])


def path_length(position: np.ndarray, turn_tol: float = 1e-12) -> np.ndarray:
    """Distance travelled along the path from the odometry frame's origin through ``position``
    ((n, 3) m), m.

    The path is measured in straight pieces: while the robot moves in one direction (successive
    steps within an angle whose 1 - cos is ``turn_tol``) the distance is that from the piece's
    start, so a straight drive gives its exact distance (no sum of n rounded steps); each turn
    starts a new piece. A curved path is the sum of its steps.
    """
    p = np.asarray(position, dtype=float).reshape(-1, 3)
    q = np.vstack([np.zeros(3), p])
    d = np.diff(q, axis=0)
    step = _norm(d)
    moving = np.flatnonzero(step > 0)
    if moving.size == 0:
        return np.zeros(p.shape[0])
    u = d[moving] / step[moving, None]
    cos = np.einsum("ij,ij->i", u[1:], u[:-1])
    turns = moving[np.concatenate([[True], 1.0 - cos > turn_tol])]
    anchors = q[turns]  # the piece's start point (q[k] begins step k)
    start_s = np.concatenate([[0.0], np.cumsum(_norm(np.diff(anchors, axis=0)))])
    piece = np.searchsorted(turns, np.arange(p.shape[0]), side="right") - 1
    s = np.zeros(p.shape[0])
    on = piece >= 0
    s[on] = start_s[piece[on]] + _norm(p[on] - anchors[piece[on]])
    return s


def integrated_speed(t: np.ndarray, speed: np.ndarray) -> np.ndarray:
    """Distance from the first sample by the trapezoid rule over (t s, speed m/s), m."""
    t, v = np.asarray(t, dtype=float), np.asarray(speed, dtype=float)
    if t.size == 0:
        return t.copy()
    return np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(t))])


def odometry_at(
    t: np.ndarray, t_odom: np.ndarray, position: np.ndarray, speed: np.ndarray,
    max_gap_s: float,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """(position, speed) at times ``t`` by linear interpolation of the odometry (increasing
    ``t_odom``); NaN where ``t`` falls in an odometry gap longer than ``max_gap_s`` or outside
    the odometry's span."""
    t = np.asarray(t, dtype=float)
    pos = np.interp(t, t_odom, position)
    spd = np.interp(t, t_odom, speed)
    j = np.clip(np.searchsorted(t_odom, t, side="right") - 1, 0, max(t_odom.size - 2, 0))
    span = np.diff(t_odom)[j] if t_odom.size > 1 else np.zeros(t.size)
    bad = (span > max_gap_s) | (t < t_odom[0]) | (t > t_odom[-1])
    pos[bad] = np.nan
    spd[bad] = np.nan
    return pos, spd
