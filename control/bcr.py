"""The Bayesian Calibration Routine (BCR): streaming accelerations in, GD posteriors out.

Methods (``BCRSettings.method``):

- ``"changepoint"`` (default): the samples are cut into disjoint blocks (125 samples, ~1 s at
  120 Hz); each block's feature vector (log band powers, `control.feature`) has a likelihood of
  GD from the emulator with the block scatter as known observation noise
  (`control.observation_model`), and a change-point filter (`control.changepoint`) pools every
  block since the last change of roughness and forgets within a few blocks after one. With
  ``update_every`` below the block length, K = ceil(block / update_every) such filters run
  interleaved ("phases"), each on its own disjoint blocks, which end K * update_every samples
  apart; every update feeds the block that just ended (the newest block_samples samples) to its
  phase and reports the phases' posteriors pooled, the phase with the newest information
  weighing K, the next K - 1, ... (an estimate every update_every samples; the default is three
  phases).
- ``"window"``: the paper's estimator: the moving buffer of the last 1,000 samples, its log
  variance, the posterior of that window alone under the emulator's prior (paper eqs. 3, 5).
- ``"filter"`` / ``"tempered"``: the previous default: the paper's windows combined by a grid
  filter with a change-point / random-walk prior (`control.tracker`), with disjoint interleaved
  windows or tempered overlapping ones.

A block next to a fault may hold part of it (a fault rarely starts or ends on a block boundary):
when a block is a fault or implausible, the change-point filter also undoes the block before it,
and skips the block after it (with phases: every phase undoes its newest block and skips its
next one, as those overlap the fault's block or the block before or after it).

Every update returns an `Estimate` whose status says why there is no number: ``filling`` (not
enough contiguous samples yet, or the first block after a fault), ``sensor_fault`` (non-finite
values, a speed beyond any vehicle's, dropped, repeated or backwards time stamps, a stuck,
quantised, clipped or dead signal, a static level off the one ``SensorLimits.static_mps2``
states, over a block or the last ``static_span`` samples: a scale fault), ``implausible`` (no
GD in the emulator's domain explains the observation; with the change-point method also where
a phase's last ``quiet_blocks`` blocks together read quieter than any GD explains: the
quiet-signal check, see below), ``out_of_domain`` (speed outside the emulator's range and no
earlier estimate), ``calibration_failed``, ``stale`` (no new information for ``max_age_s``).
While the speed is outside the emulator's range (e.g. standing) there is no new information:
the change-point estimate is carried on (its reason says so) until it turns stale.

The quiet-signal check: a sensor gain below 1 (or sensor noise below the emulator's) lowers
every band power and quantile and reads as smoother ground, within each block's scatter. Each
block's level score (`ObservationModel.level_score`: its residual at the best GD along the
direction a lower gain moves the feature, in sds) is kept per phase; where the last
``quiet_blocks`` scores, summed over the root of their count (over sqrt(nu / (nu - 2)) for a
Student-t block law), fall below the normal quantile of ``plausibility_p``, the estimate is
"implausible" (its ``plausibility_p`` the tail probability). With ``quiet_scan`` (default), so
do the newest k scores for every k below that (a scan for a drop at an unknown block: a gain
that drops mid-run reads quiet in its own blocks only, which the memory's older blocks dilute).
Ground smoother than the emulator's domain reads the same way (docs/closed-loop.md, "Guards").
A hold follows any "implausible" estimate (``release_p``): a phase that has not reached the
limit yet (its memory still holds blocks from before a gain dropped) would give an "ok"
estimate that reads the quiet blocks as smoother ground, so until every phase has read blocks
since the hold began, an estimate is "implausible" wherever a phase's scores of those blocks,
summed alike, fall below the normal quantile of ``release_p`` (at most until every phase's
memory of ``quiet_blocks`` was read since then: the check itself rules from there).

Frozen odometry: a block whose speeds all read standing (below ``STANDING_MPS``) carries the
last estimate, but a dead odometry (the pose held, the twist 0) reads so while the robot drives
on. With the quiet-signal check on, a standing block whose level score at the emulator's lowest
speed is not below the normal quantile of ``plausibility_p`` (the accelerometer reads as a
vehicle driving there, not as a sensor at rest reads its noise) is a "sensor_fault" once the
odometry has read standing for ``STANDING_SETTLE_S`` before it, and gives no estimate
("out_of_domain") before: a robot that stops rings on its suspension for a second or so.
Without the quiet-signal check (``quiet_blocks=0`` or ``plausibility_p=0``) and with the window
methods, a dead odometry reads as standing.
"""

from __future__ import annotations

import copy
import time as _time
import warnings
from collections import deque
from dataclasses import dataclass, field, replace
from itertools import islice
from math import floor, isfinite, sqrt

import numpy as np
from scipy.special import ndtr, ndtri

from control.changepoint import ChangePointFilter, ChangePointSettings, _mixture_posterior
from control.errors import ControlError, ControlWarning, EmulatorMismatchError, user_stacklevel
from control.estimate import EDGE_BAYES_FACTOR, EDGE_MARGIN, Estimate, favoured_edge, graver_fault
from control.feature import FeatureSpec, feature_of_variance, features_of_blocks
from control.sensor_checks import (
    MIN_SEGMENT,
    SensorLimits,
    StaticSpan,
    signal_fault,
    static_span_fault,
    stream_breaks,
    timing_fault,
)
from control.tracker import GDTracker, TrackerSettings
from control.validation import (
    check_instance,
    check_not_masked,
    is_choice,
    is_integer,
    is_real,
    python_number,
    replace_fields,
    require_instance,
    require_reals,
    within,
)
from gpmsa import Posterior
from gpmsa.errors import numbers_text
from roadgen.checks import tensor_values

METHODS = ("changepoint", "window", "filter", "tempered")
INTERVAL_KINDS = ("hdi", "central")
DEFAULT_PHASES = 3
"""Interleaved change-point filters by default: an estimate every third of a block (42 samples,
0.35 s at 120 Hz). Chosen on the development set of benchmarks/closed_loop_accuracy.py, with the
Simplex's speed grid, against two phases and four: the speed command moves about half as often
as with two phases (held out as well), the RMSE and coverage stay within the run-to-run scatter,
and the rise delay over 120 development tracks was 0.5 m shorter (on the held-out sets it moved
within its scatter; docs/closed-loop.md, "How often to estimate")."""
MAX_PHASES = 8
"""Most interleaved change-point filters (``block_samples / update_every``) a BCR runs."""
MAX_QUIET_BLOCKS = 1024
"""Longest memory of the quiet-signal check, blocks (`BCRSettings.quiet_blocks`)."""
MAX_SPEED_CHANGE = 0.5
"""A block whose lowest speed is below this fraction of its highest (starting, stopping) carries
no information for the change-point method: the emulator knows constant speeds only."""
CHECK_CONTEXT = MIN_SEGMENT
"""Samples before a window update's new samples that its signal checks take in too (0.27 s at
120 Hz; at most those a restart kept). A sensor that dies on an update's last samples, fewer than
the checks' shortest stretch, leaves the next update all dead, with nothing healthy to read it
against; the level check holds a quiet segment to the ``MIN_SEGMENT`` samples before it. Without
them such a death gives ok estimates on dead data (GD falling) for 5-9 m, against 0.1-1.4 m for
one earlier in an update (`tests/control/test_dead_update_end_s77.py`)."""
CHECK_LEAST = 125
"""Fewest samples a window update's signal checks read (the newest, at most those a restart
kept; 1.04 s at 120 Hz): the blocks their limits were calibrated on. With a small
``update_every`` the new samples and ``CHECK_CONTEXT`` alone leave the short level check little
margin (a clean 42-sample block of 10 new samples read 364 against its limit of 400)."""
STANDING_MPS = 0.05
"""A block whose every |speed| is below this, m/s, reads as a robot standing (5 cm in a 1 s
block: the ground gives next to no vertical acceleration). Where its accelerometer reads at
least as loud as driving at the emulator's lowest speed over its smoothest ground, the odometry
froze while the robot drove (`BCR`, "Frozen odometry")."""
STANDING_SETTLE_S = 2.0
"""A robot that stops rings on its suspension for a second or so (its first standing blocks
read as driving: up to 1.3 s after a 20 m/s^2 stop from 2 m/s over GD 300-600), s: a standing
block that reads as driving is a "sensor_fault" only once the odometry has read standing this
long before it; until then it gives no estimate ("out_of_domain")."""
PAPER_WINDOW = FeatureSpec(name="log_var", block_samples=1000)
"""The paper's observation: log of the variance of the last 1,000 samples at 120 Hz."""


@dataclass(frozen=True)
class BCRSettings:
    """Settings of a BCR.

    Attributes:
        feature: the observation (block feature for "changepoint"; the window for the others).
        method: one of METHODS (see the module docstring).
        update_every: new samples between estimates (None: a third of a block for
            "changepoint", DEFAULT_PHASES interleaved filters; 125 for the window methods:
            about one estimate a second at 120 Hz). For "changepoint", ceil(block /
            update_every) interleaved filters run (at most MAX_PHASES; see the module
            docstring); the block length is one filter.
        changepoint: settings of the change-point filter.
        tracker: settings of the window methods' filter.
        max_age_s: an estimate older than this (sample time since its newest information)
            turns "stale".
        max_silence_s: with the caller's clock (``update(..., now=)``), no sample for longer
            than this is a "sensor_fault" (a silent sensor or a broken link), s.
        interval_level: probability of the reported credible interval.
        interval_kind: "hdi" (the shortest interval: it reaches the emulator's GD bound where the
            posterior piles up there) or "central" (equal tails, which never holds a bound).
        plausibility_p: an observation whose upper-tail probability under the emulator is below
            this for every GD in the domain is "implausible"; also the level of the quiet-signal
            check (``quiet_blocks``) and of the frozen-odometry check (`BCR`). 0 switches them
            off.
        sensor: thresholds of the signal checks (stuck, quantised, clipped, dead, below the
            noise floor, a level jump; the static level of an axis that reports gravity).
        recent_change_m: the distance of ``Estimate.prob_change``, m.
        quiet_blocks: change-point method: the quiet-signal check's memory, blocks of a phase
            (~1 s each): an estimate is "implausible" where its phase's last ``quiet_blocks``
            blocks together read quieter than any GD explains (`BCR`, "The quiet-signal
            check"), with a probability under the emulator below ``plausibility_p``; 0
            switches the check off, and the frozen-odometry check (`BCR`), which reads its
            level scores.
        release_p: change-point method with the quiet-signal check on: after an "implausible"
            estimate, the estimates stay "implausible" while a phase's level scores of the
            blocks it read since then, summed as the check sums them, read a probability below
            this, until every phase has read such blocks, at most until every phase's memory
            (``quiet_blocks``) was read since then (a hysteresis: `BCR`, "The quiet-signal
            check"); 0 switches the hold off.
        quiet_scan: change-point method with the quiet-signal check on: the check also tests
            the sum of each phase's newest k level scores, for every k below its memory, at
            ``plausibility_p`` (a drop of the sensor's gain at an unknown block: a change-point
            of the level); False tests the whole memory's sum alone (the check before session
            69, which the blocks from before a drop dilute: a gain of 0.7 from the 6 m of GD
            300 to GD 500 was flagged 1.7-12.3 m into the fault (median 7.3), with the scan
            1.7-8.7 m (5.3); docs/closed-loop.md, "Guards").
    """

    feature: FeatureSpec = field(default_factory=FeatureSpec)
    method: str = "changepoint"
    update_every: int | None = None
    changepoint: ChangePointSettings = field(default_factory=ChangePointSettings)
    tracker: TrackerSettings = field(default_factory=TrackerSettings)
    max_age_s: float = 5.0
    max_silence_s: float = 0.5
    interval_level: float = 0.9
    interval_kind: str = "hdi"
    plausibility_p: float = 1e-6
    sensor: SensorLimits = field(default_factory=SensorLimits)
    recent_change_m: float = 5.0
    quiet_blocks: int = 16
    release_p: float = 0.05
    quiet_scan: bool = True

    def __post_init__(self) -> None:
        for name, cls in (
            ("feature", FeatureSpec),
            ("changepoint", ChangePointSettings),
            ("tracker", TrackerSettings),
            ("sensor", SensorLimits),
        ):
            require_instance(self, name, cls)
        require_reals(
            self,
            (
                "max_age_s",
                "max_silence_s",
                "interval_level",
                "plausibility_p",
                "recent_change_m",
                "release_p",
            ),
        )
        if not is_choice(self.method, METHODS):
            raise ControlError(f"method must be one of {METHODS}, got {self.method!r}")
        block = self.feature.name == "log_band_power"
        if (self.method == "changepoint") != block:
            raise ControlError(
                f"method {self.method!r} needs the "
                f"{'log_band_power' if self.method == 'changepoint' else 'log_var or var'} "
                f"feature, got {self.feature.name!r}"
            )
        every = self.samples_per_update
        if not (is_integer(every) and every >= 1):
            raise ControlError(f"update_every must be an integer >= 1, got {every}")
        if (
            block
            and not self.feature.block_samples / MAX_PHASES <= every <= self.feature.block_samples
        ):
            raise ControlError(
                f"the change-point method updates at most once per block and runs at most "
                f"{MAX_PHASES} interleaved filters: update_every must lie in "
                f"[block_samples / {MAX_PHASES}, block_samples] = "
                f"[{self.feature.block_samples / MAX_PHASES:g}, {self.feature.block_samples}], "
                f"got {every}"
            )
        if self.method == "window":
            _check_window_tracker(self.tracker)
        if not block and every > self.feature.block_samples:
            raise ControlError(
                f"update_every ({every}) must not exceed the window ({self.feature.block_samples})"
            )
        for name in ("max_age_s", "max_silence_s"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise ControlError(f"{name} must be finite and > 0, got {value}")
        held_s = every / self.feature.rate_hz
        if held_s > self.max_age_s:
            least = -(-self.feature.block_samples // MAX_PHASES) if block else 1
            warnings.warn(_hold_message(every, self.feature.rate_hz, self.max_age_s, least),
                          ControlWarning, stacklevel=user_stacklevel())  # fmt: skip
        if not 0 < self.interval_level < 1:
            raise ControlError(f"interval_level must lie in (0, 1), got {self.interval_level}")
        if not is_choice(self.interval_kind, INTERVAL_KINDS):
            raise ControlError(
                f"interval_kind must be one of {INTERVAL_KINDS}, got {self.interval_kind!r}"
            )
        if not 0 <= self.plausibility_p < 1:
            raise ControlError(f"plausibility_p must lie in [0, 1), got {self.plausibility_p}")
        if not 0 <= self.release_p < 1:
            raise ControlError(f"release_p must lie in [0, 1), got {self.release_p}")
        if not (np.isfinite(self.recent_change_m) and self.recent_change_m >= 0):
            raise ControlError(
                f"recent_change_m must be >= 0 and finite, m, got {self.recent_change_m}"
            )
        if not isinstance(self.quiet_scan, bool | np.bool_):
            raise ControlError(f"quiet_scan must be True or False, got {self.quiet_scan!r:.60}")
        object.__setattr__(self, "quiet_scan", bool(self.quiet_scan))
        if not (is_integer(self.quiet_blocks) and 0 <= self.quiet_blocks <= MAX_QUIET_BLOCKS):
            raise ControlError(
                f"quiet_blocks must be an integer in [0, {MAX_QUIET_BLOCKS}], got "
                f"{self.quiet_blocks!r}"
            )
        python_number(self, "quiet_blocks")
        python_number(self, "update_every")

    @property
    def samples_per_update(self) -> int:
        """New samples between estimates (``update_every`` or its default)."""
        if self.update_every is not None:
            return self.update_every
        block = self.feature.block_samples
        return -(-block // DEFAULT_PHASES) if self.method == "changepoint" else min(125, block)

    @property
    def phases(self) -> int:
        """Interleaved change-point filters: ceil(block_samples / update_every) (1 otherwise)."""
        if self.method != "changepoint":
            return 1
        return -(-self.feature.block_samples // self.samples_per_update)

    @property
    def rate_hz(self) -> float:
        """Accelerometer rate, Hz."""
        return self.feature.rate_hz


def _hold_message(every: int, rate_hz: float, max_age_s: float, least: int) -> str:
    """`BCRSettings`' warning of ``every`` samples between updates, longer than ``max_age_s``,
    with its remedies: the largest update_every held no longer than max_age_s where it is
    one the method allows (at least ``least``), and the max_age_s that the interval needs."""
    most = floor(max_age_s * rate_hz)  # (a float product may land either side of the count)
    while (most + 1) / rate_hz <= max_age_s:
        most += 1
    while most > 0 and most / rate_hz > max_age_s:
        most -= 1
    held_text, age_text = numbers_text(every / rate_hz, max_age_s)
    lower = f"lower update_every to at most {most} samples or " if most >= least else ""
    bound = "" if most >= least else f" (update_every is at least {least} here)"
    return (
        f"update_every ({every} samples, {held_text} s at {rate_hz:g} Hz) is longer than "
        f"max_age_s ({age_text} s): between two updates a controller holds an estimate older "
        "than max_age_s that never turns stale (the closed loop's Simplex keeps its speed); "
        f"{lower}raise max_age_s to at least {held_text} s{bound}"
    )


def _check_window_tracker(tracker: TrackerSettings) -> None:
    """ControlError for a tracker setting that method "window" would ignore: it starts every
    window from the prior (``mean_segment_m = 0``), so it has no memory to set."""
    default = TrackerSettings()
    if tracker.mean_segment_m not in (0.0, default.mean_segment_m):
        raise ControlError(
            f"tracker.mean_segment_m = {tracker.mean_segment_m:g} is ignored by method "
            "'window' (each window alone, mean_segment_m = 0); use method 'filter' or "
            "'tempered' for a filter with memory"
        )
    if tracker.drift_per_sqrt_m != default.drift_per_sqrt_m:
        raise ControlError(
            f"tracker.drift_per_sqrt_m = {tracker.drift_per_sqrt_m:g} is ignored by method "
            "'window' (each window alone); use method 'filter' or 'tempered' for a filter "
            "with memory"
        )


@dataclass
class _Phase:
    """One interleaved change-point filter and what the BCR remembers of its blocks."""

    filter: ChangePointFilter
    pos_block: float = np.nan  # position at the end of its newest block, m
    pending_m: float = 0.0  # distance of undone blocks, not yet propagated, m
    data_time: float = np.nan  # sample time of its newest information, s
    undo: tuple | None = None  # (filter state, data time, distance) before its newest block
    guard: bool = False  # skip its next block: it may hold the end of a fault
    levels: deque = field(default_factory=deque)  # level scores of its newest blocks (quiet)
    held_n: int = 0  # how many of the newest levels came since a hold began (`BCR._hold`)

    def reset(self) -> None:
        self.filter.reset()
        self.forget_stream()

    def forget_stream(self) -> None:
        """Forget its blocks' positions, times, undo and guard, and the quiet check's scores;
        keep the filter's GD state."""
        self.pos_block, self.pending_m, self.data_time = np.nan, 0.0, np.nan
        self.undo, self.guard = None, False
        self.levels.clear()
        self.held_n = 0


def _samples(name: str, values) -> np.ndarray:
    """``values`` as a 1-D float array; ControlError naming ``name`` for anything but real
    numbers in one dimension (bools and strings are not numbers; NaN and None are missing
    samples: sensor faults, not errors)."""
    if type(values) is np.ndarray and values.ndim == 1 and values.dtype == np.float64:
        return values.copy()  # (the usual case: what the last line gives, a copy of its own)
    if values is None:
        raise ControlError(f"{name} must be a 1-D sequence of numbers, got None")
    check_not_masked(values, name)
    try:
        a = np.atleast_1d(np.asarray(tensor_values(values)))
    except (TypeError, ValueError) as exc:  # a ragged list; a tensor on a GPU (torch says how)
        raise ControlError(f"{name} must be a 1-D sequence of numbers: {exc}") from None
    if a.ndim != 1:
        raise ControlError(f"{name} must be 1-D, got shape {a.shape}")
    if a.dtype.kind == "O":
        wrong = [v for v in a if not (v is None or is_real(v))]
        if wrong:
            raise ControlError(
                f"{name} must hold real numbers (None for a missing sample), got {wrong[0]!r:.60} "
                f"({type(wrong[0]).__name__})"
            )
        return np.array([np.nan if v is None else float(v) for v in a])
    if a.dtype.kind in "mM" and name == "t":  # numpy's or pandas' time stamps
        raise ControlError(
            f"{name} must hold real numbers, got dtype {a.dtype}: give the times as seconds as "
            "float64 (for datetime64 stamps, (t - np.datetime64(0, 's')) / np.timedelta64(1, "
            "'s'); for timedelta64, t / np.timedelta64(1, 's'))"
        )
    if a.dtype.kind not in "iuf":
        raise ControlError(f"{name} must hold real numbers, got dtype {a.dtype}")
    if name == "t" and a.dtype.kind == "f" and a.dtype.itemsize < 8:
        _check_stamp_resolution(a)
    return a.astype(float)


STAMP_RESOLUTION_S = 1e-3
"""The coarsest resolution of time stamps given in a float type narrower than float64 (s): at a
float32 stamp of 16,384 s its spacing is 2 ms, and rounded stamps step unevenly by a quarter of
a 120 Hz period; since the epoch (1.7e9 s) by 128 s, every sample then repeats a stamp."""


def _check_stamp_resolution(t: np.ndarray) -> None:
    """ControlError where float32 (or float16) stamps ``t`` are coarser than
    `STAMP_RESOLUTION_S` at their largest magnitude: every block would read as a timing fault
    (repeated or uneven stamps), not as the type it is."""
    finite = np.abs(t[np.isfinite(t)])
    if finite.size == 0:
        return
    top = finite.max()
    spacing = float(np.spacing(top))
    if spacing > STAMP_RESOLUTION_S:
        raise ControlError(
            f"t is {t.dtype} and reaches {float(top):.6g} s, where its stamps are "
            f"{spacing:.3g} s apart (coarser than {STAMP_RESOLUTION_S:g} s), so that blocks "
            "would read as timing faults: give the stamps as float64 seconds, converted where "
            "they are made (a header stamp's sec + 1e-9 * nanosec in float64; a float32 array "
            "has already rounded them)"
        )


def emulator_domain(emulator) -> tuple[tuple[float, float], tuple[float, float]]:
    """(speed range, GD range) of an emulator, native units."""
    dom = emulator.domain
    return tuple(map(float, dom[emulator.x_names[0]])), tuple(map(float, dom[emulator.t_names[0]]))


UNIT_HINT_GAIN = 3.0
"""An implausible block whose band powers read as an acceleration this many times (or more)
louder or quieter than the emulator's GD domain explains gets a clause naming that gain
(`BCR`'s reason; a message only)."""
ACCEL_UNIT_SLIPS = (
    (
        1.0 / 9.80665,
        "acceleration in g? accel must be m/s^2 (g x 9.80665); or the wrong axis "
        "(one that feels little of the ground)",
    ),
    (1e2, "acceleration in cm/s^2? accel must be m/s^2 (x 0.01)"),
    (1e3, "acceleration in mm/s^2? accel must be m/s^2 (x 0.001)"),
)
"""(gain, what it suggests): the unit slips an implausible block's reason names where its band
powers read as within a factor 2 of that gain (`BCR._gain_hint`)."""

GD_MIN_HI = 1.0
"""Smallest highest GD (1e-6 m^3) of a training set or an emulator's GD domain: 16 times
smoother than the middle of ISO 8608's class A. Every ISO road's Gd(n0) in m^3 lies below it
(class H's 0.13), so runs, or a domain, whose GDs all lie below it are GDs given in m^3, which
would train on roads a million times too smooth (`control.training`), or give estimates that
every Simplex band in 1e-6 m^3 reads as smooth ground (`check_gd_unit`)."""


def check_gd_unit(gd_range: tuple[float, float], name: str = "GD") -> None:
    """EmulatorMismatchError where the domain ``gd_range`` (lo, hi) of a parameter named GD
    (``name``, in any case: the name `control.training` and the shipped emulators give it)
    lies wholly below `GD_MIN_HI`: an emulator whose GD axis is in m^3, not 1e-6 m^3. Its
    estimates (~4e-4 on ground of GD 400) lie below any Simplex band in 1e-6 m^3 (the default
    250-350), which then commands its top speed on any ground. A parameter named otherwise (an
    emulator of your own roughness measure, e.g. "IRI" in m/km) is not checked: its unit is
    not GD's."""
    lo, hi = gd_range
    if str(name).casefold() == "gd" and hi < GD_MIN_HI:
        lo_text, hi_text = numbers_text(lo, hi)
        raise EmulatorMismatchError(
            f"the emulator's {name} domain [{lo_text}, {hi_text}] lies below {GD_MIN_HI:g}: "
            f"{name} is Gd(n0) in units of 1e-6 m^3 (ISO 8608's smoothest class, A, spans "
            f"0-32; the Simplex's band, the tracks and the estimates use that unit), so this "
            f"emulator was trained on GDs in m^3, and a Simplex band in 1e-6 m^3 would read "
            f"every estimate as smooth ground (its top speed); train it on {name} x 1e6 "
            f"(control.training.fit_band_emulator refuses GDs in m^3)"
        )


def _put_back(held: dict, saved: dict) -> None:
    """Make ``held`` (an object's ``__dict__``) equal to ``saved`` (a copy of it taken before):
    its keys set first, those added since removed after, so that no moment leaves one of
    ``saved``'s keys missing (`BCR._restore`: a clear() then update() leaves the object without
    a single attribute where an interrupt lands between them)."""
    held.update(saved)
    for key in held.keys() - saved.keys():
        del held[key]


class BCR:
    """Streaming GD estimator (see the module docstring).

    Args:
        model: for "changepoint", a `control.ObservationModel` (anything with ``gd``,
            ``speed_range``, ``loglik(y, v)`` and ``plausibility(y, v)``); for the window
            methods, a `gpmsa.Calibrator` (anything with ``log_likelihood_grid(x_obs, y_obs)``
            and ``emulator``). `BCR.from_emulator` builds the right one. When the model's
            emulator records its feature, the settings' feature must match it
            (`EmulatorMismatchError` otherwise).
        settings: `BCRSettings` (default: the change-point method); ``overrides`` replace fields.

    A BCR is a stream's state: feed it from one thread (it holds no lock; BCRs on several
    threads may share one `ObservationModel`, whose cache holds no lock either), and copy it with
    ``copy.copy`` (a BCR on the same model with a copy of the stream's state: it continues as
    this one would, and updating either leaves the other as it was) or ``copy.deepcopy`` (the
    model copied too). It pickles, and so do its estimates
    (their posteriors' lazily drawn samples are drawn then). Its estimates do not depend on
    how the samples are chunked across calls (but for their times: with ``now=``, the
    estimates that one call makes are stamped at its clock); a call returns the newest
    estimate, or the gravest fault among those it made. A call of ``update``, ``resume`` or
    ``reset`` that raises (a refused argument; part way: an error of the model's, a
    KeyboardInterrupt) leaves the BCR as it was before it: fed the same samples again, it
    continues as if the call never happened.
    """

    def __init__(self, model, settings: BCRSettings | None = None, **overrides) -> None:
        from control.compat import check_recorded_feature
        from control.observation_model import check_emulator_inputs

        settings = BCRSettings() if settings is None else settings
        check_instance(settings, "settings", BCRSettings)
        self.settings = s = replace_fields(settings, overrides)
        self.model = model
        check_recorded_feature(getattr(model, "emulator", None), s)
        if s.method == "changepoint":
            if not hasattr(model, "loglik"):
                raise ControlError(
                    f"method 'changepoint' needs an ObservationModel, got {type(model).__name__}"
                    " (BCR.from_emulator(emulator) builds the model an emulator needs)"
                )
            self.speed_range = tuple(model.speed_range)
            self.gd_range = (float(model.gd[0]), float(model.gd[-1]))
            self.gd_name = model.emulator.t_names[0]
            if s.quiet_blocks and not hasattr(model, "level_score"):
                raise ControlError(
                    f"the quiet-signal check (quiet_blocks = {s.quiet_blocks}) needs the "
                    f"model's level_score(y, v, direction), which {type(model).__name__} lacks "
                    "(control.ObservationModel has it); quiet_blocks=0 switches the check off"
                )
            self._phases = [_Phase(ChangePointFilter(model.gd, s.changepoint),
                                   levels=deque(maxlen=s.quiet_blocks))
                            for _ in range(s.phases)]  # fmt: skip
            dof = getattr(getattr(model, "scatter", None), "dof", np.inf)
            # the scores' sd under a multivariate t law (dof > 2) is sqrt(dof / (dof - 2))
            self._level_sd = float(np.sqrt(dof / (dof - 2.0))) if 2.0 < dof < np.inf else 1.0
        else:
            if not hasattr(model, "log_likelihood_grid"):
                raise ControlError(
                    f"method {s.method!r} needs a gpmsa.Calibrator, got {type(model).__name__}"
                    " (BCR.from_emulator(emulator) builds the model an emulator needs)"
                )
            check_emulator_inputs(model.emulator)  # (a window's x_obs is [[v]])
            self.speed_range, self.gd_range = emulator_domain(model.emulator)
            self.gd_name = model.emulator.t_names[0]
            tracker, n = s.tracker, 1
            if s.method == "filter":
                n = -(-s.feature.block_samples // s.samples_per_update)
            elif s.method == "window":
                tracker = replace(tracker, mean_segment_m=0.0)
            self.trackers = [GDTracker(self.gd_range, tracker) for _ in range(n)]
        check_gd_unit(self.gd_range, self.gd_name)
        self._reset()
        self._warm_up()

    def __repr__(self) -> str:
        """One line: the method, the feature, the update interval (samples and seconds), the
        estimates made since the start (or the last reset or resume) and the newest estimate's
        status. Reads attributes only: no computation, and never
        raises (an odd BCR shows "?")."""
        try:
            s = self.settings
            every = s.samples_per_update
            parts = [f"method={s.method}", f"feature={s.feature.name}",
                     f"every={every} samples ({every / s.feature.rate_hz:.3g} s)",
                     f"estimates={self._n_updates}", f"last={self.last.status}"]  # fmt: skip
        except Exception:  # a repr never raises
            parts = ["?"]
        return f"BCR({', '.join(parts)})"

    def __copy__(self) -> BCR:
        """``copy.copy``: a BCR on the same model (read-only, as BCRs sharing one) with its own
        copy of the stream's state (filters, trackers, buffers, the static span, the newest
        estimate): a shallow copy shared them, and updating it moved this one's filters."""
        return copy.deepcopy(self, {id(self.model): self.model, id(self.settings): self.settings})

    def __setstate__(self, state: dict) -> None:  # a restored BCR warms up as a new one
        # (one pickled before it had a note, the quiet-signal hold or the standing time)
        self.__dict__.update({"_start_note": "", "_held_by": None, "_standing_from": np.nan,
                              "_breaks": None, **state})  # fmt: skip
        if "_span" not in state:  # (pickled before the static-level check's long span)
            self._span = self._new_span()
        self._warm_up()

    def _warm_up(self) -> None:
        """Build the feature's cached tables now (the DPSS tapers import scipy.signal: 0.1-0.2 s
        once a process), so that the stream's first block does not pay for them inside the
        control loop."""
        if self.settings.feature.name == "log_band_power":
            with np.errstate(divide="ignore"):
                features_of_blocks(np.zeros((1, self.buffer)), self.settings.feature)

    @classmethod
    def from_emulator(cls, emulator, settings: BCRSettings | None = None, **overrides) -> BCR:
        """A BCR for ``emulator``: the settings default to its recorded feature
        (`control.bcr_settings_for`), and the likelihood model is built from it. ``overrides``
        replace `BCRSettings` fields (e.g. ``method="window"``) of ``settings`` or of that
        default."""
        import gpmsa
        from control.compat import bcr_settings_for, check_feature
        from control.observation_model import ObservationModel

        if settings is None:
            s = bcr_settings_for(emulator, **overrides)
        else:
            check_instance(settings, "settings", BCRSettings)
            s = replace_fields(settings, overrides)
        check_feature(emulator, s)
        if s.method == "changepoint":
            return cls(ObservationModel(emulator), s)
        return cls(gpmsa.Calibrator(emulator), s)

    @property
    def buffer(self) -> int:
        """Samples per block (change-point) or per window."""
        return self.settings.feature.block_samples

    @property
    def filter(self) -> ChangePointFilter:
        """The change-point filter of the newest estimate (the only one without phases).
        Method "changepoint" only (the window methods keep `GDTracker`s, ``trackers``)."""
        if self.settings.method != "changepoint":
            raise ControlError(f"filter needs method 'changepoint', not {self.settings.method!r}")
        return self._phases[self._phase].filter

    def reset(self) -> None:
        """Empty the buffers and forget the GD state (all or nothing, as `update`)."""
        self._all_or_nothing(self._reset)

    def _reset(self) -> None:
        """`reset`, also of a BCR being made (which has no state to restore yet)."""
        self._forget_stream()
        if self.settings.method == "changepoint":
            for phase in self._phases:
                phase.reset()
        else:
            for tracker in self.trackers:
                tracker.reset()
        self._start_note = ""
        self.last = Estimate(time=0.0, position=0.0, status="filling", reason="no samples yet")

    def resume(self, moved_m: float) -> None:
        """Start a new stream after downtime (a restart, or a BCR restored from a pickle),
        keeping the GD state: the buffers, clocks and faults emptied as ``reset`` empties them,
        and the GD state propagated over ``moved_m`` metres the robot may have moved while down
        (its prior of change points over that distance: 0, it stood still; the longer, the
        likelier a change; ``math.inf``, forget it, as ``reset``). As a gap in a stream, the
        downtime undoes each phase's newest block (it may hold the start of what stopped the
        robot). The first estimates then start from what the BCR knew instead of the prior
        (docs/robot.md, "A saved BCR")."""
        if not (is_real(moved_m) and moved_m >= 0):
            raise ControlError(f"moved_m must be a real number >= 0 (metres), got {moved_m!r}")
        if np.isinf(moved_m):
            self.reset()
            return
        self._all_or_nothing(self._resume, float(moved_m))

    def _resume(self, moved_m: float) -> None:
        """`resume` over a checked, finite ``moved_m``."""
        self._forget_stream()
        if self.settings.method == "changepoint":
            for phase in self._phases:
                moved = moved_m
                if phase.undo is not None:  # downtime is a gap: as after a fault, the block
                    state, _, ds_before = phase.undo  # before it may hold part of it
                    phase.filter.restore(state)
                    moved += ds_before
                phase.forget_stream()
                phase.filter.relocate(moved)
        else:
            for tracker in self.trackers:
                tracker.predict(moved_m)
        self._start_note = f"resumed ({moved_m:g} m moved while down); "
        reason = f"{self._start_note}no samples yet"
        self.last = Estimate(time=0.0, position=0.0, status="filling", reason=reason)

    def _forget_stream(self) -> None:
        """Empty the buffers, clocks and fault state (what ``reset`` and ``resume`` share)."""
        self._acc = np.empty(0)  # contiguous clean samples (block or window)
        self._spd = np.empty(0)
        self._t = np.empty(0)  # their times and positions (the timing and odometry check)
        self._pos = np.empty(0)
        self._fresh = 0  # samples in the window the tempered filter has not seen
        self._received = 0  # samples received since the last estimate
        self._breaks = None  # what broke the samples of the coming update (`StreamBreaks`)
        self._fault = ""  # the clock steps among them (before session 69: their whole reason)
        self._t_last = np.nan  # time and position of the newest finite sample
        self._t_prev = np.nan  # the newest finite time stamp, kept or dropped
        self._pos_last = np.nan
        self._clock_back = 0.0  # the sample clock's newest step back, s, while now= disagrees
        self._clock = np.nan  # the caller's clock (update's now=), newest value
        self._clock_start = np.nan  # its first value (silence before any sample)
        self._n_updates = 0
        self._data_time = np.nan  # newest information of the window methods (phases keep theirs)
        self._phase = 0  # the change-point phase of the newest update
        self._held_by: Estimate | None = None  # the implausible estimate that started a hold
        self._standing_from = np.nan  # first sample time of the newest standing blocks in a row
        self._tracked_at: list[float | None] = [None] * len(getattr(self, "trackers", ()))
        self._span = self._new_span()

    def _new_span(self) -> StaticSpan | None:
        """The static-level check's long span (`SensorLimits.static_span`), empty; None where
        the check or its span is off."""
        sensor = self.settings.sensor
        if sensor.static_mps2 is None or not sensor.static_span:
            return None
        return StaticSpan(sensor.static_span)

    def update(self, t, position, accel, speed, *, now: float | None = None) -> Estimate:
        """Take new samples; return the newest estimate (or why there is none), or the gravest
        fault (``FAULT_STATUSES``) that this call's samples gave, if any: a caller that feeds
        more than ``update_every`` samples at once still sees every fault.

        Args:
            t: (n,) sample times, s, increasing by 1 / rate_hz (a larger step means dropped
                samples, a smaller or negative one repeated or misordered samples). Seconds,
                not a ROS stamp's nanoseconds (every step would read as a gap), and float64
                for stamps since the epoch (float32 holds them only to ~2 min; float32 or
                float16 stamps coarser than `STAMP_RESOLUTION_S` where they reach are a
                ControlError).
            position: (n,) front-axle positions along the path driven, m: the distance
                travelled (as the replay's odometry path length), not a map coordinate (one
                that decreases while the speed is positive is broken odometry, a
                "sensor_fault").
            accel: (n,) measured vertical front-axle accelerations, m/s^2.
            speed: (n,) measured speeds, m/s.
            now: the caller's clock, s, on the time base of ``t`` (None: the newest sample's
                time). With it, the BCR knows time passes while no samples arrive: the estimate
                ages, and silence longer than ``max_silence_s`` is a "sensor_fault". A control
                loop should pass it: without it a silent sensor keeps the last estimate. Where
                ``t`` steps back by more than ``max_silence_s`` (a clock corrected, a bag
                replayed from its start, a driver restarted), the BCR's time base restarts with
                it (what it holds ages on the new clock); a ``now`` that did not step back is
                then ahead of every sample: a "sensor_fault" naming the step, until they agree.
            Non-finite values and speeds beyond ``MAX_SPEED_MPS`` are sensor faults, never
            errors.
        """
        if now is not None and not (is_real(now) and np.isfinite(now)):
            raise ControlError(f"now must be a finite time, s, got {now!r}")
        names = ("t", "position", "accel", "speed")
        arrays = [
            _samples(name, a) for name, a in zip(names, (t, position, accel, speed), strict=True)
        ]
        n = arrays[0].size
        for name, a in zip(names, arrays, strict=True):
            if a.size != n:
                raise ControlError(f"{name} must have t's length {n}, got {a.size}")
        # a grid posterior's far tails underflow to 0 as intended, whatever the caller's
        # np.seterr (one errstate here, ~1 us, not one per step inside)
        with np.errstate(under="ignore"):
            return self._all_or_nothing(self._update, arrays, now)

    def _update(self, arrays: list[np.ndarray], now: float | None) -> Estimate:
        """`update` of checked samples (``arrays``: t, position, accel, speed of one length)."""
        if now is not None:
            if not np.isfinite(self._clock):
                self._clock_start = float(now)
            self._clock = float(now)  # the latest: one wild value is forgotten at the next call
        n = arrays[0].size
        if n == 0:
            return self._check_silence(self._check_age(self.last))
        updates = self._n_updates
        t, position, accel, speed = arrays
        every = self.settings.samples_per_update
        start = 0
        fault = None  # the gravest fault found by this call's updates
        while start < n:
            stop = min(n, start + every - self._received)
            part = slice(start, stop)
            self._take(t[part], position[part], accel[part], speed[part])
            self._received += stop - start
            start = stop
            if self._received == every:
                self.last = self._estimate()
                fault = graver_fault(fault, self.last)
                self._received = 0
                self._n_updates += 1
        if self._n_updates == 0 and self._received:  # samples in, the first update to come
            reason = f"{self._start_note}{self._received} of the first update's {every} samples"
            t_now, pos_now = self._now()  # (the newest sample's, not the placeholder's 0)
            self.last = replace(self.last, time=t_now, position=pos_now, reason=reason)
        est = self._check_age(fault or self.last)
        return self._check_silence(est, fresh=self._n_updates > updates, pending=True)

    # --- internals -------------------------------------------------------------------------------

    def _all_or_nothing(self, call, *args):
        """``call(*args)``, or where it raises (the model's error, a KeyboardInterrupt) the BCR
        put back as it was before it (`_state`, `_restore`; a second interrupt inside the
        restore: restored again, whole, then that interrupt raised)."""
        saved = self._state()
        try:
            return call(*args)
        except BaseException:
            try:
                self._restore(saved)
            except BaseException:
                self._restore(saved)  # idempotent
                raise
            raise

    def _state(self) -> tuple:
        """The stream's state, for `_restore` (~2 us with three phases): the BCR's attributes,
        each phase's and its filter's, its quiet-check scores, the trackers' masses and the
        static span's ring. Every array among them is replaced by a step, never written in
        place (the span's ring is copied)."""
        span = None if self._span is None else self._span.state()
        if self.settings.method == "changepoint":
            inner = [(p.__dict__.copy(), tuple(p.levels), p.filter.__dict__.copy())
                     for p in self._phases]  # fmt: skip
        else:
            inner = [tracker.log_mass for tracker in self.trackers]
        return self.__dict__.copy(), list(self._tracked_at), span, inner

    def _restore(self, saved: tuple) -> None:
        """Back to a `_state` (a call that raised part way leaves the BCR as it was).
        Idempotent, and no step leaves an attribute missing: where an interrupt lands inside
        it, `update` and `resume` run it again, whole."""
        attributes, tracked_at, span, inner = saved
        _put_back(self.__dict__, attributes)
        self._tracked_at = list(tracked_at)
        if span is not None:
            self._span.restore(span)
        if self.settings.method == "changepoint":
            for phase, (fields, levels, filtered) in zip(self._phases, inner, strict=True):
                phase.__dict__.update(fields)
                phase.levels.clear()
                phase.levels.extend(levels)
                _put_back(phase.filter.__dict__, filtered)
        else:
            for tracker, log_mass in zip(self.trackers, inner, strict=True):
                tracker.log_mass = log_mass

    def _take(self, t, pos, acc, spd) -> None:
        """Append the samples of one update (or part of one); a dropped sample or a gap
        (`stream_breaks`) restarts the contiguous buffer, and what broke them waits for the
        update's estimate, counted with what broke its earlier parts (the same reason in any
        chunking)."""
        drop, restart, found = stream_breaks(t, pos, acc, spd, self._t_prev, self.settings.rate_hz)
        broken = np.flatnonzero(drop | restart)
        step = ""
        if broken.size == 0 and t.size:  # (the usual case) all finite and kept: the last is newest
            self._t_prev = self._t_last = float(t[-1])
            self._pos_last = float(pos[-1])
        else:  # a clock step first: it moves the newest kept sample's time too
            step = self._clock_step(t)
            self._take_stamps(t, pos, drop)
        if broken.size:  # every cause until a block reports them, whatever the chunking
            self._breaks = found if self._breaks is None else self._breaks + found
            if step not in self._fault:
                self._fault += step
            k = int(broken[-1])
            keep = slice(k + 1, None) if drop[k] else slice(k, None)
            self._acc, self._spd, self._t, self._pos = acc[keep], spd[keep], t[keep], pos[keep]
            self._fresh = self._acc.size
            if self._span is not None:  # a break: the long span starts again, as the buffer
                self._span.restart()
                self._span.push(self._acc)
            return
        if self._span is not None:
            self._span.push(acc)
        self._acc = np.concatenate([self._acc, acc])[-self.buffer :]
        self._spd = np.concatenate([self._spd, spd])[-self.buffer :]
        self._t = np.concatenate([self._t, t])[-self.buffer :]
        self._pos = np.concatenate([self._pos, pos])[-self.buffer :]
        self._fresh = min(self._fresh + acc.size, self.buffer)

    def _pending_fault(self) -> str:
        """The reason of what broke the samples of the coming update ("" for nothing)."""
        breaks = "" if self._breaks is None else self._breaks.reason(self.settings.rate_hz)
        return breaks + self._fault

    def _pop_fault(self) -> str:
        """`_pending_fault`, forgotten: the update reports it."""
        reason = self._pending_fault()
        self._breaks, self._fault = None, ""
        return reason

    def _clock_step(self, t: np.ndarray) -> str:
        """Where the stamps ``t`` step back from the stamp before them (kept or dropped) by
        more than max_silence_s (a clock corrected, a bag replayed from its start, a
        driver restarted), the time base restarts: the times of the newest kept sample, of the
        information held and of the newest estimate move back by the clock's steps (so that
        the information ages on the new clock, and the phases keep their order). Later steps
        forward of the same chunk count against them, so that one wild stamp among good ones
        moves nothing (one at a chunk's end is taken as a step: the information held reads
        older until the samples catch up, the cautious side). Returns the clause naming the
        steps ("" for none)."""
        stamps = t[np.isfinite(t)]
        steps = np.diff(stamps, prepend=self._t_prev)  # NaN before the first stamp: no step
        s = self.settings
        big = np.abs(steps) > s.max_silence_s
        back = float(np.sum(1.0 / s.rate_hz - steps[big]))  # vs. the next sample's place
        if not back > s.max_silence_s or not np.any(steps[big] < 0):
            return ""
        self._clock_back = back
        self._t_last -= back
        self._data_time -= back
        last = self.last
        self.last = replace(last, time=last.time - back, data_time=last.data_time - back)
        for phase in getattr(self, "_phases", ()):
            phase.data_time -= back
            if phase.undo is not None:
                state, data_time, ds = phase.undo
                phase.undo = (state, data_time - back, ds)
        return f" (the sample clock stepped back {back:.4g} s)"

    def _take_stamps(self, t, pos, drop) -> None:
        """Remember the newest time stamp, kept or dropped, and the newest kept sample's time
        and position, of samples some of which `stream_breaks` drops or restarts on."""
        stamped = np.flatnonzero(np.isfinite(t))
        if stamped.size:  # steps run from the previous stamp, kept or dropped, in any chunking
            self._t_prev = float(t[stamped[-1]])
        good = np.isfinite(t) & np.isfinite(pos) & ~drop
        if good.any():
            k = int(np.flatnonzero(good)[-1])
            self._t_last, self._pos_last = float(t[k]), float(pos[k])

    def _now(self) -> tuple[float, float]:
        """(time, position) now: the newest sample's, or the caller's clock when it is later."""
        if isfinite(self._t_last):  # (math's isfinite on these floats: no array round trip)
            t = max(self._t_last, self._clock) if isfinite(self._clock) else self._t_last
            return t, self._pos_last
        return float(self.last.time), float(self.last.position)

    def _check_silence(self, est: Estimate, fresh: bool = False, pending: bool = False) -> Estimate:
        """'sensor_fault' when the caller's clock is more than max_silence_s past the newest
        sample (or, before any sample, past the first call); a sensor fault that this call's
        samples gave (``fresh``: e.g. readings that arrived but were NaN, which leave no
        newest sample) is named before the silence, and so (``pending``) are the breaks of
        samples that wait for the coming update (fed in chunks smaller than an update)."""
        if not isfinite(self._clock):
            return est
        last = self._t_last if isfinite(self._t_last) else self._clock_start
        silence = self._clock - last
        if silence <= self.settings.max_silence_s:
            self._clock_back = 0.0  # the clocks agree (again)
            return est
        t_now, pos_now = self._now()
        most = self.settings.max_silence_s
        shown, most_text = f"{silence:.2f}", f"{most:g}"
        if not float(shown) > most:  # reads as the limit: numbers_text's digits
            shown, most_text = numbers_text(silence, most)
        limit = f"max_silence_s = {most_text}"
        reason = f"no samples for {shown} s ({limit})"
        if self._clock_back:  # samples come, on a clock that stepped back while now= did not
            reason = (
                f"the newest sample is {shown} s behind the caller's clock (now=; {limit}): "
                f"the sample clock stepped back {self._clock_back:.4g} s, now= did not (now= "
                "must run on the samples' clock)"
            )
        if fresh and est.status == "sensor_fault" and est.reason:
            reason = f"{est.reason}; {reason}"
        elif pending and (waiting := self._pending_fault()):
            reason = f"{waiting}; {reason}"
        return Estimate(t_now, pos_now, "sensor_fault", reason, data_time=est.data_time)

    def _block_distance(self, phase: _Phase) -> float:
        """Metres since the end of the last block ``phase`` saw (0 before any), with the
        distance of its undone blocks."""
        _, pos = self._now()
        ds = pos - phase.pos_block if isfinite(phase.pos_block) else 0.0
        phase.pos_block = pos
        ds = max(float(ds), 0.0) + phase.pending_m
        phase.pending_m = 0.0
        return ds

    def _estimate(self) -> Estimate:
        if self.settings.method == "changepoint":
            return self._estimate_changepoint()
        return self._estimate_window()

    def _no_estimate(self, status: str, reason: str, **kw) -> Estimate:
        t_now, pos_now = self._now()
        return Estimate(t_now, pos_now, status, reason, data_time=self._newest_data_time(), **kw)

    def _block_feature(self, block: np.ndarray) -> np.ndarray:
        """The feature vector (K,) of the newest block of clean samples."""
        return features_of_blocks(block[None, :], self.settings.feature)[0]

    def _signal_reason(
        self, accel: np.ndarray, timing: bool = True, slow: np.ndarray | None = None
    ) -> str:
        """The checks of the buffer's time stamps and odometry (`timing_fault`; with
        ``timing``), then the signal checks on ``accel`` (`signal_fault`; ``slow``: its samples
        below half their top speed, None for none): a whole block, or a window's new samples
        (`_window_signal_reason`)."""
        s = self.settings
        if timing:
            reason = timing_fault(self._t, self._pos, self._spd, s.rate_hz, s.sensor)
            if reason:
                return reason
        steady = slow is None
        return signal_fault(accel, s.sensor, steady=steady, slow=slow) or self._span_reason()

    def _span_reason(self) -> str:
        """The static-level check's long span (`static_span_fault`): "" while it is off or not
        yet full."""
        return "" if self._span is None else static_span_fault(self._span, self.settings.sensor)

    def _window_signal_reason(self) -> str:
        """The window methods' checks: the signal checks on the buffer's samples that came
        since the previous update and the ``CHECK_CONTEXT`` before them, at least the newest
        ``CHECK_LEAST`` (those a restart kept), as the window fills too, so that every sample
        of a window has passed them with the samples before it; the timing checks on a full
        window. Samples over which the speed changes by more than MAX_SPEED_CHANGE (starting,
        stopping) skip the level-jump check (their level changes with the speed), and their
        dead-stretch check passes over the stretches that take in a sample below
        MAX_SPEED_CHANGE of their top speed (a robot getting under way on flat ground reads an
        all but constant acceleration; a sensor that dies at speed is still caught)."""
        checked = max(self.settings.samples_per_update + CHECK_CONTEXT, CHECK_LEAST)
        spd = np.abs(self._spd[-checked:])
        slow = ~(spd >= MAX_SPEED_CHANGE * np.max(spd)) if spd.size else None  # (NaN: slow)
        return self._signal_reason(
            self._acc[-checked:],
            timing=self._acc.size >= self.buffer,
            slow=slow if slow is not None and slow.any() else None,
        )

    def _restart_window(self) -> None:
        """Empty the window (its samples failed a check)."""
        self._acc, self._spd, self._t, self._pos = (np.empty(0),) * 4
        self._fresh = 0

    # --- the change-point method -----------------------------------------------------------------

    def _skip_block(self, phase: _Phase, ds: float, status: str, reason: str, **kw) -> Estimate:
        """No information from this block; a fault or an implausible block also undoes every
        phase's newest block (the block before it, and those overlapping it: in the filter and
        in the quiet-signal check) and makes every phase skip its next block (they may hold
        part of it)."""
        undone = False
        for other in self._phases:
            if other.undo is not None:
                state, data_time, ds_before = other.undo
                other.filter.restore(state)
                other.data_time = data_time
                if other.levels:  # its level score, added with the update undone
                    other.levels.pop()
                    other.held_n = max(other.held_n - 1, 0)
                if other is phase:
                    ds += ds_before
                else:
                    other.pending_m += ds_before
                undone = True
            other.undo = None
            other.guard = True
        if undone:
            reason += "; the block before it is undone"
        phase.filter.predict(ds)
        return self._no_estimate(status, reason, **kw)

    def _newest_data_time(self) -> float:
        """Sample time of the newest information any estimate rests on, s (NaN before any)."""
        if self.settings.method != "changepoint":
            return self._data_time
        times = [p.data_time for p in self._phases if isfinite(p.data_time)]
        return max(times) if times else np.nan

    def _estimate_changepoint(self) -> Estimate:
        s = self.settings
        self._phase = self._n_updates % len(self._phases)
        phase = self._phases[self._phase]
        ds = self._block_distance(phase)
        acc, spd = self._acc, self._spd  # the newest block_samples contiguous samples
        standing_from, self._standing_from = self._standing_from, np.nan  # (set while standing)
        if self._breaks is not None or self._fault:
            reason = self._pop_fault()
            return self._skip_block(phase, ds, "sensor_fault", reason + "; block skipped")
        if acc.size < s.feature.block_samples:  # (re)starting, with phases
            phase.undo = None
            if np.isfinite(phase.data_time):
                phase.filter.predict(ds)
            else:  # its first block starts its run, as the first block without phases does
                phase.pos_block = np.nan
            return self._no_estimate(
                "filling", f"block holds {acc.size} of {s.feature.block_samples} samples"
            )
        tic = _time.perf_counter()
        v = float(spd.sum() / spd.size)  # np.mean's operations, without its wrapper
        lo, hi = self.speed_range
        why = ""
        if not within(v, lo, hi):
            shown = numbers_text(v, lo, hi, digits=3)[0]  # (a speed just past hi: not as hi)
            lo_text, hi_text = numbers_text(v, lo, hi)[1:]  # (:g, more where v reads as one)
            why = f"speed {shown} m/s outside the emulator's [{lo_text}, {hi_text}]"
        elif spd.min() < MAX_SPEED_CHANGE * spd.max():
            why = f"speed changed within the block ({np.min(spd):.3g}-{np.max(spd):.3g} m/s)"
        if why:  # the emulator knows constant speeds in its range only
            # odometry that disagrees with the speeds (a sign flip, a wild speed); a long span off
            # the static level (standing too: a healthy axis then reads the level itself)
            fault = timing_fault(self._t, self._pos, self._spd, s.rate_hz, s.sensor)
            fault = fault or self._span_reason()
            if fault:
                return self._skip_block(phase, ds, "sensor_fault", fault, speed=v)
            status, frozen = self._frozen_odometry(phase, acc, spd, standing_from)
            if status == "sensor_fault":  # standing by the odometry, driving by the accelerometer
                return self._skip_block(phase, ds, status, frozen, speed=v)
            phase.undo = None
            phase.filter.predict(ds)
            if status or not np.isfinite(self._newest_data_time()):
                return self._no_estimate("out_of_domain", frozen or why, speed=v)
            return self._held_reason(v, None) or self._posterior_estimate(
                "no new information: " + why, tic, v, None
            )
        bad_signal = self._signal_reason(acc)
        if bad_signal:
            return self._skip_block(phase, ds, "sensor_fault", bad_signal, speed=v)
        y = self._block_feature(acc)
        if not np.all(np.isfinite(y)):
            return self._skip_block(
                phase, ds, "sensor_fault", "a band of the block has no power", speed=v
            )
        d2, p = self.model.plausibility(y, v)
        if p < s.plausibility_p:
            why = (
                f"no GD in [{self.gd_range[0]:g}, {self.gd_range[1]:g}] explains the block at "
                f"{v:.3g} m/s: squared Mahalanobis distance {d2:.3g} (p = "
                f"{numbers_text(p, s.plausibility_p, digits=2)[0]} < "
                f"{numbers_text(p, s.plausibility_p)[1]})" + self._gain_hint(y, v)
            )
            return self._hold(self._skip_block(
                phase, ds, "implausible", why, speed=v, feature=y, plausibility_p=p))  # fmt: skip
        if phase.guard:
            phase.guard = False
            phase.undo = None
            phase.filter.predict(ds)
            return self._no_estimate(
                "filling", "first block after a fault: skipped (it may hold its end)", speed=v
            )
        score = self._level_score(y, v) if phase.levels.maxlen else None  # before the update
        phase.undo = (phase.filter.state(), phase.data_time, ds)
        phase.filter.update(self.model.loglik(y, v), ds)
        phase.data_time = float(self._t[-1])  # the block's newest sample, not the caller's clock
        if score is not None:
            quiet = self._quiet_reason(phase, score, v)
            if quiet:
                return self._hold(self._no_estimate("implausible", quiet[0], speed=v, feature=y,
                                                    plausibility_p=quiet[1]))  # fmt: skip
        return self._held_reason(v, y) or self._posterior_estimate("", tic, v, y)

    def _frozen_odometry(
        self, phase: _Phase, acc: np.ndarray, spd: np.ndarray, standing_from: float
    ) -> tuple[str, str]:
        """(status, why) for a block whose speeds read standing (every |speed| below
        ``STANDING_MPS``) but whose accelerometer reads no quieter than driving at the
        emulator's lowest speed over the smoothest ground (the block's level score there, in
        the quiet-signal check's sds, not below the normal quantile of ``plausibility_p``; with
        that check on): "sensor_fault" (the odometry froze while the robot drove) once the
        odometry has read standing for ``STANDING_SETTLE_S`` before the block, "out_of_domain"
        before (a stop's ringing); ("", "") otherwise. ``standing_from``: the first sample time
        of the standing blocks in a row before this one (NaN: none). A robot at rest reads its
        own noise (a block of N(0, 1) noise scores -6.6 sd at worst in 5,000 with emulator B,
        a drive at 0.5-2 m/s over GD 200-500 -3.8 at worst)."""
        s = self.settings
        if not np.max(np.abs(spd)) < STANDING_MPS:
            return "", ""
        self._standing_from = self._t[0] if np.isnan(standing_from) else standing_from
        if not (phase.levels.maxlen and s.plausibility_p > 0):
            return "", ""
        y = self._block_feature(acc)
        if not np.all(np.isfinite(y)):  # a sensor at rest without noise: no power in a band
            return "", ""
        lo, limit = self.speed_range[0], ndtri(s.plausibility_p)
        z = self._level_score(y, lo) / self._level_sd
        if not z >= limit:
            return "", ""
        z_text, limit_text = numbers_text(z, limit, digits=3)
        why = (
            f"the speeds read standing (below {STANDING_MPS:g} m/s) but the accelerometer reads "
            f"as driving at {lo:g} m/s or faster (level score {z_text} sd, a sensor at rest reads "
            f"below {limit_text})"
        )
        if self._t[0] - self._standing_from >= STANDING_SETTLE_S:
            return "sensor_fault", f"frozen odometry: {why}"
        return "out_of_domain", (
            f"{why}: a stop's ringing, or frozen odometry (a sensor_fault once it has read "
            f"standing for STANDING_SETTLE_S = {STANDING_SETTLE_S:g} s)"
        )

    def _gain_hint(self, y: np.ndarray, v: float) -> str:
        """For an implausible block: a clause naming the gain its band powers read as
        (`ObservationModel.band_gain`) where that reaches `UNIT_HINT_GAIN` either way, and
        the likely unit slip where it lies within a factor 2 of one (`ACCEL_UNIT_SLIPS`); ""
        otherwise, or for a model without ``band_gain``."""
        band_gain = getattr(self.model, "band_gain", None)
        if band_gain is None or self.settings.feature.name != "log_band_power":
            return ""
        gain = band_gain(y, v, slice(0, len(self.settings.feature.bands_hz) - 1))
        if not (np.isfinite(gain) and gain > 0) or 1 / UNIT_HINT_GAIN < gain < UNIT_HINT_GAIN:
            return ""
        side = "smoothest" if gain < 1 else "roughest"
        text = f"; its band powers read as the {side} ground's acceleration times {gain:.2g}"
        for factor, slip in ACCEL_UNIT_SLIPS:
            if 0.5 < gain / factor < 2.0:
                return f"{text}: if every block reads so, {slip}"
        return text

    def _level_score(self, y: np.ndarray, v: float) -> float:
        """The block's level score (`ObservationModel.level_score`) along the direction of a
        lower sensor gain; ControlError where the model gives no finite number."""
        feature = self.settings.feature
        bands = len(feature.bands_hz) - 1
        quantiles = slice(bands, bands + len(feature.quantiles))
        # d y / d log(gain): 2 for a log band power (a subclass's longer feature: its extra
        # channels' too), the value itself for a quantile
        direction = np.full(y.size, 2.0)
        direction[quantiles] = y[quantiles]
        score = self.model.level_score(y, v, direction)
        if not (is_real(score) and np.isfinite(score)):
            raise ControlError(
                f"the model's level_score(y, v, direction) must return a finite number, got "
                f"{score!r} (quiet_blocks=0 switches the quiet-signal check off)"
            )
        return float(score)

    def _quiet_reason(self, phase: _Phase, score: float, v: float) -> tuple[str, float] | None:
        """The quiet-signal check (module docstring): adds the newest block's level ``score``
        to ``phase``'s; (reason, probability) where their standardised sum says that the
        phase's last blocks read quieter than any GD explains, with a probability below
        ``plausibility_p`` (with ``quiet_scan``: the sum of its newest k blocks, for any k);
        None otherwise."""
        phase.levels.append(score)
        n = len(phase.levels)
        if self._held_by is not None:
            phase.held_n = min(phase.held_n + 1, n)
        z = sum(phase.levels) / (np.sqrt(n) * self._level_sd)
        p = float(ndtr(z))
        limit = self.settings.plausibility_p
        if p >= limit and self.settings.quiet_scan:
            # the newest k blocks, k = 1..n-1: a drop at an unknown block (~4 us for 16 blocks:
            # a Python loop beats numpy's calls at this size)
            total, lowest, newest = 0.0, z, n
            for k, level in enumerate(islice(reversed(phase.levels), n - 1), 1):
                total += level
                zk = total / (sqrt(k) * self._level_sd)
                if zk < lowest:
                    lowest, newest = zk, k
            if lowest < z:
                z, n = lowest, newest
                p = float(ndtr(z))
        if p >= limit:
            return None
        lo, hi = self.gd_range
        return (
            f"the last {n} block(s) read quieter than any GD in [{lo:g}, {hi:g}] explains at "
            f"{v:.3g} m/s: level score {z:.3g} sd (p = {numbers_text(p, limit, digits=2)[0]} < "
            f"{numbers_text(p, limit)[1]}); a sensor gain or noise below the emulator's, or ground "
            "smoother than it knows",
            p,
        )

    def _hold(self, est: Estimate) -> Estimate:
        """``est``, an "implausible" estimate; with the quiet-signal check and ``release_p`` on,
        it begins a hold (`_held_reason`) unless one is on."""
        s = self.settings
        on = s.release_p > 0 and s.plausibility_p > 0 and self._phases[0].levels.maxlen
        if on and self._held_by is None:
            self._held_by = est
            for phase in self._phases:
                phase.held_n = 0
        return est

    def _held_reason(self, v: float, y) -> Estimate | None:
        """During a hold (since an "implausible" estimate): an "implausible" estimate where a
        phase's level scores of the blocks it read since the hold began (at most its last
        ``quiet_blocks``), summed as `_quiet_reason` sums them, read a probability below
        ``release_p``, or where no phase has read a block since (the hold's own probability);
        else None, and the hold ends once every phase has read such blocks that read loud
        enough, or, whatever they read, its whole memory (``quiet_blocks``) since the flag: the
        check itself then rules. None without a hold."""
        held = self._held_by
        if held is None:
            return None
        if all(phase.held_n >= phase.levels.maxlen for phase in self._phases):
            self._held_by = None  # every phase's memory read since the flag
            return None
        since = f"held since the implausible estimate at {held.time:.2f} s"
        scores = [list(phase.levels)[-phase.held_n :] for phase in self._phases if phase.held_n]
        if not scores:  # (standing or accelerating since): nothing read to end it
            reason = f"{since}: no block read since then"
            return self._no_estimate("implausible", reason, speed=v, feature=y,
                                     plausibility_p=held.plausibility_p)  # fmt: skip
        z = min(sum(fresh) / (np.sqrt(len(fresh)) * self._level_sd) for fresh in scores)
        p = float(ndtr(z))
        if p >= self.settings.release_p:
            if len(scores) == len(self._phases):
                self._held_by = None
            return None
        release = self.settings.release_p
        reason = (
            f"{since}: the blocks read since then still read quiet on a phase (level score "
            f"{z:.3g} sd, p = {numbers_text(p, release, digits=2)[0]} < release_p "
            f"{numbers_text(p, release)[1]})"
        )
        return self._no_estimate("implausible", reason, speed=v, feature=y, plausibility_p=p)

    def _posterior_estimate(self, reason: str, tic: float, v: float, y) -> Estimate:
        t_now, pos_now = self._now()
        post, prob_change = self._pooled_posterior()
        name = self.gd_name
        edge, note = self._edge_note(post, self._phases[0].filter.prior)
        return Estimate(
            t_now,
            pos_now,
            "ok",
            "; ".join(filter(None, (reason, note))),
            gd_mean=post.mean(name),
            gd_sd=post.sd(name),
            interval=self._interval(post),
            posterior=post,
            latency_s=_time.perf_counter() - tic,
            speed=v,
            feature=y,
            prob_change=prob_change,
            data_time=self._newest_data_time(),
            domain_edge=edge,
        )

    def _interval(self, post: Posterior) -> tuple[float, float]:
        """The credible interval of GD of the settings' kind and level."""
        s = self.settings
        interval = post.hdi if s.interval_kind == "hdi" else post.interval
        return interval(self.gd_name, s.interval_level)

    def _edge_note(self, post: Posterior, prior_mass: np.ndarray) -> tuple[str, str]:
        """(`favoured_edge` of a grid posterior with the given prior masses on its nodes, its
        `_edge_sentence`)."""
        marginal = post.grids[self.gd_name]
        edge = favoured_edge(marginal.nodes, marginal.density * marginal.weights, prior_mass)
        return edge, self._edge_sentence(edge)

    def _edge_sentence(self, edge: str) -> str:
        """The estimate's note on a favoured edge of the GD domain ("" for none)."""
        if not edge:
            return ""
        lo, hi = self.gd_range
        at, side, bound = (hi, "rougher", f"<= {hi:g}") if edge == "upper" else (
            lo, "smoother", f">= {lo:g}")  # fmt: skip
        return (
            f"the data favour GD {at:g}, the emulator's {edge} edge, over every GD "
            f"{EDGE_MARGIN:.0%} or more inside its domain by a Bayes factor > "
            f"{EDGE_BAYES_FACTOR:g}: the road may be {side} than any the emulator knows (the "
            f"posterior assumes GD {bound})"
        )

    def _pooled_posterior(self) -> tuple[Posterior, float]:
        """(GD posterior, P(a change within recent_change_m)) of the phases pooled: a mixture in
        which the phase with the newest information weighs K, the next K - 1, and so on (in
        steady driving: the share of the newest block's worth of samples each has seen; while
        no information comes, the weights stay). One phase: its own posterior."""
        recent = self.settings.recent_change_m
        filters, weights = self._pooled_filters()
        if len(filters) == 1:
            return filters[0].posterior(self.gd_name), filters[0].prob_change_within(recent)
        change = np.array([f.prob_change_within(recent) for f in filters])
        return (
            _mixture_posterior(filters, weights, self.gd_name),
            float(weights @ change / weights.sum()),
        )

    def _pooled_filters(self) -> tuple[list[ChangePointFilter], np.ndarray]:
        """The phases' filters that hold data (all of them with one phase), newest information
        first, and their weights in the pooled estimate (`_pooled_posterior`)."""
        if len(self._phases) == 1:
            return [self._phases[0].filter], np.ones(1)
        used = sorted(  # data of this stream (a resumed phase's GD state joins with its block)
            (ph for ph in self._phases if ph.filter.has_data and isfinite(ph.data_time)),
            key=lambda ph: -ph.data_time,
        )
        weights = np.arange(len(self._phases), len(self._phases) - len(used), -1, dtype=float)
        return [ph.filter for ph in used], weights

    def mass_by_run(self, edges_m) -> np.ndarray:
        """The pooled GD posterior split by the distance since the last change
        (`ChangePointFilter.mass_by_run` of each phase, mixed as the estimate mixes them): row i
        holds the mass of the runs that began more than ``edges_m[i-1]`` and at most
        ``edges_m[i]`` metres ago (row 0 from 0, the last row beyond ``edges_m[-1]``), per node
        of ``model.gd``; the rows sum to the posterior mass. It shows how much of an estimate
        rests on a recent change. Method "changepoint" only, after an estimate."""
        if self.settings.method != "changepoint":
            raise ControlError(
                f"mass_by_run needs method 'changepoint', not {self.settings.method!r}"
            )
        filters, weights = self._pooled_filters()
        if not any(f.has_data for f in filters):
            raise ControlError("mass_by_run: no block has been used yet")
        parts = np.array([f.mass_by_run(edges_m) for f in filters])
        return np.einsum("f,fcg->cg", weights / weights.sum(), parts)

    # --- the window methods (the paper's, and the previous filters) -----------------------------

    def _estimate_window(self) -> Estimate:
        s = self.settings
        bad_signal = self._window_signal_reason()
        if self._breaks is not None or self._fault:
            reason = self._pop_fault()
            if bad_signal:  # the samples kept after the break fail too
                self._restart_window()
                reason += f" and {bad_signal}"
            return self._no_estimate("sensor_fault", reason + "; buffer restarted")
        if bad_signal:
            self._restart_window()
            return self._no_estimate("sensor_fault", bad_signal + "; buffer restarted")
        if self._acc.size < self.buffer:
            return self._no_estimate(
                "filling", f"buffer holds {self._acc.size} of {self.buffer} samples"
            )
        tic = _time.perf_counter()
        v = float(np.mean(self._spd))
        lo, hi = self.speed_range
        unit = float(self.model.emulator.standardizer.x_to_unit([[v]])[0, 0])
        if not 0.0 <= unit <= 1.0:  # the emulator's own rule (snaps rounding at the ends)
            shown = numbers_text(v, lo, hi, digits=3)[0]  # (a speed just past hi: not as hi)
            lo_text, hi_text = numbers_text(v, lo, hi)[1:]  # (:g, more where v reads as one)
            why = (
                f"window speed {shown} m/s outside the emulator's range [{lo_text}, {hi_text}] m/s"
            )
            if self.last.ok:
                note = self._edge_sentence(self.last.domain_edge)
                reason = "; ".join(filter(None, ("no new information: " + why, note)))
                return replace(self.last, time=self._now()[0], position=self._now()[1],
                               reason=reason)  # fmt: skip
            return self._no_estimate("out_of_domain", why, speed=v)
        y = float(feature_of_variance(np.var(self._acc), s.feature.name))  # clean samples
        if not np.isfinite(y):
            return self._no_estimate(
                "sensor_fault", "window feature undefined (zero variance?)", speed=v
            )
        why, p = self._window_implausible(v, y)
        if why:
            return self._no_estimate(
                "implausible", why, speed=v, feature=np.array([y]), plausibility_p=p
            )
        try:
            grid, loglik = self.model.log_likelihood_grid([[v]], [[y]])
        except ValueError as exc:  # the gpmsa errors are ValueError subclasses
            return self._no_estimate("calibration_failed", str(exc), speed=v)
        chain = self._n_updates % len(self.trackers)
        tracker, last_pos = self.trackers[chain], self._tracked_at[chain]
        t_now, pos_now = self._now()
        tracker.predict(0.0 if last_pos is None else max(pos_now - last_pos, 0.0))
        power = self._fresh / self.buffer if s.method == "tempered" else 1.0
        tracker.update(np.ravel(grid), np.ravel(loglik), power=power)
        self._fresh = 0
        self._tracked_at[chain] = pos_now
        self._data_time = float(self._t[-1])  # the window's newest sample, not the caller's clock
        post = tracker.posterior(self.gd_name)
        name = self.gd_name
        edge, note = self._edge_note(post, np.exp(tracker.log_prior))
        return Estimate(
            t_now,
            pos_now,
            "ok",
            note,
            gd_mean=post.mean(name),
            gd_sd=post.sd(name),
            interval=self._interval(post),
            posterior=post,
            latency_s=_time.perf_counter() - tic,
            speed=v,
            feature=np.array([y]),
            data_time=self._data_time,
            domain_edge=edge,
        )

    def _window_implausible(self, v: float, y: float) -> tuple[str, float]:
        """(why no GD in the domain explains the window's y, or ""; the check's p) by a scalar
        predictive check."""
        emulator = self.model.emulator
        if not hasattr(emulator, "predict"):
            return "", np.nan
        gd = np.linspace(*self.gd_range, 65)
        mean, var = emulator.predict(np.full(gd.size, v), gd)
        z2 = float(np.min((y - mean[:, 0]) ** 2 / var[:, 0]))
        from scipy.stats import chi2

        p = float(chi2.sf(z2, 1))
        if p >= self.settings.plausibility_p:
            return "", p
        limit = self.settings.plausibility_p
        return (
            f"no GD in [{self.gd_range[0]:g}, {self.gd_range[1]:g}] explains the window at "
            f"{v:.3g} m/s: y is {np.sqrt(z2):.3g} predictive sds from the nearest "
            f"(p = {numbers_text(p, limit, digits=2)[0]} < {numbers_text(p, limit)[1]})"
        ), p

    def _check_age(self, est: Estimate) -> Estimate:
        """Replace an estimate whose newest information is older than max_age_s by 'stale'."""
        t_now, pos_now = self._now()
        age = t_now - est.data_time
        if est.ok and age > self.settings.max_age_s:
            limit = self.settings.max_age_s
            shown, limit_text = f"{age:.2f}", f"{limit:g}"
            if not float(shown) > limit:  # reads as the limit: numbers_text's digits
                shown, limit_text = numbers_text(age, limit)
            return Estimate(
                t_now,
                pos_now,
                "stale",
                f"newest information is {shown} s old (max_age_s = {limit_text})",
                data_time=est.data_time,
            )
        return est
