"""Replay a robot recording through the BCR and the Simplex: estimates as a table, CSV and bag.

The pipeline (`replay_bag`):

1. read the IMU and odometry topics (`control.robot.bags.read_recording`);
2. the IMU's acceleration along ``imu_axis`` times ``imu_sign``, on the time base chosen
   (header stamps, or receive times); its stamps checked (`condition.check_stream`), put in
   stamp order where delivered late (header stamps; `clock.stamp_order`) and re-stamped on
   their own fitted clock where they jitter by less than 1/6 period (`clock.restamp`: a dropped
   message, a duplicate or a clock step stays one); brought to the emulator's rate
   (`condition.to_rate`: as recorded when the rates agree, else resampled); optionally
   high-passed (``gravity="highpass"``; by default gravity's static part is kept: the BCR
   removes each block's mean before its feature, so a constant offset leaves the estimate
   alone, but without a noise sd its sensor checks exempt flights only near -9.81 m/s^2, where
   a gravity-free signal puts them: a noise-free signal with +9.81 in it has its flights
   flagged as dead or quantised, docs/robot.md); with ``static_mps2`` a block whose mean
   before the high-pass is off that static level is a scale fault (`ReplaySettings`);
   on header stamps, IMU messages whose header clock is not the odometry's (against their
   receive times, `clock.header_skew`) are fed as faults, or the replay refused where all are;
3. the odometry, in stamp order where delivered late (header stamps; however late, where a
   stamp fills the gap it left, `clock.into_gaps`); its position along the
   path (``position="path"``: the length of the pose trajectory from the odometry frame's
   origin, `condition.path_length`; ``"speed"``: the integral of the speed) and speed (the
   planar norm of ``twist.twist.linear``), interpolated linearly at the IMU's sample times;
   IMU samples before the first or after the last odometry message are left out, those inside
   an odometry gap get NaN (the BCR reports a sensor fault);
4. the BCR fed in time order, one update's worth of samples (one block) at a time with the
   newest sample's time as its clock (``now=``), the call `control.run_closed_loop` makes, and
   the Simplex's command for each estimate.

Faults in the recording are reported, never raised: repeated or backwards stamps and gaps
(those re-stamping keeps: not jitter) reach the BCR, which gives ``sensor_fault`` with the
reason for the blocks they touch (status and reason columns of the CSV), and the per-topic
`StreamReport` counts them. A missing topic, a topic of another type, no messages, an IMU
slower than the emulator's rate or an IMU stamped on another clock than the odometry throughout
raise `BagError` naming the topic.
"""

from __future__ import annotations

import csv
import dataclasses
import os
import shutil
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import gpmsa
from control.bcr import BCR, BCRSettings
from control.compat import (
    bcr_settings_for,
    check_likelihood,
    check_recorded_feature,
    check_recorded_vehicle,
    check_simplex,
    recorded_vehicle_mismatch,
)
from control.errors import BagError, ControlError, ControlWarning, user_stacklevel
from control.estimate import Estimate, edge_counts, run_text
from control.robot import clock, condition
from control.robot import messages as msgs
from control.robot.bags import (
    STORAGES,
    ImuMessages,
    Recording,
    check_bag_path,
    merge_in_time,
    open_bag_writer,
    read_recording,
    recording_path,
    source_of,
)
from control.sensor_checks import MAX_SPEED_MPS, SensorLimits, flight_reading
from control.shipped import shipped_emulator
from control.simplex import Simplex
from control.validation import (
    check_flags,
    check_instance,
    check_lookup,
    is_choice,
    path_argument,
    replace_fields,
    require_instance,
    require_reals,
)
from gpmsa._progress import progress_bar
from gpmsa.errors import numbers_text
from gpmsa.io.atomic import atomic_write
from gpmsa.model.data import repr_name
from roadgen.checks import home_path

TIME_BASES = ("header", "log")
POSITIONS = ("path", "speed")
GRAVITY = ("keep", "highpass")
SHIPPED = ("A", "B")
CSV_COLUMNS = (
    "stamp_ns", "time_s", "position_m", "speed_mps", "status", "reason", "domain_edge",
    "gd_mean", "gd_sd", "gd_lo", "gd_hi", "prob_gd_above_max", "prob_change", "command_mps",
    "mode",
)  # fmt: skip
CSV_HEADER = ",".join(CSV_COLUMNS).encode()
"""The first line of a CSV of estimates (`ReplayResult.to_csv`), without its line end."""
OLDER_CSV_HEADERS = (
    CSV_HEADER.replace(b"domain_edge,", b""),  # before the domain_edge column (07aa72a)
)
"""The first lines of the CSVs of estimates that earlier versions wrote (`check_csv_target`
replaces those too)."""


MIN_HIGHPASS_HZ = 1e-4
"""Lowest ``ReplaySettings.highpass_hz``: a period of ~3 h; far lower cut-offs make the
Butterworth filter's initial conditions a singular system (1e-9 Hz at 120 Hz did)."""


@dataclass(frozen=True)
class ReplaySettings:
    """What to read from a recording and how (see the module docstring).

    Attributes:
        imu_topic: topic of ``sensor_msgs/msg/Imu`` messages.
        odom_topic: topic of ``nav_msgs/msg/Odometry`` messages.
        imu_axis: "x", "y" or "z": the IMU axis that points up (along the front axle's
            vertical) when the robot stands level.
        imu_sign: +1 or -1 (an int or a float; not a bool): -1 when that axis points down.
        time_base: "header" (the messages' header stamps; the receive times of both topics
            when every header stamp of either is zero) or "log" (the receive times the
            recorder wrote).
        position: "path" (length of the odometry's pose trajectory) or "speed" (integral of
            the odometry's speed).
        gravity: "keep" (the BCR demeans each block) or "highpass" (a zero-phase 2nd-order
            Butterworth high-pass at ``highpass_hz`` first: for a signal with gravity in it and
            an emulator without noise, whose sensor checks expect flights at -9.81 m/s^2).
        highpass_hz: cut-off of the high-pass, Hz (at least MIN_HIGHPASS_HZ).
        rate_tolerance: an IMU whose nominal rate is within this relative difference of the
            emulator's is used as recorded; a faster one is resampled.
        resample: how a faster IMU is resampled: "sample" (band-limited interpolation: samples
            at the emulator's rate, the simulator's sensor model) or "lowpass" (an
            anti-aliasing low-pass at the emulator's Nyquist frequency first);
            `control.robot.condition`.
        max_odometry_gap_s: IMU samples inside a longer odometry gap get no position or speed
            (a sensor fault), s.
        reorder_periods: IMU messages whose stamps step back by at most this many nominal
            periods are put in stamp order (received late, stamped right); a longer step back
            is a clock step and stays (a sensor fault). Odometry messages likewise, by their
            own periods, and one later still where its stamp fills the gap it left
            (`clock.into_gaps`); others are left out (a clock step back, a stale stamp). 0: the
            order received. Only on header stamps (receive times are in order).
        restamp: put the IMU's stamps on their own fitted regular clock where they jitter
            about one by less than 1/6 period (`clock.restamp`): jitter goes, a dropped
            message, a duplicate or a clock step stays a sensor fault. Exact stamps are kept
            bit for bit.
        static_mps2: the mean the up axis reads at rest, m/s^2, after ``imu_sign``: +9.80665
            for an IMU that reports gravity (a sensor_msgs/Imu's specific force, REP-145);
            None (default): no static-level check. With it, a block whose raw mean lies
            outside ``static_mps2 * (1 +- bcr.sensor.static_tolerance)``, or whose newest
            ``bcr.sensor.static_span`` contiguous samples (1,000) have a mean outside
            ``static_mps2 * (1 +- static_span_tolerance)`` (7%: a gain of 0.9), is a scale (or
            tilt) fault, ``sensor_fault`` (`control.SensorLimits.static_mps2`). With ``gravity=
            "keep"`` the BCR checks it (its ``sensor.static_mps2`` set to this); with
            ``"highpass"`` the conditioning checks each update's block and span of the signal
            before the filter (`condition.static_level_marks`) and marks a failing update's
            newest sample non-finite, which the BCR reports as a sensor fault; the estimate's
            reason names the level. An IMU that removes gravity itself cannot be checked so.
        max_clock_skew_s: on header stamps, IMU messages whose header clock runs further
            than this from the odometry's, s, against their receive times
            (`clock.header_skew`: an IMU stamped in GPS time, a driver's clock step) would be
            paired with the odometry of another time: they become sensor faults (non-finite
            accel), with a note and a `ControlWarning`; where all of them do, the replay is
            refused (`BagError`: replay on receive times, ``time_base="log"``). ``math.inf``:
            no check.
        estimate_topic: the output bag's topic of the estimates.
        storage: the output bag's storage, "mcap" or "sqlite3".
    """

    imu_topic: str = "/imu/data"
    odom_topic: str = "/odometry/filtered"
    imu_axis: str = "z"
    imu_sign: float = 1.0
    time_base: str = "header"
    position: str = "path"
    gravity: str = "keep"
    highpass_hz: float = 0.5
    rate_tolerance: float = 0.02
    resample: str = "sample"
    max_odometry_gap_s: float = 0.25
    reorder_periods: float = clock.REORDER_PERIODS
    restamp: bool = True
    static_mps2: float | None = None
    max_clock_skew_s: float = 1.0
    estimate_topic: str = "/bcr/estimate"
    storage: str = "mcap"

    def __post_init__(self) -> None:
        for name in ("imu_topic", "odom_topic", "estimate_topic", "imu_axis"):
            require_instance(self, name, str)
        require_reals(self, ("imu_sign", "highpass_hz", "rate_tolerance", "max_odometry_gap_s",
                             "reorder_periods", "static_mps2", "max_clock_skew_s"),
                      optional=("static_mps2",))  # fmt: skip
        if self.static_mps2 is not None:  # (SensorLimits' rule, naming this field)
            SensorLimits(static_mps2=self.static_mps2)
        if not isinstance(self.restamp, bool):
            raise ControlError(f"restamp must be True or False, got {self.restamp!r}")
        if not is_choice(self.imu_axis, ("x", "y", "z")):
            raise ControlError(f"imu_axis must be 'x', 'y' or 'z', got {self.imu_axis!r}")
        if self.imu_sign not in (1, -1):
            raise ControlError(f"imu_sign must be +1 or -1, got {self.imu_sign!r}")
        for name, allowed in (
            ("time_base", TIME_BASES), ("position", POSITIONS), ("gravity", GRAVITY),
            ("storage", STORAGES), ("resample", condition.METHODS),
        ):  # fmt: skip
            if not is_choice(getattr(self, name), allowed):
                raise ControlError(f"{name} must be one of {allowed}, got {getattr(self, name)!r}")
        if not (np.isfinite(self.highpass_hz) and self.highpass_hz >= MIN_HIGHPASS_HZ):
            raise ControlError(
                f"highpass_hz must be >= {MIN_HIGHPASS_HZ:g} Hz (a period of hours: below it the "
                f"filter removes nothing and its coefficients turn singular), got "
                f"{self.highpass_hz}"
            )
        if not 0 <= self.rate_tolerance < 0.5:
            raise ControlError(f"rate_tolerance must lie in [0, 0.5), got {self.rate_tolerance}")
        if not (np.isfinite(self.reorder_periods) and self.reorder_periods >= 0):
            raise ControlError(
                f"reorder_periods must be >= 0 and finite (periods), got {self.reorder_periods}"
            )
        if not self.max_clock_skew_s > 0:  # NaN too; inf: no check
            raise ControlError(f"max_clock_skew_s must be > 0 (s), got {self.max_clock_skew_s}")
        if not (np.isfinite(self.max_odometry_gap_s) and self.max_odometry_gap_s > 0):
            raise ControlError(
                f"max_odometry_gap_s must be > 0 and finite, s, got {self.max_odometry_gap_s}"
            )
        for name, option in (("imu_topic", " / --imu-topic"), ("odom_topic", " / --odom-topic"),
                             ("estimate_topic", "")):  # fmt: skip
            topic = getattr(self, name)
            if not topic.startswith("/"):  # a bag records absolute names (ros2 resolves them)
                hint = f": give {'/' + topic!r}" if topic[:1].isalpha() or topic[:1] == "_" else ""
                raise ControlError(
                    f"{name}{option} must start with '/' (a bag records a topic by its absolute "
                    f"name), got {topic!r}{hint}"
                )


@dataclass(frozen=True, eq=False)
class ReplayResult:
    """The estimates of a replay and how they were made.

    Per estimate (length k; one per BCR update, i.e. per block): ``stamp_ns`` (int, bag time of
    the newest sample), ``time`` (s since the first IMU message's stamp), ``position`` (m along
    the path), ``speed`` (m/s, the odometry's at that sample), ``status``, ``reason``,
    ``domain_edge`` (`Estimate.domain_edge`: "upper", "lower" or ""), ``gd_mean``,
    ``gd_sd``, ``gd_lo``, ``gd_hi`` (the credible interval at the BCR's ``interval_level``),
    ``prob_above`` (P(GD > the Simplex's GD_max)), ``prob_change``, ``command`` (m/s), ``mode``;
    ``estimates``: the `Estimate` objects (with their posteriors).
    Per sample fed to the BCR (length n): ``sample_time`` (s, as ``time``), ``sample_position``,
    ``sample_speed``, ``sample_accel`` (m/s^2).
    ``imu``, ``odometry``: `StreamReport` of each topic (the stamps as recorded; the IMU's note
    says what re-stamping and ordering did); ``restamping``: what `clock.restamp` did to
    the IMU's stamps; ``resampling``: what was done to the IMU's rate; ``notes``: what else
    was left out. ``read_s``, ``condition_s``, ``bcr_s``: wall-clock times of the three
    stages, s; ``t0_ns``: stamp of time 0; ``settings``, ``bcr``,
    ``simplex``: what ran; ``source``: the recording read; ``gd_unit``: the emulator's unit
    of GD ("1e-6 m^3" for the shipped ones; "" where it records none).
    """

    stamp_ns: np.ndarray
    time: np.ndarray
    position: np.ndarray
    speed: np.ndarray
    status: np.ndarray
    reason: np.ndarray
    domain_edge: np.ndarray
    gd_mean: np.ndarray
    gd_sd: np.ndarray
    gd_lo: np.ndarray
    gd_hi: np.ndarray
    prob_above: np.ndarray
    prob_change: np.ndarray
    command: np.ndarray
    mode: np.ndarray
    estimates: tuple[Estimate, ...]
    sample_time: np.ndarray
    sample_position: np.ndarray
    sample_speed: np.ndarray
    sample_accel: np.ndarray
    imu: condition.StreamReport
    odometry: condition.StreamReport
    resampling: condition.Resampling
    notes: tuple[str, ...]
    read_s: float
    condition_s: float
    bcr_s: float
    t0_ns: int
    settings: ReplaySettings
    bcr: BCRSettings
    simplex: Simplex
    source: str = ""
    restamping: clock.Restamping = clock.Restamping(False)
    gd_unit: str = ""

    def __repr__(self) -> str:
        """One line: the estimates, the span replayed, the statuses, the IMU samples fed to the
        BCR (`run_text`) and the recording's file name; not the arrays nor the estimates (a
        dataclass's repr printed each with its posterior: 90,000 characters for 50 m)."""
        text = run_text(self.status, self.sample_time, self.sample_position, "IMU")
        name = Path(str(self.source)).name if self.source else ""
        return f"ReplayResult({text}" + (f" from {name[:60]!r})" if name else ")")

    @property
    def duration_s(self) -> float:
        """Span of the samples fed to the BCR, s."""
        return float(self.sample_time[-1] - self.sample_time[0]) if self.sample_time.size else 0.0

    @property
    def wall_s(self) -> float:
        """Wall-clock time of reading, conditioning and estimating, s."""
        return self.read_s + self.condition_s + self.bcr_s

    @property
    def real_time_factor(self) -> float:
        """Recorded seconds replayed per wall-clock second."""
        return self.duration_s / self.wall_s if self.wall_s > 0 else np.nan

    def status_counts(self) -> dict[str, int]:
        """Number of estimates of each status."""
        names, counts = np.unique(self.status, return_counts=True)
        return {str(k): int(c) for k, c in zip(names, counts, strict=True)}

    def rows(self) -> list[dict]:
        """One dict per estimate, keyed by CSV_COLUMNS."""
        cols = (
            self.stamp_ns, self.time, self.position, self.speed, self.status, self.reason,
            self.domain_edge, self.gd_mean, self.gd_sd, self.gd_lo, self.gd_hi, self.prob_above,
            self.prob_change, self.command, self.mode,
        )  # fmt: skip
        return [dict(zip(CSV_COLUMNS, vals, strict=True)) for vals in zip(*cols, strict=True)]

    def to_csv(self, path: str | os.PathLike) -> Path:
        """Write the estimates as CSV (columns CSV_COLUMNS; floats in full precision, "nan"
        where there is no number). An existing file at ``path`` is replaced only where it is
        empty or a CSV of estimates (`check_csv_target`): `ControlError` for any other."""
        path = path_argument(path, "path")
        check_csv_target(path, "path")
        with atomic_write(path, text=True, error=ControlError) as f:
            writer = csv.writer(f)
            writer.writerow(CSV_COLUMNS)
            for row in self.rows():
                writer.writerow(
                    [repr(float(v)) if isinstance(v, float | np.floating) else v
                     for v in row.values()]
                )  # fmt: skip
        return path

    def write_bag(self, path: str | os.PathLike, storage: str | None = None) -> Path:
        """Write the estimates as a ROS 2 bag (topic ``settings.estimate_topic``, type
        ``terrain_gpmsa_msgs/msg/GDEstimate``, stamped with ``stamp_ns``) at ``path``, a new
        folder (`control.robot.bags.open_bag_writer`); returns its path. ``storage``: "mcap" or
        "sqlite3" (None: ``settings.storage``)."""
        storage = storage or self.settings.storage
        self._check_header_stamps()
        store = msgs.typestore()
        level, gd_max = self.bcr.interval_level, self.simplex.gd_max
        datas = [estimate_message(store, row, level, gd_max) for row in self.rows()]
        with open_bag_writer(path, storage) as writer:
            text, rihs01 = msgs.definition(store, msgs.GD_ESTIMATE_TYPE)
            conn = writer.add_connection(
                self.settings.estimate_topic, msgs.GD_ESTIMATE_TYPE, msgdef=text, rihs01=rihs01
            )
            for c, stamp, data in merge_in_time([(conn, self.stamp_ns, datas)]):
                writer.write(c, stamp, data)
        return home_path(path)

    def _check_header_stamps(self) -> None:
        """`ControlError` where an estimate's stamp lies outside a ROS 2 header stamp's range
        (int32 s: 1970 to January 2038), as receive times or a ROS 1 bag's stamps may."""
        bad = (self.stamp_ns < 0) | (self.stamp_ns > msgs.MAX_STAMP_NS)
        if bad.any():
            first = int(self.stamp_ns[bad][0])
            raise ControlError(
                f"an estimate's stamp is {first} ns ({first / 1e9:.6g} s since 1970), outside a "
                f"ROS 2 header stamp's [0, {msgs.MAX_STAMP_NS}] ns (int32 s, to January 2038): "
                "the estimates cannot be written as a ROS 2 bag; keep the CSV (replay_bag's csv=, "
                "ReplayResult.to_csv), which holds any stamp, or replay on the other time base "
                "(time_base, --time-base) where its times fit"
            )

    def _count_line(self) -> str:
        """How many estimates of each status, or why there is none."""
        if self.status.size:
            counts = ", ".join(f"{k} {v}" for k, v in sorted(self.status_counts().items()))
            n = self.status.size
            return f"{n} estimate{'s' if n != 1 else ''} over {self.duration_s:.1f} s: {counts}"
        every = self.bcr.samples_per_update
        return (
            f"no estimate: only {self.sample_time.size} IMU sample(s) lie within the "
            f"odometry's time span ({self.duration_s:.2f} s), fewer than the {every} of one BCR "
            f"update ({every / self.bcr.rate_hz:.2f} s)"
        )

    def describe(self) -> str:
        """A few lines for a person: the topics, the resampling, the statuses, the timing."""
        ok = self.status == "ok"
        lines = [
            self.imu.describe(),
            self.odometry.describe(),
            f"resampling: {self.resampling.filter}",
            *self.notes,
            self._count_line(),
        ]
        if ok.any():
            # the unit in brackets, as `gpmsa info` prints it ("1e-6 m^3" reads as a number)
            unit = getattr(self, "gd_unit", "")  # ("": a result pickled before it had one)
            unit = f" [{repr_name(unit)}]" if unit else ""
            lines.append(
                f"GD posterior mean {np.min(self.gd_mean[ok]):.0f} to "
                f"{np.max(self.gd_mean[ok]):.0f}{unit}; safety mode "
                f"{np.mean(self.mode == 'safety'):.0%} of the time"
            )
        beyond = {"upper": "rougher", "lower": "smoother"}
        for edge, named in edge_counts(self.domain_edge).items():
            if named:
                counted = "1 estimate favours" if named == 1 else f"{named} estimates favour"
                lines.append(
                    f"{counted} the {edge} edge of the emulator's GD domain: the road may be "
                    f"{beyond[edge]} than any it was trained on"
                )
        lines.append(
            f"replayed at {self.real_time_factor:.0f}x real time (read {self.read_s:.3f} s, "
            f"resample {self.condition_s:.3f} s, BCR {self.bcr_s:.3f} s)"
        )
        return "\n".join(lines)


def estimate_message(store, row: dict, interval_level: float, gd_max: float) -> bytes:
    """One row (keys CSV_COLUMNS) as a CDR ``GD_ESTIMATE_TYPE`` message."""
    types = store.types
    sec, nsec = divmod(int(row["stamp_ns"]), 1_000_000_000)
    header = types["std_msgs/msg/Header"](
        stamp=types["builtin_interfaces/msg/Time"](sec=sec, nanosec=nsec), frame_id="base_link"
    )
    msg = types[msgs.GD_ESTIMATE_TYPE](
        header=header,
        status=str(row["status"]),
        reason=str(row["reason"]),
        domain_edge=str(row["domain_edge"]),
        position=float(row["position_m"]),
        speed=float(row["speed_mps"]),
        gd_mean=float(row["gd_mean"]),
        gd_sd=float(row["gd_sd"]),
        gd_lo=float(row["gd_lo"]),
        gd_hi=float(row["gd_hi"]),
        interval_level=float(interval_level),
        gd_max=float(gd_max),
        prob_above_gd_max=float(row["prob_gd_above_max"]),
        prob_change=float(row["prob_change"]),
        command_speed=float(row["command_mps"]),
        mode=str(row["mode"]),
        safety=row["mode"] == "safety",
    )
    return bytes(store.serialize_cdr(msg, msgs.GD_ESTIMATE_TYPE))


def load_emulator(
    emulator: gpmsa.Emulator | str | os.PathLike, name: str = "emulator"
) -> gpmsa.Emulator:
    """The `gpmsa.Emulator` that ``emulator`` names: an Emulator as it is; "A" or "B": the
    shipped Jackal one (`control.shipped_emulator`; a file named A or B needs a path such as
    ./A); a str or path: the ``*.gpmsa`` file there (`gpmsa.load`). `ControlError` naming
    ``name`` for anything else, a path that is missing or no regular file, or a file gpmsa
    cannot load (chaining gpmsa's `EmulatorFileError`)."""
    if isinstance(emulator, gpmsa.Emulator):
        return emulator
    if isinstance(emulator, str) and emulator in SHIPPED:
        return shipped_emulator(emulator)
    if not isinstance(emulator, str | os.PathLike) or not str(emulator):
        raise ControlError(
            f"{name} must be a gpmsa.Emulator, the path of an emulator file (*.gpmsa) or 'A' / "
            f"'B' (the shipped ones), got {emulator!r} ({type(emulator).__name__})"
        )
    path = path_argument(emulator, name)  # a leading ~ is the home folder, as for the bag
    check_lookup(path, name)
    if not path.exists():
        raise ControlError(f"{name} {str(path)!r}: no such file (or give A or B: the shipped ones)")
    if not path.is_file():
        kind = "a folder" if path.is_dir() else "not a regular file"
        raise ControlError(
            f"{name} {str(path)!r} is {kind}, not an emulator file (*.gpmsa; or give A or B: "
            "the shipped ones)"
        )
    try:
        return gpmsa.load(path)
    except gpmsa.GPMSAError as exc:  # a damaged, foreign or too large emulator file
        raise ControlError(f"{name} {str(path)!r}: {exc}") from exc
    except OSError as exc:
        raise ControlError(f"{name} {str(path)!r}: cannot read it ({exc.strerror})") from exc


def _settings(settings: ReplaySettings | None, overrides: dict) -> ReplaySettings:
    """``settings`` (default `ReplaySettings()`) with ``overrides`` replacing its fields;
    `ControlError` for settings of another type or an override that is no field."""
    s = ReplaySettings() if settings is None else settings
    if not isinstance(s, ReplaySettings):
        raise ControlError(f"settings must be a ReplaySettings, got {type(s).__name__}")
    return replace_fields(s, overrides)


def _time_base(rec: Recording, time_base: str) -> tuple[str, str]:
    """(the base both topics are read on, a note): "log" when asked, or when either topic's
    header stamps are all zero (then neither's can be trusted to share the other's clock)."""
    if time_base == "log":
        return "log", ""
    zero = [m.topic for m in (rec.imu, rec.odometry) if np.all(m.stamp_ns == 0)]
    if zero:
        return "log", (f"every header stamp of {' and '.join(map(repr, zero))} is zero: "
                       "receive times used for both topics")  # fmt: skip
    return "header", ""


def _times(topic_msgs, base: str) -> np.ndarray:
    """A topic's times, ns, on ``base``."""
    return topic_msgs.log_ns if base == "log" else topic_msgs.stamp_ns


def replay_bag(
    bag: str | os.PathLike,
    emulator,
    settings: ReplaySettings | None = None,
    *,
    bcr: BCRSettings | None = None,
    simplex: Simplex | None = None,
    likelihood=None,
    csv: str | os.PathLike | None = None,
    out_bag: str | os.PathLike | None = None,
    progress: bool = False,
    check_vehicle: bool = True,
    **overrides,
) -> ReplayResult:
    """Run the BCR and the Simplex over a robot recording.

    Args:
        bag: a ROS 2 bag folder (MCAP or sqlite3 storage), a ``*.mcap`` file, or a ROS 1
            ``*.bag`` (see `control.robot.bags`).
        emulator: a `gpmsa.Emulator`, the path of a ``*.gpmsa`` file, or "A" / "B" for the
            shipped Jackal ones (as ``terrain-replay --emulator``; `load_emulator`), trained
            for this vehicle, sensor and rate (`control.shipped_emulator`,
            examples/train_emulator.py).
        settings: `ReplaySettings` (topics, IMU axis and sign, time base, ...); ``overrides``
            replace its fields (e.g. ``imu_topic="/imu"``).
        bcr: BCR settings (default: `control.bcr_settings_for(emulator)`).
        simplex: the controller (default `Simplex()`); its commands are what it would have
            ordered. Its v_safe and v_max must lie in the emulator's speed domain.
        likelihood: the BCR's prepared likelihood model for ``emulator`` (as in
            `control.run_closed_loop`), to save preparing it per replay; one prepared for
            another emulator is refused (`control.check_likelihood`).
        csv: write the estimates here as CSV (`ReplayResult.to_csv`); an existing file there
            is replaced only where it is empty or a CSV of estimates (its first line
            CSV_COLUMNS' header, as a replay writes it), any other is refused.
        out_bag: write the estimates here as a ROS 2 bag folder (`ReplayResult.write_bag`); a
            new one: an existing path is refused, and so is, for storage "sqlite3", a path
            holding '?', '#' or '%XX' (`control.robot.bags.check_bag_path`).
        progress: show a tqdm bar over the blocks.
        check_vehicle: where the recording is a simulation this package wrote and records its
            vehicle (`Recording.vehicle`: `control.record_run`, `write_sensor_bag(model=...)`)
            and the emulator records its own (metadata ``vehicle``), refuse the replay when
            they differ (`control.compat.check_recorded_vehicle`; a noise sd that differs is
            a `ControlWarning`). False: replay anyway (a note in ``notes`` says so). A robot's
            recording records no vehicle: nothing is checked.

    Returns:
        `ReplayResult`. Raises `BagError` (a topic missing, mistyped or empty; an IMU slower
        than the emulator's rate; on header stamps, an IMU stamped on another clock than the
        odometry throughout, ``max_clock_skew_s``; a damaged file or simulation record),
        `EmulatorMismatchError` (the recording's simulated vehicle is not the emulator's, see
        ``check_vehicle``), `ControlError` (``bag`` not a path; ``progress`` or
        ``check_vehicle`` not True or False; ``csv``
        or ``out_bag`` not a path, one in or on what is read (the recording, the whole bag
        folder of a file given inside one, or the emulator file) or an existing output
        refused as above; an
        override that is no `ReplaySettings` field; ``emulator`` none of the forms above, a
        missing file or one gpmsa cannot load, its `gpmsa.EmulatorFileError` chained; a
        setting that does not fit the emulator, a likelihood prepared for another one, a
        Simplex outside its speeds; all before the recording is read) and
        `MissingExtraError` (the ``robot`` extra not installed).
    """
    bag = recording_path(bag, "bag")
    check_lookup(bag, "bag", BagError)
    csv, out_bag = _check_outputs(bag, emulator, csv, out_bag)
    s = _settings(settings, overrides)
    check_flags(progress=progress, check_vehicle=check_vehicle)
    if out_bag is not None:
        check_bag_path(out_bag, s.storage, "out_bag")
    emulator = load_emulator(emulator)
    bcr = bcr_settings_for(emulator) if bcr is None else bcr
    simplex = Simplex() if simplex is None else simplex
    _check_fit(s, bcr, emulator, likelihood, simplex)
    rec = read_recording(bag, s.imu_topic, s.odom_topic)
    result = replay_recording(
        rec, emulator, s, bcr=bcr, simplex=simplex, likelihood=likelihood, progress=progress,
        check_vehicle=check_vehicle,
    )  # fmt: skip
    if out_bag is not None:  # a new folder, written whole or not at all
        result.write_bag(out_bag)
    if csv is not None:
        try:
            result.to_csv(csv)
        except BaseException:
            if out_bag is not None:
                shutil.rmtree(out_bag, ignore_errors=True)
            raise
    return result


def _check_outputs(bag: Path, emulator, csv, out_bag) -> tuple[Path | None, Path | None]:
    """``csv`` and ``out_bag`` as Paths, checked before the replay: `ControlError` where one is
    not a path, the OS cannot look it up (`check_lookup`: a name too long, say), lies in or on
    an input (`replay_inputs`), both are the same, ``out_bag`` exists (even as a dangling link)
    or ``csv`` is refused by `check_csv_target`."""
    inputs = replay_inputs(bag, emulator)
    paths = []
    for name, value in (("csv", csv), ("out_bag", out_bag)):
        if value is None:
            paths.append(None)
            continue
        path = path_argument(value, name)
        check_lookup(path, name)  # a name too long for the file system: before the replay
        what = overlapped_input(path, inputs)
        if what is not None:
            raise ControlError(f"{name}={str(path)!r} would overwrite {what}")
        paths.append(path)
    csv, out_bag = paths
    if csv is not None and out_bag is not None and csv.resolve() == out_bag.resolve():
        raise ControlError(f"csv and out_bag are the same path, {str(csv)!r}")
    if out_bag is not None and os.path.lexists(out_bag):
        raise ControlError(f"out_bag={str(out_bag)!r} exists already; a bag is written to a new "
                           "folder")  # fmt: skip
    if csv is not None:
        check_csv_target(csv, "csv")
    return csv, out_bag


def replay_inputs(bag: Path, emulator) -> list[tuple[str, Path]]:
    """(what it is, for a message; the path read) of each input on disk: the recording (its
    whole bag folder for a file given inside one, as `read_recording` reads it) and the
    emulator file where ``emulator`` is given as a path."""
    source = source_of(bag)
    what = f"the recording {str(bag)!r}"
    if source != bag:
        what += f" (its bag folder {str(source)!r} is read)"
    inputs = [(what, source)]
    if (isinstance(emulator, str | os.PathLike) and str(emulator)
            and not (isinstance(emulator, str) and emulator in SHIPPED)):  # fmt: skip
        inputs.append((f"the emulator file {str(emulator)!r}", path_argument(emulator, "emulator")))
    return inputs


def overlapped_input(target: Path, inputs: list[tuple[str, Path]]) -> str | None:
    """What of ``inputs`` (`replay_inputs`: the recording, the emulator file) writing ``target``
    would replace or write into (for a message), or None."""
    return next((what for what, read in inputs if _overlaps(target, read)), None)


def _overlaps(target: Path, source: Path) -> bool:
    """Whether writing ``target`` would replace ``source`` or a file inside it (links followed;
    a hard link to ``source`` counts)."""
    target_r = target.resolve()
    try:
        source_r = source.resolve()
    except ValueError:  # a name the OS cannot look up (a lone surrogate): no file to replace
        return False
    if target_r == source_r or source_r in target_r.parents:
        return True
    try:
        return os.path.samefile(target, source)
    except OSError:  # either is missing: no file to replace
        return False


def check_csv_target(path: Path, name: str) -> None:
    """`ControlError` naming the argument ``name`` unless ``path`` is free for a CSV of
    estimates: missing, an empty file or a CSV of estimates (its first line `CSV_HEADER`, as
    `ReplayResult.to_csv` writes it, or one of `OLDER_CSV_HEADERS`), which is replaced. A
    folder, a link to nowhere, a FIFO or device, and any other file (an emulator, a recording,
    someone's data) are refused, as is a path the OS cannot look up (`check_lookup`: a name too
    long, say)."""
    check_lookup(path, name)
    if path.is_dir():
        raise ControlError(f"{name}={str(path)!r} is a folder; give the CSV file's path")
    if not os.path.lexists(path):
        return
    if not path.is_file():
        raise ControlError(f"{name}={str(path)!r} exists and is not a regular file")
    try:
        with open(path, "rb") as f:
            head = f.read(len(CSV_HEADER) + 2)
    except OSError as exc:
        raise ControlError(f"{name}={str(path)!r}: cannot read it ({exc.strerror})") from exc
    if head and head.split(b"\n", 1)[0].rstrip(b"\r") not in (CSV_HEADER, *OLDER_CSV_HEADERS):
        raise ControlError(
            f"{name}={str(path)!r} exists and is not a CSV of estimates (its first line is not "
            f"the columns' header {CSV_HEADER.decode()[:30]}...); refusing to replace it: "
            "remove it or choose another path"
        )


def replay_recording(
    rec: Recording,
    emulator,
    settings: ReplaySettings | None = None,
    *,
    bcr: BCRSettings | None = None,
    simplex: Simplex | None = None,
    likelihood=None,
    progress: bool = False,
    check_vehicle: bool = True,
) -> ReplayResult:
    """`replay_bag` on a recording already read (`control.robot.bags.read_recording`)."""
    check_flags(progress=progress, check_vehicle=check_vehicle)
    s = _settings(settings, {})
    emulator = load_emulator(emulator)
    bcr = bcr_settings_for(emulator) if bcr is None else bcr
    simplex = Simplex() if simplex is None else simplex
    _check_fit(s, bcr, emulator, likelihood, simplex)
    unchecked = _check_vehicle(rec, emulator, check_vehicle)
    bcr, raw_check = _static_check(s, bcr)
    estimator = BCR.from_emulator(emulator, bcr) if likelihood is None else BCR(likelihood, bcr)
    tic = time.perf_counter()
    t, a, pos, spd, reports, resampling, notes, t0, restamping, marks = _condition(
        rec, s, bcr.rate_hz, flight_reading(bcr.sensor), raw_check,
        bcr.sensor.static_mps2 if raw_check is None else raw_check[0].static_mps2,
    )  # fmt: skip
    notes[:0] = unchecked
    condition_s = time.perf_counter() - tic

    tic = time.perf_counter()
    every = bcr.samples_per_update
    n_full = t.size // every
    ests, cmds, ends = [], [], []
    controller = simplex.start()
    # (no tqdm bar without progress: its monitor thread would outlive the replay)
    with progress_bar(progress, n_full, None, "update", mininterval=0.1, leave=False) as bar:
        for k in range(n_full):
            part = slice(k * every, (k + 1) * every)
            est = estimator.update(t[part], pos[part], a[part], spd[part], now=t[part.stop - 1])
            marked = marks.get(part.stop - 1)
            if marked and est.status == "sensor_fault":  # (the marker's fault: name the level)
                est = dataclasses.replace(est, reason=f"{marked}; {est.reason}")
            ests.append(est)
            cmds.append(controller.command(est))
            ends.append(part.stop - 1)
            bar.update(1)
    if t.size > n_full * every:
        tail = slice(n_full * every, None)
        estimator.update(t[tail], pos[tail], a[tail], spd[tail], now=t[-1])
        notes.append(f"the last {t.size - n_full * every} samples did not fill an update")
    bcr_s = time.perf_counter() - tic

    ends = np.asarray(ends, dtype=int)
    return ReplayResult(
        stamp_ns=t0 + np.rint(t[ends] * 1e9).astype(np.int64),
        time=t[ends],
        position=pos[ends],
        speed=spd[ends],
        status=np.array([e.status for e in ests], dtype=object).astype(str),
        reason=np.array([e.reason for e in ests], dtype=object),
        domain_edge=np.array([e.domain_edge for e in ests], dtype=object).astype(str),
        gd_mean=np.array([e.gd_mean for e in ests]),
        gd_sd=np.array([e.gd_sd for e in ests]),
        gd_lo=np.array([e.interval[0] for e in ests]),
        gd_hi=np.array([e.interval[1] for e in ests]),
        prob_above=np.array([e.prob_above(simplex.gd_max) for e in ests]),
        prob_change=np.array([e.prob_change for e in ests]),
        command=np.array([c.speed for c in cmds]),
        mode=np.array([c.mode for c in cmds], dtype=object).astype(str),
        estimates=tuple(ests),
        sample_time=t,
        sample_position=pos,
        sample_speed=spd,
        sample_accel=a,
        imu=reports[0],
        odometry=reports[1],
        resampling=resampling,
        notes=tuple(notes),
        read_s=rec.read_s,
        condition_s=condition_s,
        bcr_s=bcr_s,
        t0_ns=int(t0),
        settings=s,
        bcr=bcr,
        simplex=simplex,
        source=str(rec.path),
        restamping=restamping,
        gd_unit=str(emulator.t_units[0]) if emulator.t_units else "",
    )


def _check_vehicle(rec: Recording, emulator, check: bool) -> list[str]:
    """`check_recorded_vehicle` of the recording's simulation record (``check``); where not
    asked to check, a note for a vehicle that it would have refused."""
    check_flags(check_vehicle=check)
    what = f"the recording {str(rec.path)!r}"
    if check:
        check_recorded_vehicle(emulator, rec.vehicle, rec.noise_std, what)
        return []
    why = recorded_vehicle_mismatch(emulator, rec.vehicle, what)
    return [f"{why}: replayed anyway (check_vehicle=False)"] if why else []


def _check_fit(s: ReplaySettings, bcr: BCRSettings, emulator, likelihood, simplex: Simplex) -> None:
    """`ControlError` for BCR settings that are not `BCRSettings` or settings that do not fit
    the BCR's rate (a high-pass cut-off at or above its Nyquist frequency),
    `EmulatorMismatchError` for a BCR feature other than the one the emulator records, a
    likelihood prepared for another emulator or a Simplex whose speeds lie outside the
    emulator's speed domain: all before the recording is read."""
    if not isinstance(simplex, Simplex):
        raise ControlError(f"simplex must be a control.Simplex, got {type(simplex).__name__}")
    check_instance(bcr, "bcr", BCRSettings)
    check_simplex(emulator, simplex, bcr)  # the emulator too; the BCR's method: the reach
    check_recorded_feature(emulator, bcr)  # as the BCR would, once the recording was read
    nyquist = bcr.rate_hz / 2
    if s.gravity == "highpass" and s.highpass_hz >= nyquist:
        raise ControlError(
            f"highpass_hz = {s.highpass_hz:g} Hz must lie below {nyquist:g} Hz, the Nyquist "
            f"frequency of the emulator's rate ({bcr.rate_hz:g} Hz)"
        )
    static = bcr.sensor.static_mps2
    if static is not None and s.gravity == "highpass":
        raise ControlError(
            f"bcr.sensor.static_mps2 = {static:g} with gravity='highpass': the high-pass removes "
            "the static level the BCR would check (every block would read a scale fault); give "
            "ReplaySettings.static_mps2 instead, which checks the signal before the filter"
        )
    if static is not None and s.static_mps2 is not None and static != s.static_mps2:
        raise ControlError(
            f"static_mps2 = {s.static_mps2:g} and bcr.sensor.static_mps2 = {static:g} differ: "
            "give the static level once"
        )
    if likelihood is not None:
        check_likelihood(emulator, likelihood)


def _static_check(
    s: ReplaySettings, bcr: BCRSettings
) -> tuple[BCRSettings, tuple[SensorLimits, int, int] | None]:
    """Where ``s.static_mps2`` asks for the static-level check: with gravity kept, (the BCR
    settings with it, None); with "highpass", (the settings as they are, (the sensor limits
    with it, samples per update, samples per block)) for the conditioning to check the raw
    signal (`condition.static_level_marks`). Without it, (bcr, None)."""
    if s.static_mps2 is None:
        return bcr, None
    sensor = dataclasses.replace(bcr.sensor, static_mps2=s.static_mps2)
    if s.gravity == "keep":
        return dataclasses.replace(bcr, sensor=sensor), None
    return bcr, (sensor, bcr.samples_per_update, bcr.feature.block_samples)


def _check_span(rec: Recording, base: str, imu_ns, odom_ns, t0: int) -> None:
    """`BagError` naming the topic and the time when a time of either topic lies further from
    t0 (the first IMU time, ns) than int64 holds (e.g. a receive time of -2**63 in a damaged
    file): its difference from t0 would wrap around silently."""
    limit = np.iinfo(np.int64).max
    for topic_msgs, times in ((rec.imu, imu_ns), (rec.odometry, odom_ns)):
        for value in (int(times.min()), int(times.max())):
            if abs(value - t0) > limit:
                what = "receive time" if base == "log" else "header stamp"
                raise BagError(
                    f"{rec.path} is damaged: the first IMU {what} is {t0} ns and the topic "
                    f"{topic_msgs.topic!r} has one of {value} ns, {abs(value - t0) / 1e9:.4g} "
                    "s apart: more than int64 ns hold (their difference would wrap around)"
                )


def _condition(
    rec: Recording, s: ReplaySettings, rate_hz: float, flight_mps2=None,
    raw_check: tuple[SensorLimits, int, int] | None = None, static_mps2: float | None = None,
):  # fmt: skip
    """The BCR's samples (t s from t0, accel, position, speed), the reports, t0 (ns) and the
    static-level marks ({sample index: reason}, `condition.static_level_marks`: with
    ``raw_check``, (limits, samples per update, per block), of the signal before the
    high-pass; those samples read NaN); ``flight_mps2``: the BCR's `flight_reading`, and
    ``static_mps2``: the static-level check's level (None: off), for
    `condition.gravity_direction`, whose finding is a note and a `ControlWarning`."""
    notes: list[str] = []
    imu_accel, unknown = _known_accel(rec)
    if unknown:
        notes.append(unknown)
    upright = condition.gravity_direction(
        imu_accel, s.imu_axis, s.imu_sign, rec.imu.topic, flight_mps2, s.gravity, static_mps2
    )
    if upright:
        notes.append(upright)
        warnings.warn(upright, ControlWarning, stacklevel=user_stacklevel())
    base, note = _time_base(rec, s.time_base)
    imu_ns, odom_ns = _times(rec.imu, base), _times(rec.odometry, base)
    accel = s.imu_sign * imu_accel[:, "xyz".index(s.imu_axis)]
    t0 = int(imu_ns[0])
    _check_span(rec, base, imu_ns, odom_ns, t0)
    t_imu = (imu_ns - t0) / 1e9
    t_odom = (odom_ns - t0) / 1e9
    imu_recorded, accel_recorded = t_imu, accel
    if base == "header":
        accel, skewed = _other_clock(rec, accel, s.max_clock_skew_s)
        if skewed:
            notes.append(skewed)
            warnings.warn(skewed, ControlWarning, stacklevel=user_stacklevel())
    copies = _exact_copies(rec.imu, base)
    if copies.any():  # a recording's duplicate (merged or overlapping bags), not a sample
        t_imu, accel = t_imu[~copies], accel[~copies]
        same = "header stamp" if base == "header" else "header stamp, receive time"
        notes.append(
            f"{np.count_nonzero(copies)} IMU message(s) left out as exact copies of an earlier "
            f"one (the same {same} and acceleration, bit for bit)"
        )
    odom_finite = np.all(np.isfinite(rec.odometry.position), axis=1) & np.all(
        np.isfinite(rec.odometry.velocity), axis=1
    )
    order, odom_said = np.arange(t_odom.size), ""
    if base == "header" and s.reorder_periods > 0 and t_odom.size > 1:
        period = condition.nominal_period(t_odom)  # odometry delivered late: stamp order
        if np.isfinite(period):
            order = clock.stamp_order(t_odom, s.reorder_periods * period)
            order, far = clock.into_gaps(t_odom, order, period)
            odom_said = _odometry_reordered(t_odom, order, far, s.reorder_periods)
    t_imu, accel, said, restamping = _imu_clock(rec.imu.topic, t_imu, accel, base, s)
    imu_note = "; ".join(filter(None, [note, *said]))
    odom_note = "; ".join(filter(None, [note, odom_said]))
    reports = (
        condition.check_stream(
            rec.imu.topic, imu_recorded, np.isfinite(accel_recorded), base, imu_note
        ),  # fmt: skip
        condition.check_stream(rec.odometry.topic, t_odom, odom_finite, base, odom_note),
    )
    t_odom, odom_finite = t_odom[order], odom_finite[order]
    t, a, resampling = condition.to_rate(
        t_imu, accel, rate_hz, s.rate_tolerance, s.resample, rec.imu.topic
    )
    if t.size == 0:  # resampled: every run too short for the filter's start-up at both ends
        raise BagError(
            f"the IMU topic {rec.imu.topic!r} gives no sample at {rate_hz:g} Hz: resampling "
            f"its {resampling.rate_in_hz:.4g} Hz needs runs of increasing stamps and finite "
            f"values longer than {2 * resampling.trimmed_per_edge / rate_hz:.3g} s, and "
            f"{resampling.dropped} of its {t_imu.size} messages (repeated or backwards stamps, "
            "non-finite values) cut it into shorter ones"
        )
    raw = a
    if s.gravity == "highpass":
        a = condition.highpass(t, a, rate_hz, s.highpass_hz)

    keep = condition.increasing(t_odom) & odom_finite
    if not keep.any():
        raise BagError(f"the odometry topic {rec.odometry.topic!r} has no usable message")
    if not keep.all():
        notes.append(
            f"{np.count_nonzero(~keep)} odometry messages left out (repeated or backwards "
            "stamps, non-finite values)"
        )
    to = t_odom[keep]
    po, vo = rec.odometry.position[order][keep], rec.odometry.velocity[order][keep]
    speed = np.hypot(vo[:, 0], vo[:, 1])
    if s.position == "path":
        along = condition.path_length(po)
    else:
        along = condition.integrated_speed(to, speed)
    # samples outside the odometry's span are left out (a bag often starts the IMU first)
    finite_t = np.isfinite(t)
    inside = ~finite_t | ((t >= to[0]) & (t <= to[-1]))
    first = int(np.argmax(inside)) if inside.any() else t.size
    last = t.size - int(np.argmax(inside[::-1])) if inside.any() else t.size
    if first or last < t.size:
        notes.append(
            f"{first} IMU samples before the first and {t.size - last} after the last "
            "odometry message left out"
        )
    t, a = t[first:last], a[first:last]
    pos, spd = condition.odometry_at(t, to, along, speed, s.max_odometry_gap_s)
    marks: dict[int, str] = {}
    if raw_check is not None:  # (samples the BCR drops for their odometry: as non-finite)
        kept = _bcr_kept(pos, spd)
        marks = condition.static_level_marks(raw[first:last], *raw_check, t, rate_hz, kept)
        a[list(marks)] = np.nan
        if marks:
            notes.append(
                f"{len(marks)} update(s) whose block or span read a static level off "
                f"{s.static_mps2:g} m/s^2 before the high-pass (a scale fault): their newest "
                "sample marked non-finite (sensor_fault)"
            )
    in_gap = finite_t[first:last] & ~np.isfinite(pos)
    if in_gap.any():
        notes.append(
            f"{np.count_nonzero(in_gap)} IMU samples fell in odometry gaps longer than "
            f"{s.max_odometry_gap_s:g} s (no position or speed: sensor faults)"
        )
    if t.size == 0:
        raise BagError(
            f"the IMU topic {rec.imu.topic!r} and the odometry topic {rec.odometry.topic!r} do "
            "not overlap in time"
        )
    return t, a, pos, spd, reports, resampling, notes, t0, restamping, marks


def _known_accel(rec: Recording) -> tuple[np.ndarray, str]:
    """The IMU's (n, 3) accelerations with NaN (a sensor fault for the BCR) in the messages
    that mark theirs unknown (`ImuMessages.accel_unknown`), and a note saying how many ("" for
    none); `BagError` where every message does: the topic holds no acceleration."""
    imu, unknown = rec.imu, rec.imu.accel_unknown
    if unknown is None or not unknown.any():
        return imu.accel, ""
    how = "linear_acceleration_covariance[0] = -1, the Imu message's mark for no estimate"
    if unknown.all():
        imu_types = (msgs.IMU_TYPE, "sensor_msgs/Imu")  # (ROS 1 and some MCAP writers)
        others = sorted(t for t, ty in rec.topics.items() if ty in imu_types and t != imu.topic)
        raise BagError(
            f"the IMU topic {imu.topic!r} marks its linear acceleration unknown in each of its "
            f"{unknown.size} messages ({how}; an orientation-only output): it holds no "
            "acceleration to replay; choose the IMU topic that reports it (imu_topic / "
            "--imu-topic" + (f"; the recording's other IMU topics: {', '.join(others)})"
                             if others else ")")
        )  # fmt: skip
    accel = imu.accel.copy()
    accel[unknown] = np.nan
    return accel, (
        f"{np.count_nonzero(unknown)} of the IMU's {unknown.size} messages mark their linear "
        f"acceleration unknown ({how}): fed as sensor faults (non-finite accel)"
    )


def _exact_copies(imu: ImuMessages, base: str) -> np.ndarray:
    """(n,) bool: the IMU messages that repeat an earlier one of the topic exactly: the same
    header stamp, on receive times (``base`` "log": asked for, or where a topic's header stamps
    are all zero) the same receive time too, and the same acceleration, bit for bit. On
    receive times, messages of one header stamp received apart are samples (a driver that
    stamps several at once, a stuck sensor's repeated reading): none is a copy."""
    n = imu.stamp_ns.size
    key = np.empty(n, dtype=[("t", "<i8"), ("r", "<i8"), ("a", "V24")])
    key["t"] = imu.stamp_ns
    key["r"] = imu.log_ns if base == "log" else 0
    key["a"] = np.ascontiguousarray(imu.accel, dtype="<f8").view("V24")[:, 0]
    _, first = np.unique(key, return_index=True)
    copies = np.ones(n, dtype=bool)
    copies[first] = False
    return copies


def _bcr_kept(pos: np.ndarray, spd: np.ndarray) -> np.ndarray:
    """(n,) bool: False for a sample that the BCR drops for its odometry (`stream_breaks`): no
    position or speed (an odometry gap), or a speed beyond ``MAX_SPEED_MPS`` (a wild odometry
    velocity, interpolated)."""
    with np.errstate(invalid="ignore"):
        return np.isfinite(pos) & np.isfinite(spd) & (np.abs(spd) <= MAX_SPEED_MPS)


def _other_clock(rec: Recording, accel: np.ndarray, limit_s: float) -> tuple[np.ndarray, str]:
    """``accel`` with NaN at the IMU messages whose header clock runs more than ``limit_s``
    from the odometry's (`clock.header_skew`), and a note saying so ("" where none);
    `BagError` where every message does (the two topics were stamped on different clocks)."""
    if not np.isfinite(limit_s):
        return accel, ""
    imu, odom = rec.imu, rec.odometry
    skew = clock.header_skew(imu.stamp_ns, imu.log_ns, odom.stamp_ns, odom.log_ns)
    if skew is None:
        return accel, ""
    off = np.abs(skew) > limit_s
    if not off.any():
        return accel, ""
    worst = float(skew[np.argmax(np.abs(skew))])
    how = f"{abs(worst):.3g} s {'ahead of' if worst > 0 else 'behind'}"
    remedy = (
        "paired on header stamps, an IMU sample would meet the odometry of another time; "
        'replay on the receive times (--time-base log, time_base="log"), or stamp both '
        "topics on one clock"
    )
    if off.all():
        median = numbers_text(np.median(skew), limit_s, digits=3)[0]
        raise BagError(
            f"the IMU topic {imu.topic!r} and the odometry topic {odom.topic!r} are stamped "
            f"on different clocks: against their receive times the IMU's header stamps run "
            f"{how} the odometry's (median {median} s, more than "
            f"max_clock_skew_s = {limit_s:g} s): {remedy}"
        )
    t_off = (imu.log_ns[np.argmax(off)] - imu.log_ns[0]) / 1e9
    return np.where(off, np.nan, accel), (
        f"{np.count_nonzero(off)} of the IMU's {off.size} messages (from {t_off:.1f} s of "
        f"receive time on) were stamped on another clock than the odometry's: their header "
        f"stamps run up to {how} it against their receive times (more than max_clock_skew_s "
        f"= {limit_s:g} s; a clock step of the IMU's driver?), fed as sensor faults "
        f"(non-finite accel): {remedy}"
    )


def _reordered(t: np.ndarray, order: np.ndarray, periods: float) -> str:
    """A topic's report note where ``order`` (`clock.stamp_order`) put some of its messages,
    times ``t`` (s, as recorded), back in stamp order ("" where it moved none)."""
    if np.count_nonzero(np.diff(t) < 0) > np.count_nonzero(np.diff(t[order]) < 0):
        return (
            f"messages received out of stamp order by at most {periods:g} periods put in "
            "stamp order"
        )
    return ""


def _odometry_reordered(t: np.ndarray, order: np.ndarray, far: int, periods: float) -> str:
    """The odometry report's note where ``order`` put messages received behind a later one
    (times ``t``, s, as recorded) in stamp order: how many, ``far`` of them more than
    ``periods`` late (`clock.into_gaps`); "" where it put none."""
    behind = np.zeros(t.size, dtype=bool)
    behind[1:] = t[1:] < np.maximum.accumulate(t)[:-1]
    used = np.zeros(t.size, dtype=bool)
    used[order] = condition.increasing(t[order])
    n = int(np.count_nonzero(behind & used))
    if not n:
        return ""
    return f"{n} message(s) received out of stamp order put in stamp order" + (
        f" ({far} of them more than {periods:g} periods late, each into the gap its stamp "
        "left)" if far else f" (by at most {periods:g} periods)"
    )  # fmt: skip


def _imu_clock(topic: str, t: np.ndarray, accel: np.ndarray, base: str, s: ReplaySettings):
    """The IMU's (times s, accel) in stamp order within ``s.reorder_periods`` (header stamps
    only) and re-stamped on their clock (``s.restamp``, `clock.restamp`), what was done
    (texts for its `StreamReport`'s note) and the `clock.Restamping`."""
    said = []
    period = condition.nominal_period(t)
    if base == "header" and s.reorder_periods > 0 and np.isfinite(period):
        order = clock.stamp_order(t, s.reorder_periods * period)
        if reordered := _reordered(t, order, s.reorder_periods):
            said.append(reordered)
        t, accel = t[order], accel[order]
    if not s.restamp:
        return t, accel, said, clock.Restamping(False)
    what = "header stamps" if base == "header" else "receive times"
    new, info = clock.restamp(t, f"its {what}")
    if info.restamped:
        seen = condition.check_stream(topic, new, np.ones(new.size, bool), base)
        said.append(f"{info.note}; on that clock: {seen.faults()}")
    elif info.note:
        said.append(info.note)
    return new, accel, said, info
