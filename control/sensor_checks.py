"""Checks of raw sensor samples before the BCR uses them: what a healthy accelerometer never does.

A real accelerometer on a moving vehicle gives values that change from sample to sample, take
many distinct values, never line up on a lattice coarser than its resolution, never sit at the
ends of the sensor's range and never read quieter than its own noise. Each check returns a
reason (a sentence for a person) or "" when the samples pass.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from scipy.special import bdtrc
from scipy.stats import chi2

from control.errors import ControlError
from control.validation import is_integer, require_integers, require_reals
from gpmsa.errors import numbers_text
from vehicle.models import GRAVITY

MIN_SEGMENT = 32
"""Shortest stretch (samples, 0.27 s at 120 Hz) whose variance the level check compares with the
rest of the block: shorter stretches of a healthy signal scatter too much (free flight)."""
SHORT_LEVEL_STRETCHES = ((8, 20_000.0), (16, 2_000.0), (24, 400.0))
"""(stretch in samples, largest ratio allowed) of the short level check (`short_level_drop`):
the variance of a stretch shorter than ``MIN_SEGMENT`` (0.07, 0.13, 0.2 s at 120 Hz) against
that of the rest of the block and of each half of the samples before it, where the level
drops (a gain that drops for 8-31 samples), with or without a known noise sd. Each limit is
4.2-6.1x the largest ratio of clean campaign blocks (`benchmarks/sensor_checks.py`; 3,282, 471
and 83 over 302,580 blocks of 318 drives, GD 200-600, 0.5-2 m/s, with and without noise): a
healthy signal holds short quiet stretches (a wheel resting on a smooth bit at low speed, a
front wheel in the air while the rear one rolls), so the shorter the stretch, the higher the
limit."""
SHORT_LEVEL_BEFORE = 8
"""Fewest samples before a stretch that the short level check holds it to (4 in each half): a
stretch with fewer before it scores 1 (a quiet start, then louder, reads as a level that rises:
`level_jump`)."""
NEAR_FLIGHT = 0.25
"""Fraction of |``SensorLimits.free_fall_mps2``| within which the short level check takes a
stretch's mean as a wheel in the air: a flight (-g) and a front wheel off the ground while the
rear one rolls (the vehicle pitching about it reads a smooth -0.84 to -0.95 g in the
simulator). A gain below 0.75 moves a reading (at least -g; 0.65 for a mean of 8 samples with
N(0, 1) noise) out of that band, so the exemption hides only drops of less than 2.4x in
variance, far below every limit. Where the noise sd is known the band lies |-g| above or below
the mean of the rest of the block instead (the other checks read no absolute level there: a
flight reads about 0 with gravity kept, +g with the axis' sign flipped, docs/robot.md)."""
DEAD_STRETCH = 6
"""Shortest stretch (samples, 0.05 s at 120 Hz) that the dead-sensor check looks at."""
NOISE_STRETCH = 32
"""Stretch (samples, 0.27 s at 120 Hz) whose variance the noise-floor check compares with
``SensorLimits.noise_floor`` times the sensor's noise variance."""
SHORT_NOISE_STRETCHES = (8, 16)
"""Shorter stretches the noise-floor check also looks at, each against the fraction of the noise
variance that pure noise reads as rarely as ``NOISE_STRETCH`` samples read ``noise_floor``
(`noise_floors`): a gain that drops for 8-31 samples (0.07-0.26 s)."""
LATTICE_STRETCHES = (6, 8)
"""Stretches (samples, 0.05 and 0.07 s at 120 Hz) the lattice check looks at: a coarse
quantisation as short as 6 samples (`lattice_stretch`)."""
MAX_ACCEL_MPS2 = 1e5
"""Largest |acceleration| the signal checks take as a reading, m/s^2 (about 10,000 g: beyond any
accelerometer's range; larger values are a fault, and their squares could overflow)."""
MAX_SPEED_MPS = 50.0
"""Largest |speed| the stream checks take as a reading, m/s (180 km/h: 25 times a Jackal-class
ground robot's 2 m/s top speed, beyond any vehicle this BCR serves; a larger value is a broken
sample, dropped like a non-finite one, before a mean or the odometry check overflows on it)."""
MAX_NOISE_SD_MPS2 = 1e4
"""Largest sensor noise sd the checks take, m/s^2 (about 1,000 g: beyond any accelerometer;
its square must stay finite)."""
FREE_FALL_MPS2 = -GRAVITY
"""What the vertical acceleration reads while a wheel is in the air (the simulator's -g), m/s^2."""
NEAR_EQUAL = 1e-6
"""Fraction of a block's largest |acceleration| within which the clip check takes samples as
one value (free-fall samples read -g up to the solver's residual: two flights of one block
can differ by ~1e-8)."""
EPS = float(np.finfo(float).eps)
"""Machine epsilon of float64 (the rounding bounds of the level checks' shortcuts)."""
STATIC_BLOCK = 125
"""Samples (1.04 s at 120 Hz, the shipped emulators' block) for which
``SensorLimits.static_tolerance`` holds; a shorter block's mean is held to that tolerance times
``STATIC_BLOCK / n`` (its mean is the change of vertical velocity over a shorter time: the
window methods' chunks of ``update_every`` samples)."""
MAX_STATIC_SPAN = 1 << 20
"""Longest ``SensorLimits.static_span``, samples (2.4 h at 120 Hz; its ring holds 16 MiB)."""


@dataclass(frozen=True)
class SensorLimits:
    """Thresholds of the signal checks (per block of samples).

    Attributes:
        max_repeats: longest run of identical consecutive accelerations allowed (a stuck sensor
            repeats its last value).
        min_distinct: fewest distinct acceleration values allowed in a block (a coarsely
            quantised or clipped signal takes few); at most half the block's samples are
            asked for (62 of a 125-sample block).
        max_same: most samples allowed at each of two values (a clipped signal piles up at both
            ends of its range, also when the clipped stretch is only part of the block; a wheel
            in the air piles up at one value, -g; of 22,770 clean campaign blocks none had a
            second value repeated at all).
        range_mps2: the sensor's measurement range, m/s^2 (|a| at or beyond it is clipped);
            None: unknown.
        max_level_jump: largest ratio allowed between the variance of any segment of at least
            ``MIN_SEGMENT`` samples of a block and that of the rest of the block, each about its
            own mean, where the level drops (`level_jump`: a gain that drops within the block,
            or jumps and comes back; a level that only rises reads rougher and is not counted;
            of the 22,770 clean blocks of 125 samples of the shipped emulators' campaign none
            exceeded 323 without noise, 255 with it, counting rises too: lift-off gives
            near-constant free-flight stretches, so the limit is high, and catches gains below
            ~0.05). Stretches of 8-31 samples: the short level check (`SHORT_LEVEL_STRETCHES`).
        dead_fraction: a stretch of ``DEAD_STRETCH`` consecutive samples whose range is below
            this fraction of the block's standard deviation, away from ``free_fall_mps2``, is a
            dead sensor (a gain near zero, a clip or quantisation near zero, a short stuck
            stretch), however short the fault (from 6 samples). Of 41,904 clean blocks of
            125 samples (GD 200-600, 0.5-2 m/s, with and without noise) the smallest such range
            was 0.0077 of the block's sd.
        free_fall_mps2: the reading of a wheel in the air, m/s^2: without sensor noise a
            flight holds this one value, so it is exempt from the dead-sensor and lattice
            checks; None: no exemption. Where ``noise_sd_mps2`` is set every reading carries
            noise, flights too, and the exemption is dropped: it would hide a quantisation or a
            dead stretch that falls in a flight (`flight_reading`). The short level check
            exempts stretches whose mean lies within 25% of it, noise or not (`NEAR_FLIGHT`: a
            gain that drops moves the mean out of that band; with the noise sd, |it| above or
            below the rest's mean: blind to an offset and to the sign).
        noise_sd_mps2: the sensor's own white-noise standard deviation, m/s^2 (every reading
            carries it, in flight and at rest too); None: unknown, no noise-floor check.
            `control.bcr_settings_for` takes it from the emulator's training noise.
        noise_floor: a stretch of ``NOISE_STRETCH`` samples whose variance about its mean is
            below this fraction of ``noise_sd_mps2`` squared reads quieter than the sensor's
            own noise: an attenuated signal (a gain that dropped). For 32 samples of pure
            Gaussian noise that happens with probability 4e-11 (chi-square, 31 dof); of the
            2.8 million 32-sample stretches of the shipped emulator B's training campaign
            (N(0, 1) noise) the quietest had variance 1.16. Stretches of 16 and 8 samples are
            held to the floors pure noise falls below as rarely (0.020 and 6.2e-4 at the
            default; `noise_floors`); in a campaign of 198 clean noisy drives (2.9 million
            stretches, seed 7) the quietest read 0.345 and 0.018.
        lattice_p: a stretch of 6 or 8 samples whose values sit on a lattice (an offset plus
            multiples of a step far above the block's resolution) as often as a healthy sensor
            does with a probability below this (`lattice_stretch`, Bonferroni over the steps
            tried and the two stretch lengths) is a quantised signal: the short quantisations
            that ``min_distinct`` cannot see. Of 45,540 clean blocks of 125 samples (198 drives
            of 120 s, seed 7, with and without noise, also rounded to ADC resolutions of
            0.001-0.1 m/s^2) the most lattice-like scored 1.3e-6 (`benchmarks/sensor_checks.py`).
            0 switches the check off.
        rate_tolerance: a block whose time stamps span more or less than its samples at the
            BCR's rate, by more than this fraction, comes at another rate (a 150 Hz stream fed
            as 120 Hz: its band powers would be read at the wrong frequencies). Single steps
            within half a period either way are jitter, not a fault (`stream_breaks`). Above
            `control.ReplaySettings.rate_tolerance` (0.02), beyond which a recording is
            resampled: one kept as recorded is not refused for its rate and its jitter.
        odometry_tolerance, odometry_slack_m: a block the BCR would use, whose position advances
            by more than ``odometry_tolerance`` times the distance its speeds give (the
            trapezoid rule over its time stamps) plus ``odometry_slack_m`` away from it, has
            broken odometry (a frozen or backwards position, a jump): the change-point filter
            counts distance with the positions and would stop forgetting.
        static_mps2: the mean a healthy axis reads, m/s^2: +9.80665 (standard gravity) for an up
            axis that reports gravity (a real IMU's specific force, ROS REP-145), -9.80665 for
            one that points down; None (default): unknown (the simulator's signal is
            gravity-free, an IMU may remove gravity), no static-level check. With it, a block
            whose mean lies outside ``static_mps2 * (1 +- static_tolerance)`` is a scale (or
            tilt) fault (`static_level`): a gain error scales gravity's reading too. It needs
            gravity kept in the signal: not high-passed (the replay checks the raw signal
            itself there, `control.ReplaySettings.static_mps2`).
        static_tolerance: the static-level check's tolerance, a fraction of ``static_mps2`` for a
            block of ``STATIC_BLOCK`` samples (times ``STATIC_BLOCK / n`` for a shorter one). A
            block's mean of the vertical acceleration is its change of vertical velocity over the
            block's time: over 175,440 clean blocks of 125 samples, one every 42 (GD 200-600, 0.5-2
            m/s, with and without N(0, 1) noise; campaign seeds 7 and 11, ``lhs_design`` of 198 and
            60 drives of 120 s) it lay within 0.157 g of 0 (p99.99 0.13 g, worst at 1.7-1.9 m/s over
            GD 550-600). 0.2 leaves 1.27x that on level ground, and allows a slope of 10 degrees
            (the level reads g cos 10 = 0.985 g: 1.18x margin); a gain of 0.7 or below is flagged in
            its first block, 0.8 in about every other block, 0.9 only in blocks that read 11% of g
            low (fast, rough ground): the long span below catches it.
        static_span: the static-level check's long span, samples (1,000: 8.3 s at 120 Hz; 0
            switches it off): with ``static_mps2``, the mean of the newest ``static_span``
            contiguous samples outside ``static_mps2 * (1 +- static_span_tolerance)`` is a scale
            (or tilt) fault too (`static_span_level`), checked at every update once the span is
            full. The BCR keeps it (`StaticSpan`, a ring summed at each check) across its
            blocks, phases and window restarts; a break in the stream (a dropped, repeated or
            backwards sample, a gap), ``reset`` and ``resume`` start it again (it then checks
            nothing for ``static_span`` samples); a fault of the checks does not (a persistent
            scale fault is a fault at every update, until the span reads healthy again); a
            standstill fills it too (a healthy axis at rest reads the level itself). The mean of
            the vertical acceleration over a span is its change of vertical velocity over the
            span's time, which shrinks as 1 / span: over clean drives (GD 200-600, 0.5-2 m/s,
            with and without N(0, 1) noise; campaign seeds 7 and 11, 258 drives of 120 s, a
            span every 42 samples) it reached 0.157 g over 125 samples, 0.078 g over 250, 0.046
            g over 500 and 0.021 g over 1,000 (0.011 g over 2,000).
        static_span_tolerance: the long span's tolerance, a fraction of ``static_mps2`` (0.07):
            the dynamics' 0.021 g over 1,000 samples plus a slope of 15 degrees held for the
            whole span (g cos 15 = 0.966 g: 0.055 g off in all, 1.27x margin; up to 18 degrees
            on smooth ground). A gain of 0.9 reads at most 0.92 of the level over a full span and
            is flagged once most of the span reads it (5-8 s after it begins); 0.95 lies within
            the tolerance (an 18-degree slope reads as much), and so does a gain of up to 1.07
            (less on a slope: 1.1 cos 15 = 1.06).
    """

    max_repeats: int = 8
    min_distinct: int = 24
    max_same: int = 4
    range_mps2: float | None = None
    max_level_jump: float = 400.0
    dead_fraction: float = 1e-3
    free_fall_mps2: float | None = FREE_FALL_MPS2
    noise_sd_mps2: float | None = None
    noise_floor: float = 0.1
    lattice_p: float = 1e-10
    rate_tolerance: float = 0.03
    odometry_tolerance: float = 0.25
    odometry_slack_m: float = 0.1
    static_mps2: float | None = None
    static_tolerance: float = 0.2
    static_span: int = 1000
    static_span_tolerance: float = 0.07

    def __post_init__(self) -> None:
        require_reals(
            self,
            ("range_mps2", "max_level_jump", "dead_fraction", "free_fall_mps2", "noise_sd_mps2",
             "noise_floor", "lattice_p", "rate_tolerance", "odometry_tolerance",
             "odometry_slack_m", "static_mps2", "static_tolerance", "static_span_tolerance"),
            optional=("range_mps2", "free_fall_mps2", "noise_sd_mps2", "static_mps2"),
        )  # fmt: skip
        counts = ("max_repeats", "min_distinct", "max_same")
        require_integers(self, (*counts, "static_span"))
        for name in counts:
            value = getattr(self, name)
            if value < 1:
                raise ControlError(f"{name} must be an integer >= 1, got {value}")
        if not (np.isfinite(self.max_level_jump) and self.max_level_jump > 1):
            raise ControlError(f"max_level_jump must be finite and > 1, got {self.max_level_jump}")
        if not (np.isfinite(self.dead_fraction) and 0 <= self.dead_fraction < 1):
            raise ControlError(f"dead_fraction must lie in [0, 1), got {self.dead_fraction}")
        if self.free_fall_mps2 is not None and not np.isfinite(self.free_fall_mps2):
            raise ControlError(f"free_fall_mps2 must be None or finite, got {self.free_fall_mps2}")
        if self.range_mps2 is not None and not (
            np.isfinite(self.range_mps2) and self.range_mps2 > 0
        ):
            raise ControlError(f"range_mps2 must be None or finite and > 0, got {self.range_mps2}")
        if self.noise_sd_mps2 is not None and not 0 < self.noise_sd_mps2 <= MAX_NOISE_SD_MPS2:
            raise ControlError(
                f"noise_sd_mps2 must be None or lie in (0, {MAX_NOISE_SD_MPS2:g}] m/s^2, got "
                f"{self.noise_sd_mps2}"
            )
        if not (np.isfinite(self.noise_floor) and 0 < self.noise_floor < 1):
            raise ControlError(f"noise_floor must lie in (0, 1), got {self.noise_floor}")
        if not (np.isfinite(self.lattice_p) and 0 <= self.lattice_p < 1):
            raise ControlError(f"lattice_p must lie in [0, 1), got {self.lattice_p}")
        if not 0 < self.rate_tolerance < 0.5:
            raise ControlError(f"rate_tolerance must lie in (0, 0.5), got {self.rate_tolerance}")
        if not 0 < self.odometry_tolerance < 1:
            raise ControlError(
                f"odometry_tolerance must lie in (0, 1), got {self.odometry_tolerance}"
            )
        if not (np.isfinite(self.odometry_slack_m) and self.odometry_slack_m >= 0):
            raise ControlError(
                f"odometry_slack_m must be finite and >= 0, got {self.odometry_slack_m}"
            )
        if self.static_mps2 is not None and not 0 < abs(self.static_mps2) <= MAX_ACCEL_MPS2:
            raise ControlError(
                f"static_mps2 must be None or a level of 0 < |level| <= {MAX_ACCEL_MPS2:g} m/s^2 "
                f"(+9.80665 for an up axis that reports gravity), got {self.static_mps2}"
            )
        if not 0 < self.static_tolerance < 1:
            raise ControlError(
                f"static_tolerance must lie in (0, 1) (a fraction of static_mps2), got "
                f"{self.static_tolerance}"
            )
        if not (self.static_span == 0 or 2 <= self.static_span <= MAX_STATIC_SPAN):
            raise ControlError(
                f"static_span must be 0 (off) or an integer in [2, {MAX_STATIC_SPAN}] (samples), "
                f"got {self.static_span}"
            )
        if not 0 < self.static_span_tolerance < 1:
            raise ControlError(
                f"static_span_tolerance must lie in (0, 1) (a fraction of static_mps2), got "
                f"{self.static_span_tolerance}"
            )


def longest_repeat(a: np.ndarray) -> int:
    """Length of the longest run of identical consecutive values of ``a``."""
    if a.size == 0:
        return 0
    change = np.flatnonzero((a[1:] - a[:-1]) != 0)  # np.diff(a) != 0, without its wrapper
    if change.size == a.size - 1:  # (the usual case: every sample differs from the one before)
        return 1
    edges = np.concatenate([[-1], change, [a.size - 1]])
    return int((edges[1:] - edges[:-1]).max())


def signal_fault(
    accel: np.ndarray, limits: SensorLimits, *, steady: bool = True,
    slow: np.ndarray | None = None,
) -> str:  # fmt: skip
    """Why a block of accelerations (finite values, m/s^2) cannot come from a healthy sensor,
    or "" (stuck, quantised, clipped, a dead stretch, quieter than the sensor's noise, a level
    that drops within the block; with ``limits.static_mps2``, a mean off the static level:
    `static_level`). ``steady=False``: the vehicle started or stopped within the block, whose
    level then changes with the speed: no level-jump check. ``slow`` (bool, one per sample;
    None: none): the samples at which the vehicle was slow (below half the block's top speed):
    a dead stretch that takes one in is no fault (a robot getting under way on flat ground, or
    coming to rest, reads an all but constant acceleration), one at speed still is."""
    a = np.asarray(accel, dtype=float)
    if a.ndim != 1:
        raise ControlError(f"accel must be a 1-D block of accelerations, got shape {a.shape}")
    if a.size < 2:
        return ""
    peak = float(np.abs(a).max())
    if not peak <= MAX_ACCEL_MPS2:  # before any check squares them (and overflows); NaN too
        if np.isnan(peak):
            return f"{int(np.isnan(a).sum())} sample(s) with non-finite accel"
        return f"out of range: |a| reaches {peak:.3g} m/s^2, beyond any accelerometer's range"
    run = longest_repeat(a)
    if run > limits.max_repeats:
        return f"stuck sensor: {run} identical consecutive samples (allowed {limits.max_repeats})"
    ordered = np.sort(a)  # one sort for the distinct values, the near-equal groups, the lattice
    gaps = ordered[1:] - ordered[:-1]
    positive = gaps[gaps > 0]
    distinct = _distinct_count(ordered, positive)
    need = min(limits.min_distinct, a.size // 2)
    if distinct < need:
        return f"quantised or clipped signal: {distinct} distinct values in {a.size} samples"
    if limits.range_mps2 is not None and np.any(np.abs(a) >= limits.range_mps2):
        return f"clipped signal: |a| reaches the sensor's range {limits.range_mps2:g} m/s^2"
    tol = NEAR_EQUAL * (peak or 1.0)
    # two piles of more than max_same samples each hold max_same gaps within tol between their
    # sorted samples (the usual case: fewer such gaps, no groups to form)
    if np.count_nonzero(gaps <= tol) >= 2 * limits.max_same:
        values, counts = _near_equal_groups(ordered, gaps, tol)
        if np.count_nonzero(counts > limits.max_same) >= 2:  # free flight piles up at one value
            top = np.argsort(counts, kind="stable")[::-1][:2]
            lo, hi = sorted(top, key=lambda i: values[i])
            return (
                f"clipped signal: {counts[lo]} samples at {values[lo]:.4g} m/s^2 and "
                f"{counts[hi]} at {values[hi]:.4g} m/s^2 (allowed {limits.max_same} at two "
                f"values)"
            )
    flight = flight_reading(limits)
    s1, s2, sd = _centred_sums(a)  # shared by the dead, noise-floor and level checks
    # every DEAD_STRETCH consecutive samples in order: their ranges (the dead check) and the
    # lattice check's shortest stretches
    sorted_runs = _sorted_runs(a, DEAD_STRETCH)
    spread = None if sorted_runs is None else sorted_runs[-1] - sorted_runs[0]
    start = _dead_stretch(a, limits.dead_fraction, flight, sd, spread, slow)
    if start >= 0:
        return (
            f"dead sensor: samples {start}-{start + DEAD_STRETCH - 1} span less than "
            f"{limits.dead_fraction:g} of the block's standard deviation"
        )
    if limits.lattice_p > 0:
        resolution = float(positive.min()) if positive.size else None  # (`_resolution`)
        p, start, stretch, step = _most_lattice_like(a, flight, resolution, sorted_runs)
        if p < limits.lattice_p:
            return (
                f"quantised signal: samples {start}-{start + stretch - 1} sit on a lattice of "
                f"step {step:.4g} m/s^2 (probability "
                f"{numbers_text(p, limits.lattice_p, digits=2)[0]} for a healthy sensor, "
                f"allowed {limits.lattice_p:g})"
            )
    if limits.noise_sd_mps2 is not None:
        noise_var = limits.noise_sd_mps2**2
        for stretch, fraction in noise_floors(limits.noise_floor):
            variance, start = _quietest_stretch(s1, s2, stretch)
            if variance < fraction * noise_var:
                return (
                    f"attenuated signal: samples {start}-{start + stretch - 1} vary less than "
                    f"the sensor's own noise (variance {variance:.3g} (m/s^2)^2, below "
                    f"{fraction:.3g} of the noise variance {noise_var:g})"
                )
    if steady and not _level_within(s1, s2, MIN_SEGMENT, limits.max_level_jump):
        ratio, (start, stop) = _level_jump(s1, s2, MIN_SEGMENT)
    else:  # (the usual case: no segment can reach the limit, `_level_within`)
        ratio, (start, stop) = 1.0, (0, 0)
    if ratio > limits.max_level_jump:
        shown = numbers_text(ratio, limits.max_level_jump, digits=3)[0]
        return (
            f"signal level jumps within the block: the variance of samples {start}-{stop - 1} "
            f"differs from the rest's by a factor {shown} (allowed {limits.max_level_jump:g})"
        )
    if steady:  # (the usual case: no stretch to scan, `_short_levels_to_scan`)
        for stretch, limit in _short_levels_to_scan(s1, s2):
            # at free fall itself, or (a known noise sd) |free fall| from the rest's mean
            mean = None if flight is None else float(a.mean())  # (`NEAR_FLIGHT`)
            ratio, start = _short_level_drop(s1, s2, stretch, limits.free_fall_mps2, mean)
            if ratio > limit:
                return (
                    f"signal level drops within the block: the variance of samples {start}-"
                    f"{start + stretch - 1} is 1/{numbers_text(ratio, limit, digits=3)[0]} of "
                    "the rest's and of the samples' "
                    f"before it (allowed 1/{limit:g} for {stretch} samples)"
                )
    if limits.static_mps2 is not None:
        return static_level(float(a.sum() / a.size), a.size, limits)
    return ""


def static_level(mean: float, n: int, limits: SensorLimits) -> str:
    """The static-level check (``SensorLimits.static_mps2``): why a block of ``n`` samples
    whose mean acceleration is ``mean`` (m/s^2) cannot come from a healthy axis of that static
    level (a scale fault, or an axis tilted from the vertical), or "" (also without a level)."""
    if limits.static_mps2 is None or n < 1:
        return ""
    tol = limits.static_tolerance * max(1.0, STATIC_BLOCK / n)
    return _off_static(mean, limits.static_mps2, tol, "the block's mean acceleration", f"{n}")


def static_span_level(mean: float, limits: SensorLimits) -> str:
    """The static-level check's long span (``SensorLimits.static_span``): why the mean
    acceleration ``mean`` (m/s^2) of the newest ``static_span`` contiguous samples cannot come
    from a healthy axis of level ``static_mps2`` (beyond ``static_span_tolerance``), or "" (also
    without a level or a span)."""
    if limits.static_mps2 is None or not limits.static_span:
        return ""
    n = limits.static_span
    return _off_static(
        mean, limits.static_mps2, limits.static_span_tolerance,
        f"the last {n} samples' mean acceleration", f"a span of {n} (static_span)",
    )  # fmt: skip


def _off_static(mean: float, static: float, tol: float, what: str, over: str) -> str:
    """The reason of `static_level` and `static_span_level` for ``what`` reading ``mean``
    (m/s^2) against the level ``static`` and the tolerance ``tol`` over ``over`` samples, or
    "" within it."""
    ratio = mean / static
    if abs(ratio - 1.0) <= tol:
        return ""
    if ratio <= 0:
        why = "an axis of the other sign (flipped), or gravity removed"
    elif ratio < 1:
        tilt = float(np.degrees(np.arccos(ratio)))
        why = f"a sensor gain of about {ratio:.2g}, or an axis tilted ~{tilt:.0f} deg"
    else:
        why = f"a sensor gain of about {ratio:.2g}"
    shown, lo, hi = numbers_text(ratio, 1 - tol, 1 + tol, digits=3)
    return (
        f"scale or tilt: {what} {mean:.4g} m/s^2 is {shown} of the static level {static:g} "
        f"m/s^2 a healthy axis reads (allowed {lo}-{hi} over {over} samples): {why}"
    )


class StaticSpan:
    """The newest ``size`` contiguous samples of a stream (the static-level check's long span,
    `static_span_level`): a ring in which each sample sits at its place in the stream modulo
    ``size``, and again ``size`` slots on, so that the span is one contiguous stretch of it in
    the stream's order. Its mean, summed afresh at each check (one sum of ``size`` values: ~1 us
    for 1,000), is then bit for bit the sum of those samples as a recording's (the replay's
    `static_level_marks`), whatever the chunking and wherever the span started."""

    def __init__(self, size: int) -> None:
        self._size = size
        self._ring = np.empty(2 * size)
        self.restart()

    def __setstate__(self, state: dict) -> None:
        # (pickled in session 75: each sample once, at its place modulo size; a running sum)
        if "_size" not in state:
            ring = state.pop("_ring")
            state = {**state, "_size": ring.size, "_ring": np.concatenate([ring, ring])}
            state.pop("_total", None), state.pop("_exact", None)
        self.__dict__.update(state)

    def restart(self) -> None:
        """Forget every sample (a break in the stream: the span starts again; the ring's old
        values are all overwritten before it is full again)."""
        self._next, self._held = 0, 0

    def state(self) -> tuple:
        """What `restore` takes back to (a copy of the ring: ~1 us for 1,000 samples)."""
        return self._ring.copy(), self._next, self._held

    def restore(self, state: tuple) -> None:
        """Return to a `state` taken of this span (a call that failed part way: `BCR.update`)."""
        ring, self._next, self._held = state
        self._ring[:] = ring

    @property
    def full(self) -> bool:
        """Whether the span holds ``size`` samples."""
        return self._held == self._size

    def push(self, a: np.ndarray) -> None:
        """Append the samples ``a`` (finite, m/s^2), the oldest ones leaving."""
        ring, size, k = self._ring, self._size, a.size
        self._held = min(self._held + k, size)
        start = self._next
        if k > size:  # only the newest size samples stay, each in its slot of the stream
            start, a, k = (start + k - size) % size, a[k - size :], size
        stop = start + k  # (at most 2 size: each sample in its slot, then its copy)
        ring[start:stop] = a
        if stop <= size:
            ring[start + size : stop + size] = a
        else:
            ring[start + size :] = a[: size - start]
            ring[: stop - size] = a[size - start :]
        self._next = stop % size

    def mean(self) -> float:
        """The span's mean, m/s^2 (inf or NaN where values beyond any accelerometer's overflow
        the sum: a fault then)."""
        size = self._size
        with np.errstate(over="ignore", invalid="ignore"):
            return float(self._ring[self._next : self._next + size].sum() / size)


def static_span_fault(span: StaticSpan, limits: SensorLimits) -> str:
    """`static_span_level` of a full `StaticSpan` ("" before it is full)."""
    if limits.static_mps2 is None or not span.full:
        return ""
    return static_span_level(span.mean(), limits)


def _distinct_count(ordered: np.ndarray, positive_gaps: np.ndarray) -> int:
    """``np.unique(ordered).size`` of sorted values, from their positive gaps: NaNs (sorted
    last) count as one value, as np.unique counts them."""
    nan_group = bool(np.isnan(ordered[-1]) and not np.isnan(ordered[0]))
    return 1 + positive_gaps.size + nan_group


def flight_reading(limits: SensorLimits) -> float | None:
    """The reading the dead-sensor and lattice checks exempt as a wheel in the air: the limits'
    ``free_fall_mps2`` for a sensor without known noise, None (no exemption) for one with it (a
    noisy flight neither holds one value nor sits on a lattice)."""
    return limits.free_fall_mps2 if limits.noise_sd_mps2 is None else None


def dead_stretch(a: np.ndarray, fraction: float, free_fall: float | None) -> int:
    """Start of the first stretch of ``DEAD_STRETCH`` samples of ``a`` whose range is below
    ``fraction`` times the standard deviation of ``a``, its mean not within 5% of ``free_fall``;
    -1 if none (or ``a`` is shorter than a stretch)."""
    return _dead_stretch(a, fraction, free_fall, float(np.std(a)))


def _dead_stretch(
    a: np.ndarray, fraction: float, free_fall: float | None, sd: float,
    spread: np.ndarray | None = None, slow: np.ndarray | None = None,
) -> int:  # fmt: skip
    """`dead_stretch` with the standard deviation ``sd`` of ``a`` known, and the range of each
    stretch (``spread``, by start: from `_sorted_runs`) where given; a stretch that takes in a
    ``slow`` sample (`signal_fault`) is none."""
    n = a.size - DEAD_STRETCH + 1
    if n < 1:
        return -1
    if spread is None:
        hi, lo = a[:n].copy(), a[:n].copy()
        for j in range(1, DEAD_STRETCH):  # running max and min over the stretch
            np.maximum(hi, a[j : j + n], out=hi)
            np.minimum(lo, a[j : j + n], out=lo)
        spread = hi - lo
    dead = spread < fraction * sd
    if not dead.any():  # the usual case: no flight exemption to work out
        return -1
    if slow is not None and slow.any():
        dead &= np.convolve(slow, np.ones(DEAD_STRETCH), mode="valid")[:n] == 0
    if free_fall is not None:
        total = a[:n].copy()
        for j in range(1, DEAD_STRETCH):  # running sum over the stretch
            total += a[j : j + n]
        dead &= ~_in_flight(total / DEAD_STRETCH, free_fall)
    hit = np.flatnonzero(dead)
    return int(hit[0]) if hit.size else -1


def _in_flight(x: np.ndarray, free_fall: float) -> np.ndarray:
    """Where ``x`` lies within 5% of ``free_fall``: what a wheel in the air reads."""
    return np.abs(x - free_fall) <= 0.05 * abs(free_fall)


def most_lattice_like(
    a: np.ndarray, free_fall: float | None = FREE_FALL_MPS2
) -> tuple[float, int, int, float]:
    """What the lattice check compares with ``SensorLimits.lattice_p``: (the smallest
    `lattice_stretch` probability over ``LATTICE_STRETCHES`` times their number (Bonferroni),
    that stretch's start, its length, its step in m/s^2)."""
    return _most_lattice_like(a, free_fall, _resolution(a))


def _most_lattice_like(
    a: np.ndarray, free_fall: float | None, resolution: float | None,
    sorted_runs: np.ndarray | None = None,
) -> tuple[float, int, int, float]:  # fmt: skip
    """`most_lattice_like` with the block's `_resolution` known (and `_sorted_runs` of
    ``DEAD_STRETCH`` samples, where given: that stretch's)."""
    if free_fall is not None and not _in_flight(a, free_fall).any():
        free_fall = None  # (the usual case: no value of the block to exempt)
    found = [
        (*_lattice_stretch(a, n, free_fall, resolution,
                           sorted_runs if n == DEAD_STRETCH else None), n)
        for n in LATTICE_STRETCHES
    ]  # fmt: skip
    p, start, step, stretch = min(found, key=lambda f: f[0])
    return p * len(LATTICE_STRETCHES), start, stretch, step


def lattice_stretch(
    a: np.ndarray, stretch: int, free_fall: float | None = FREE_FALL_MPS2
) -> tuple[float, int, float]:
    """How lattice-like the most lattice-like ``stretch`` consecutive samples of ``a`` are:
    (probability, the stretch's start, the step in m/s^2); (1, -1, nan) if no stretch is.

    For each stretch and each step ``g`` between two of its values that are neighbours in
    value, counts the stretch's other values that lie within r/2 of the lattice through those
    two (r: the block's resolution, its smallest gap between distinct values, at least the
    sensor's). A healthy sensor puts a value there with probability at most ``2 r / g``, so the
    binomial tail of the count, times the number of steps tried (Bonferroni), bounds the chance
    of that many hits; a signal rounded to a coarse step puts every value there. Values within
    5% of ``free_fall`` (a wheel in the air reads it) neither count nor make a step.
    """
    _check_count(stretch, "stretch", 2)
    return _lattice_stretch(a, stretch, free_fall, _resolution(a))


def _check_count(value, name: str, least: int) -> None:
    """ControlError unless ``value`` is an integer >= ``least`` (samples)."""
    if not (is_integer(value) and value >= least):
        raise ControlError(f"{name} must be an integer >= {least} (samples), got {value!r}")


def _resolution(a: np.ndarray) -> float | None:
    """The smallest gap between distinct values of ``a`` (None for fewer than two)."""
    gaps = np.diff(np.sort(a))
    gaps = gaps[gaps > 0]
    return float(gaps.min()) if gaps.size else None


def _lattice_stretch(
    a: np.ndarray, stretch: int, free_fall: float | None, resolution: float | None,
    ordered: np.ndarray | None = None,
) -> tuple[float, int, float]:  # fmt: skip
    """`lattice_stretch` with the block's `_resolution` known (and its `_sorted_runs` of
    ``stretch`` samples, ``ordered``, where given)."""
    if resolution is None or a.size < stretch:
        return 1.0, -1, float("nan")
    if ordered is None:
        ordered = _sorted_runs(a, stretch)  # (stretch, stretches)
    if free_fall is not None:  # a wheel in the air's values as NaN: they neither count nor
        # make a step (every comparison with NaN is False), in their places in value order
        ordered = np.where(_in_flight(ordered, free_fall), np.nan, ordered)
    low = ordered[:-1]
    step = ordered[1:] - low  # (stretch - 1 steps, stretches): neighbours in value
    usable = step > resolution
    if not usable.any():
        return 1.0, -1, float("nan")
    g = np.where(usable, step, 1.0)
    # |x - rint(x)| g <= r / 2 with x = (value - low) / g for each of the stretch's other values
    # than the two that make the step (they lie on it), in one buffer (in place): this (others,
    # steps, stretches) array is the check's main cost; g, (steps, stretches), spans its inner
    # axes (one pass of the ufunc loop over them)
    x = ordered[_others(stretch)]
    x -= low
    x /= g
    x -= np.rint(x)
    np.abs(x, out=x)
    x *= g
    on = x <= 0.5 * resolution
    # (counted in the smallest type that holds the stretch: a sum into int64 costs ~2x as much)
    hits = on.sum(axis=0, dtype=np.min_scalar_type(stretch))
    found = np.flatnonzero(usable & (hits > 0))  # (steps, stretches), in C order
    if found.size == 0:
        return 1.0, -1, float("nan")
    chance = np.minimum(1.0, 2.0 * resolution / g.ravel()[found])
    p = bdtrc(hits.ravel()[found] - 1, stretch - 2, chance)  # P(hits or more)
    k = int(np.argmin(p))
    row, col = divmod(int(found[k]), g.shape[1])
    return float(p[k] * (stretch - 1)), col, float(step[row, col])


@functools.lru_cache(maxsize=8)
def _others(stretch: int) -> np.ndarray:
    """Indices (stretch - 2, stretch - 1) of a sorted stretch's values other than the two that
    make each step: column i, those of the step from value i to value i + 1. Read-only."""
    steps = [[j for j in range(stretch) if j not in (i, i + 1)] for i in range(stretch - 1)]
    index = np.array(steps, dtype=np.intp).reshape(stretch - 1, stretch - 2).T.copy()
    index.flags.writeable = False
    return index


def _sorted_runs(a: np.ndarray, stretch: int) -> np.ndarray | None:
    """Every ``stretch`` consecutive samples of ``a``, each sorted: (stretch, n - stretch + 1),
    column i the samples i..i+stretch-1 in increasing order; None if ``a`` is shorter."""
    if a.size < stretch:
        return None
    return np.sort(a[_window_index(a.size, stretch)], axis=0)


@functools.lru_cache(maxsize=16)
def _window_index(n: int, stretch: int) -> np.ndarray:
    """Indices (stretch, n - stretch + 1) of every ``stretch`` consecutive of n samples."""
    return np.arange(stretch)[:, None] + np.arange(n - stretch + 1)


@functools.lru_cache(maxsize=8)
def noise_floors(noise_floor: float) -> tuple[tuple[int, float], ...]:
    """(stretch in samples, fraction of the noise variance) of each noise-floor check, longest
    first: ``NOISE_STRETCH`` at ``noise_floor``, and each of ``SHORT_NOISE_STRETCHES`` at the
    fraction below which the variance of that many samples of pure Gaussian noise falls with the
    same probability (chi-square)."""
    p = chi2.cdf(noise_floor * (NOISE_STRETCH - 1), NOISE_STRETCH - 1)
    shorter = sorted(SHORT_NOISE_STRETCHES, reverse=True)
    return ((NOISE_STRETCH, noise_floor),) + tuple(
        (n, float(chi2.ppf(p, n - 1) / (n - 1))) for n in shorter
    )


def quietest_stretch(a: np.ndarray, stretch: int = NOISE_STRETCH) -> tuple[float, int]:
    """(smallest variance about its own mean of any ``stretch`` consecutive samples of ``a``,
    its start); (inf, -1) if ``a`` is shorter than a stretch."""
    _check_count(stretch, "stretch", 2)
    if a.size < stretch:
        return float("inf"), -1
    s1, s2, _ = _centred_sums(a)
    return _quietest_stretch(s1, s2, stretch)


def _quietest_stretch(s1: np.ndarray, s2: np.ndarray, stretch: int) -> tuple[float, int]:
    """`quietest_stretch` from the block's `_centred_sums`."""
    if s1.size - 1 < stretch:
        return float("inf"), -1
    variance = np.maximum(_stretch_spreads(s1, s2, stretch) / (stretch - 1), 0.0)
    i = int(np.argmin(variance))
    return float(variance[i]), i


def _stretch_spreads(s1: np.ndarray, s2: np.ndarray, stretch: int) -> np.ndarray:
    """Each run of ``stretch`` consecutive samples' sum of squares about its own mean, by start,
    from the block's `_centred_sums` (at least ``stretch`` samples)."""
    total, squares = s1[stretch:] - s1[:-stretch], s2[stretch:] - s2[:-stretch]
    return squares - total * total / stretch


def _near_equal_groups(
    ordered: np.ndarray, gaps: np.ndarray, tol: float
) -> tuple[np.ndarray, np.ndarray]:
    """(a value, the count) of each group of sorted values ``ordered`` (``gaps``: their
    differences) equal within ``tol`` (``NEAR_EQUAL`` of their largest magnitude)."""
    starts = np.concatenate([[0], np.flatnonzero(gaps > tol) + 1])
    return ordered[starts], np.diff(np.concatenate([starts, [ordered.size]]))


def level_jump(a: np.ndarray, min_segment: int = MIN_SEGMENT) -> tuple[float, tuple[int, int]]:
    """(largest ratio between the variance of a segment of ``a`` and that of the rest, the
    segment as (start, stop)) over the segments with at least ``min_segment`` samples inside and
    outside; each part's variance about its own mean, so that a part held near any constant (a
    gain that dropped) counts as no variance. Only drops count: a quiet segment is held to the
    samples before it as well (the smaller of the two ratios), a loud one to the samples after
    it, and one with fewer than ``min_segment`` samples on that side scores 1. A level that only
    rises (a quiet start, then louder to the block's end: a robot driving from a smooth floor
    onto rough ground, a simulated track's flat lead-in, a signal coming back) reads rougher,
    never smoother; a gain that falls reads smoother, and the first block of the change-point
    BCR that holds its fall holds it late (at the default three updates a block, with 83 or more
    samples before it). (1, (0, 0)) for blocks shorter than 2 * min_segment."""
    _check_count(min_segment, "min_segment", 2)
    if a.size < 2 * min_segment:
        return 1.0, (0, 0)
    s1, s2, _ = _centred_sums(a)
    return _level_jump(s1, s2, min_segment)


def _level_jump(s1: np.ndarray, s2: np.ndarray, min_segment: int) -> tuple[float, tuple[int, int]]:
    """`level_jump` from the block's `_centred_sums`."""
    n = s1.size - 1
    if n < 2 * min_segment:
        return 1.0, (0, 0)
    best = (1.0, (0, 0))
    before, after = _part_variances(s1, s2, min_segment)
    per_chunk = _starts_per_chunk(n)
    for first in range(0, n + 1, per_chunk):
        start, stop, (n_in, n_in_1, n_out, n_out_1) = _segments(n, min_segment, first, per_chunk)
        if start.size == 0:
            continue
        # (sq - sum**2 / count) / (count - 1) of each part, in place: the same operations,
        # fewer temporaries
        sum_in, sq_in = s1[stop] - s1[start], s2[stop] - s2[start]
        var_in = sum_in * sum_in
        var_in /= n_in
        np.subtract(sq_in, var_in, out=var_in)
        var_in /= n_in_1
        np.maximum(var_in, 0.0, out=var_in)
        var_out = s1[-1] - sum_in
        var_out *= var_out
        var_out /= n_out
        np.subtract(s2[-1] - sq_in, var_out, out=var_out)
        var_out /= n_out_1
        np.maximum(var_out, 0.0, out=var_out)
        with np.errstate(divide="ignore", invalid="ignore"):  # a drop, either way round:
            ratio = var_in / np.maximum(var_out, after[stop])  # loud, then quieter after it
            np.maximum(ratio, np.minimum(var_out, before[start]) / var_in, out=ratio)  # quiet
        np.fmax(ratio, 1.0, out=ratio)  # NaN (0 / 0: both parts constant) as 1; the rest >= 1
        i = int(np.argmax(ratio))
        if ratio[i] > best[0]:
            best = (float(ratio[i]), (int(start[i]), int(stop[i])))
    return best


def _level_within(s1: np.ndarray, s2: np.ndarray, min_segment: int, limit: float) -> bool:
    """Whether every ratio `_level_jump` computes from the block's `_centred_sums` provably
    stays below ``limit`` (False: it may not), in O(n) against its O(n^2) segments.

    A segment [s, e) of L samples, m = ``min_segment`` <= L <= n - m, has a variance of at most
    the sum of squares of [0, e) over m - 1 (a sum of squares about its own mean only grows as
    samples join), and at least that of [s, s + m) over n - m - 1; so its ratio to the samples
    after it is at most before[e] (e - 1) / (m - 1) / after[e], and that of the samples before it
    to it at most before[s] (n - m - 1) / (var[s, s + m) (m - 1)). Both bounds are held to half
    the limit, each variance widened by ``delta``, a bound on the rounding of the cumulative
    sums (8 n^2 eps times the block's sum of squares, over m - 1)."""
    n, m = s1.size - 1, min_segment
    if n < 2 * m:
        return True
    before, after = _part_variances(s1, s2, m)
    delta = 8.0 * n * n * EPS * s2[-1] / (m - 1)
    ends = slice(m, n - m + 1)  # the ends (and starts) of segments with m samples beyond them
    inside_hi = (before[ends] + delta) * np.arange(m - 1, n - m) / (m - 1) + delta
    if not (inside_hi <= 0.5 * limit * after[ends]).all():
        return False
    total, squares = s1[2 * m :] - s1[ends], s2[2 * m :] - s2[ends]  # [s, s + m) from each s
    first = (squares - total * total / m) / (m - 1)
    inside_lo = (first - delta) * (m - 1) / (n - m - 1) - delta
    return bool((before[ends] <= 0.5 * limit * inside_lo).all())


def short_level_drop(
    a: np.ndarray, stretch: int, free_fall: float | None = FREE_FALL_MPS2, *, anchored: bool = True
) -> tuple[float, int]:
    """What the short level check compares with its limit (`SHORT_LEVEL_STRETCHES`): (the
    largest ratio, over the stretches of ``stretch`` consecutive samples of ``a``, of the
    smallest of the variances of the rest of ``a`` and of each half of the samples before the
    stretch to the stretch's variance, each about its own mean; that stretch's start). Only
    drops count, as in `level_jump`: a level loud before the stretch throughout (one loud
    sample before a quiet start makes no drop); a stretch with fewer than
    ``SHORT_LEVEL_BEFORE`` samples before it scores 1, and so does one whose mean lies within
    ``NEAR_FLIGHT`` of |``free_fall``| of ``free_fall`` (a wheel in the air; None: no
    exemption; ``anchored=False``: of |``free_fall``| above or below the rest's mean, blind to
    an offset and to the sign as `signal_fault` is where the noise sd is known: gravity kept
    puts a flight near 0, a flipped axis near +g); a stretch held constant (a dead one) scores
    inf. (1, -1) if none is scored."""
    _check_count(stretch, "stretch", 2)
    a = np.asarray(a, dtype=float)
    if a.ndim != 1:
        raise ControlError(f"a must be a 1-D block of accelerations, got shape {a.shape}")
    if a.size == 0:
        return 1.0, -1
    s1, s2, _ = _centred_sums(a)
    return _short_level_drop(s1, s2, stretch, free_fall, float(a.mean()) if anchored else None)


def _least_spread(s1: np.ndarray, s2: np.ndarray, stretch: int) -> float:
    """The smallest sum of squares about its own mean of any ``stretch`` consecutive samples,
    from the block's `_centred_sums` (inf if there are fewer samples)."""
    if s1.size - 1 < stretch:
        return float("inf")
    return float(_stretch_spreads(s1, s2, stretch).min())


def _short_levels_to_scan(
    s1: np.ndarray,
    s2: np.ndarray,
    stretches: tuple[tuple[int, float], ...] = SHORT_LEVEL_STRETCHES,
) -> list[tuple[int, float]]:
    """The (stretch, limit) pairs of ``stretches`` (lengths in increasing order) whose ratios
    `_short_level_drop` may find above the limit from the block's `_centred_sums` (the others
    provably stay at or below it), in O(n) for them all: the variance a stretch is held to (the
    smallest of the rest's and the halves') is at most the rest's, at most the block's sum of
    squares over n - stretch - 1, and the stretch's own sum of squares about its mean is at
    least the `_least_spread` of the shortest stretches (a stretch holds a shorter one, and such
    a sum only grows as samples join), else of its own length. Each side is widened by a bound
    on the cumulative sums' rounding (8 n^2 eps times the block's sum of squares, as in
    `_level_within`)."""
    n, total = s1.size - 1, float(s2[-1])
    delta = 8.0 * n * n * EPS * total
    shortest = stretches[0][0]
    least = _least_spread(s1, s2, shortest) - 2.0 * delta
    scan = []
    for stretch, limit in stretches:
        if n < stretch + SHORT_LEVEL_BEFORE + 2:
            continue
        most = (total + delta) * (stretch - 1) / (limit * (n - stretch - 1))
        if least >= most or (
            stretch != shortest and _least_spread(s1, s2, stretch) - 2.0 * delta >= most
        ):  # (the shortest's own: ``least``)
            continue
        scan.append((stretch, limit))
    return scan


def _short_level_drop(
    s1: np.ndarray, s2: np.ndarray, stretch: int, free_fall: float | None, mean: float | None
) -> tuple[float, int]:
    """`short_level_drop` from the block's `_centred_sums` and ``mean`` (the sums are
    centred on it; None: ``anchored=False``, a flight |``free_fall``| from the rest's mean,
    either way)."""
    n, m, k = s1.size - 1, stretch, SHORT_LEVEL_BEFORE
    if n < m + k + 2:  # (a stretch with k samples before it and 2 after, for their variance)
        return 1.0, -1
    # the stretches [s, s + m) with s >= k (fewer samples before: a level that rises, scores 1)
    lead_1, lead_2 = s1[k : n - m + 1], s2[k : n - m + 1]  # sums of the samples before each
    total, squares = s1[k + m :] - lead_1, s2[k + m :] - lead_2
    inside = (squares - total * total / m) / (m - 1)
    np.maximum(inside, 0.0, out=inside)
    rest_1, rest_2 = s1[-1] - total, s2[-1] - squares  # a drop: quieter than the rest ...
    rest = (rest_2 - rest_1 * rest_1 / (n - m)) / (n - m - 1)
    # ... and than each half of the samples before it: loud before it throughout (one loud sample
    # before a quiet start is a level that rises, not a drop)
    start = np.arange(k, n - m + 1)
    half = start // 2
    for lo_1, lo_2, hi_1, hi_2, count in (
        (0.0, 0.0, s1[half], s2[half], half),
        (s1[half], s2[half], lead_1, lead_2, start - half),
    ):
        part_1, part_2 = hi_1 - lo_1, hi_2 - lo_2
        np.minimum(rest, (part_2 - part_1 * part_1 / count) / (count - 1), out=rest)
    np.maximum(rest, 0.0, out=rest)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = rest / inside
    if free_fall is not None:  # a wheel in the air (`NEAR_FLIGHT`)
        if mean is None:  # offset and sign unknown: |free_fall| from the rest's mean
            off = np.abs(total * (n / (m * (n - m)))) - abs(free_fall)
        else:
            off = total / m - (free_fall - mean)
        ratio[np.abs(off) <= NEAR_FLIGHT * abs(free_fall)] = 1.0
    np.fmax(ratio, 1.0, out=ratio)  # NaN (0 / 0: constant parts) as 1
    i = int(np.argmax(ratio))
    return float(ratio[i]), (i + k if ratio[i] > 1.0 else -1)


def _part_variances(
    s1: np.ndarray, s2: np.ndarray, min_segment: int
) -> tuple[np.ndarray, np.ndarray]:
    """(before, after): before[i] the variance of samples 0..i-1, after[j] that of samples
    j..n-1, each about its own mean, from the block's `_centred_sums`; 0 before fewer than
    ``min_segment`` samples, inf after fewer (a side too short to hold a level: no drop)."""
    n = s1.size - 1
    count = np.arange(n + 1, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        before = (s2 - s1 * s1 / count) / (count - 1)
        rest = count[::-1]
        tail1, tail2 = s1[-1] - s1, s2[-1] - s2
        after = (tail2 - tail1 * tail1 / rest) / (rest - 1)
    before[:min_segment] = 0.0
    after[n - min_segment + 1 :] = np.inf
    return np.maximum(before, 0.0), np.maximum(after, 0.0)


def _centred_sums(a: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Cumulative sums (with a leading 0) of ``a - mean(a)`` and of its square: the sum of
    samples i..j-1 is s[j] - s[i] (centred first: fewer cancellation digits); and the standard
    deviation of ``a`` from the same squares (np.std's operations, to the last bit)."""
    x = a - a.sum() / a.size  # a.mean(): its operations, without its wrapper
    squares = x * x
    s1, s2 = np.zeros(a.size + 1), np.zeros(a.size + 1)
    np.cumsum(x, out=s1[1:])
    np.cumsum(squares, out=s2[1:])
    return s1, s2, float(np.sqrt(squares.sum() / a.size))


SEGMENT_PAIRS_PER_CHUNK = 1 << 16
"""The level check compares every segment of a block with the rest, O(n^2) pairs; it takes them
in chunks of about this many, so that its memory stays bounded for long blocks."""


def _starts_per_chunk(n: int) -> int:
    return max(1, SEGMENT_PAIRS_PER_CHUNK // (n + 1))


@functools.lru_cache(maxsize=8)
def _segments(
    n: int, min_segment: int, first: int, count: int
) -> tuple[np.ndarray, np.ndarray, tuple[np.ndarray, ...]]:
    """(start, stop, counts) of every segment of n samples with >= min_segment samples in and
    out whose start lies in [first, first + count); counts: (samples inside, the same - 1,
    samples outside, the same - 1) as floats. Read-only: every call shares them."""
    start, stop = np.meshgrid(
        np.arange(first, min(first + count, n + 1)), np.arange(n + 1), indexing="ij"
    )
    keep = (stop - start >= min_segment) & (n - (stop - start) >= min_segment)
    start, stop = start[keep], stop[keep]
    n_in = (stop - start).astype(float)
    counts = n_in, n_in - 1, n - n_in, n - n_in - 1
    for arr in (start, stop, *counts):
        arr.flags.writeable = False
    return start, stop, counts


@dataclass(frozen=True)
class StreamBreaks:
    """What broke a stream's samples (`stream_breaks`), counted so that the counts of
    consecutive chunks add up (``a + b``) to those of the chunks joined: the reason of an
    update's samples does not depend on how they were chunked.

    Attributes:
        nonfinite: samples with a non-finite value; names: which of t, position, accel, speed
            held one (`STREAM_FIELDS` order).
        too_fast: samples with |speed| beyond ``MAX_SPEED_MPS``; fastest: the largest such
            |speed|, m/s.
        backwards: repeated or backwards time stamps.
        worst_gap: the largest step above 1.5 periods, s (0: none).
    """

    nonfinite: int = 0
    names: tuple[str, ...] = ()
    too_fast: int = 0
    fastest: float = 0.0
    backwards: int = 0
    worst_gap: float = 0.0

    def __add__(self, other: StreamBreaks) -> StreamBreaks:
        names = tuple(n for n in STREAM_FIELDS if n in self.names or n in other.names)
        return StreamBreaks(
            self.nonfinite + other.nonfinite,
            names,
            self.too_fast + other.too_fast,
            max(self.fastest, other.fastest),
            self.backwards + other.backwards,
            max(self.worst_gap, other.worst_gap),
        )

    def reason(self, rate_hz: float) -> str:
        """The sentence naming them ("" for none), for a stream at ``rate_hz``."""
        what = []
        if self.nonfinite:
            what.append(f"{self.nonfinite} sample(s) with non-finite {'/'.join(self.names)}")
        if self.too_fast:
            what.append(
                f"{self.too_fast} sample(s) with |speed| up to "
                f"{numbers_text(self.fastest, MAX_SPEED_MPS, digits=3)[0]} m/s, beyond any "
                f"ground robot's (MAX_SPEED_MPS = {MAX_SPEED_MPS:g} m/s)"
                + _speed_unit_hint(self.fastest)
            )
        if self.backwards:
            what.append(f"{self.backwards} repeated or backwards time stamp(s)")
        if self.worst_gap:
            dt = 1.0 / rate_hz
            what.append(
                f"a gap of {self.worst_gap:.4g} s (about {round(self.worst_gap / dt) - 1:.4g} "
                f"dropped samples)" + _stamp_unit_hint(self.worst_gap / dt)
            )
        return " and ".join(what)


STREAM_FIELDS = ("t", "position", "accel", "speed")
"""The arrays of a stream, in the order `StreamBreaks.names` lists them."""
NO_BREAKS = StreamBreaks()
"""The `StreamBreaks` of samples that break nothing."""


def stream_breaks(
    t: np.ndarray, position: np.ndarray, accel: np.ndarray, speed: np.ndarray, t_prev: float,
    rate_hz: float,
) -> tuple[np.ndarray, np.ndarray, StreamBreaks]:  # fmt: skip
    """Samples that break the stream: (drop (n,), restart (n,), `StreamBreaks`).

    ``drop`` marks samples to discard: a value that is not finite, a speed beyond
    ``MAX_SPEED_MPS``, or a time stamp that repeats or goes backwards (a step below half a
    period from the previous sample; ``t_prev``: the time of the sample before the first, NaN
    if none). ``restart`` marks samples after a gap (a step above 1.5 periods: dropped
    samples): they are kept but begin a new contiguous run.
    """
    dt = 1.0 / rate_hz
    if _unbroken(t, position, accel, speed, t_prev, dt):  # (the usual case)
        unbroken = np.zeros(t.size, dtype=bool)
        return unbroken, unbroken.copy(), NO_BREAKS
    finite = np.isfinite(t) & np.isfinite(position) & np.isfinite(accel) & np.isfinite(speed)
    with np.errstate(invalid="ignore"):
        too_fast = np.abs(speed) > MAX_SPEED_MPS
    bad_value = ~finite | too_fast
    with np.errstate(invalid="ignore"):  # inf - inf (an inf stamp after an inf t_prev): NaN
        step = t - _previous_finite(t, t_prev)
    finite_step = np.isfinite(step)  # a non-finite time stamp is a bad value, not a step
    with np.errstate(invalid="ignore"):
        backwards = finite_step & (step < 0.5 * dt)
        gap = finite_step & (step > 1.5 * dt)
    breaks = NO_BREAKS
    if not finite.all() or too_fast.any() or backwards.any() or gap.any():
        arrays = zip(STREAM_FIELDS, (t, position, accel, speed), strict=True)
        breaks = StreamBreaks(
            int((~finite).sum()),
            tuple(name for name, a in arrays if not np.all(np.isfinite(a))),
            int(too_fast.sum()),
            float(np.max(np.abs(speed[too_fast]))) if too_fast.any() else 0.0,
            int(backwards.sum()),
            float(np.max(step[gap])) if gap.any() else 0.0,
        )
    return bad_value | backwards, gap & ~bad_value, breaks


def _unbroken(
    t: np.ndarray, position: np.ndarray, accel: np.ndarray, speed: np.ndarray, t_prev: float,
    dt: float,
) -> bool:  # fmt: skip
    """Whether `stream_breaks` finds nothing (True: every value finite, no |speed| beyond
    ``MAX_SPEED_MPS``, every step from ``t_prev`` on within [0.5, 1.5] periods ``dt``), in a
    few whole-array reductions; False where it may find something. A finite sum has finite
    terms (a sum of finite values that overflows reads False: `stream_breaks` then looks).
    Stamps other than float64 (the BCR's) read False: their steps, taken in their own dtype,
    may wrap around (integers) or round into the band (float32), where `stream_breaks`'s,
    taken in float64, do not."""
    if t.size == 0 or t.dtype.char != "d":
        return False
    with np.errstate(over="ignore", invalid="ignore"):  # (`stream_breaks` names what is wrong)
        total = t.sum() + position.sum() + accel.sum() + speed.sum()
        if not (np.isfinite(total) and -MAX_SPEED_MPS <= speed.min()
                and speed.max() <= MAX_SPEED_MPS):  # fmt: skip
            return False
        if t_prev == t_prev and not 0.5 * dt <= t[0] - t_prev <= 1.5 * dt:  # (NaN: no step)
            return False
        steps = t[1:] - t[:-1]
    return bool(steps.size == 0 or (steps.min() >= 0.5 * dt and steps.max() <= 1.5 * dt))


STAMP_UNITS = (("milliseconds", 1e3), ("microseconds", 1e6), ("nanoseconds", 1e9))
"""Time stamps in these units, fed as seconds, step by this many sample periods."""


def _stamp_unit_hint(periods: float) -> str:
    """A clause asking whether the stamps are in another unit than seconds, where a step of
    ``periods`` sample periods is 1e3, 1e6 or 1e9 of them (within 10%: a ROS stamp's
    nanoseconds fed as seconds read as gaps of ~8e6 s at 120 Hz), else ""."""
    for unit, factor in STAMP_UNITS:
        if abs(periods / factor - 1.0) < 0.1:
            return f"; if every step reads so, the time stamps are in {unit}: t must be seconds"
    return ""


def timing_fault(
    t: np.ndarray, position: np.ndarray, speed: np.ndarray, rate_hz: float, limits: SensorLimits
) -> str:
    """Why a block of contiguous samples (finite times s, positions m, speeds m/s) does not
    come from a stream at ``rate_hz`` with working odometry, or "": its time stamps span
    another duration than its samples at that rate (beyond ``limits.rate_tolerance``), or its
    positions advance otherwise than its speeds say (beyond ``limits.odometry_tolerance`` and
    ``limits.odometry_slack_m``), or a speed exceeds ``MAX_SPEED_MPS``."""
    if t.size < 2:
        return ""
    fastest = float(np.max(np.abs(speed)))
    if fastest > MAX_SPEED_MPS:  # before the odometry check integrates them (and overflows)
        return (
            f"out of range: |speed| reaches {numbers_text(fastest, MAX_SPEED_MPS, digits=3)[0]} "
            "m/s, beyond any ground robot's "
            f"(MAX_SPEED_MPS = {MAX_SPEED_MPS:g} m/s)" + _speed_unit_hint(fastest)
        )
    span, expected = float(t[-1] - t[0]), (t.size - 1) / rate_hz
    if abs(span / expected - 1.0) > limits.rate_tolerance:
        if not span > 0:  # (no rate to name)
            return f"time stamps that do not advance: the block's {t.size} stamps span {span:.4g} s"
        spans = numbers_text(span, expected, digits=4)
        return (
            f"samples at another rate: the block's {t.size} time stamps span {spans[0]} s "
            f"({(t.size - 1) / span:.4g} Hz), not the {spans[1]} s of {rate_hz:g} Hz"
        )
    moved = float(position[-1] - position[0])
    # np.trapezoid(speed, t): its operations, without its wrapper
    by_speed = float(((t[1:] - t[:-1]) * (speed[1:] + speed[:-1]) / 2.0).sum())
    if abs(moved - by_speed) > limits.odometry_tolerance * abs(by_speed) + limits.odometry_slack_m:
        moved_text, by_speed_text = numbers_text(moved, by_speed, digits=4)
        return (
            f"odometry disagrees with the speeds: the position moved {moved_text} m over the "
            f"block, its speeds give {by_speed_text} m" + _odometry_unit_hint(moved, by_speed)
        )
    return ""


ODOMETRY_UNIT_SLIPS = (
    (
        -1.0,
        "the position and the speeds advance in opposite directions: a distance remaining "
        "(counting down), or signed speeds beside a path length? position must be the distance "
        "travelled and speed its rate (both signed, or the speed's norm beside a path length)",
    ),
    (
        1.0 / 3.6,
        "the speeds read 3.6 times the position's rate: speed in km/h? speed must be "
        "m/s (km/h / 3.6)",
    ),
    (1e3, "the position moves 1000 times the speeds' distance: position in mm? it must be m"),
    (1e2, "the position moves 100 times the speeds' distance: position in cm? it must be m"),
    (
        1e-3,
        "the position moves 1/1000 of the speeds' distance: position in km, or speed in "
        "mm/s? they must be m and m/s",
    ),
    (1e-2, "the position moves 1/100 of the speeds' distance: speed in cm/s? it must be m/s"),
)
"""(ratio of the position's advance to the speeds' distance over a block, what it suggests):
the unit slips that `timing_fault` names where a block's ratio lies within 10% of one."""


def _speed_unit_hint(fastest: float) -> str:
    """A clause asking whether speeds beyond ``MAX_SPEED_MPS`` are in mm/s (up to 1000 times
    it: a ground robot's speed in mm/s), else ""."""
    if MAX_SPEED_MPS < fastest <= 1e3 * MAX_SPEED_MPS:
        return "; if every sample reads so, speed in mm/s? it must be m/s"
    return ""


def _odometry_unit_hint(moved: float, by_speed: float) -> str:
    """A clause naming the likely unit slip (`ODOMETRY_UNIT_SLIPS`) where the position's
    advance ``moved`` over a block is within 10% of one of those ratios to the speeds' distance
    ``by_speed`` (m), else "" (computed only for a block that fails the odometry check)."""
    if not by_speed:
        return ""
    ratio = moved / by_speed
    for factor, text in ODOMETRY_UNIT_SLIPS:
        if abs(ratio / factor - 1.0) < 0.1:
            return f"; if every block reads so, {text}"
    return ""


def _previous_finite(t: np.ndarray, t_prev: float) -> np.ndarray:
    """Per sample, the newest finite time stamp before it (``t_prev`` before the first; NaN
    if there is none)."""
    before = np.concatenate([[t_prev], t[:-1]])
    if np.isfinite(before[1:]).all():  # (the usual case) each sample's previous stamp
        return before
    index = np.where(np.isfinite(before), np.arange(before.size), 0)
    return before[np.maximum.accumulate(index)]
