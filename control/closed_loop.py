"""The closed loop: vehicle -> BCR -> Simplex -> speed command -> vehicle; traces and metrics."""

from __future__ import annotations

import os
import time as _time
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np

import roadgen
import vehicle
from control.bcr import BCR, BCRSettings
from control.compat import bcr_settings_for, check_against, check_emulator, check_likelihood
from control.errors import ControlError, ControlWarning, EmulatorMismatchError, user_stacklevel
from control.estimate import Estimate, run_text
from control.faults import FaultInjector, SensorFault
from control.metrics import (
    GDError,
    detection_delays,
    fast_on_rough_m,
    gd_errors,
    interval_coverage,
    segment_index,
    strict_json,
)
from control.robot.storage import check_mcap_target
from control.sensor_checks import SensorLimits
from control.simplex import Simplex
from control.validation import check_flags, check_instance, is_real, path_argument
from gpmsa._progress import progress_bar
from gpmsa.errors import numbers_text
from vehicle.simulate import SUBSTEPS

EXACT_CLOCK_SILENCE = 0.5
"""The simulated sensor's clock is exact, so any sample missing at an update is silence: the
loop's BCR uses ``max_silence_s`` no longer than this many sample periods (a real link's jitter
is what the BCR's own default of 0.5 s allows for)."""


_GD_RTOL = 1e-6
"""Relative tolerance of `LoopMetrics.rmse`'s match of a GD to the track's (float32 rounding is
below 6e-8)."""


def gd_key(x: float) -> str:
    """``x`` as %g where that reads back as ``x``, else all its digits (300.1000061): the key
    of a part of the track with prescribed GD ``x`` in `LoopMetrics.as_dict` (two GDs that
    differ never share one)."""
    short = f"{x:g}"
    return short if float(short) == x else repr(float(x))


@dataclass(frozen=True)
class LoopMetrics:
    """Scores of one run.

    Attributes:
        gd_errors: RMSE ingredients per prescribed GD (estimates vs the GD at their position).
        detection_delay_m: per GD change along the track, m (NaN: never detected).
        fast_on_rough_m: distance driven faster than v_safe where the prescribed GD > GD_max, m.
        traversal_time_s: simulated time to the end of the track, s.
        wall_time_s: wall-clock time of the whole loop, s.
        latency_median_s, latency_max_s: BCR compute latency over its estimates, s.
        ok_fraction: fraction of BCR updates that produced an estimate.
        coverage: fraction of the estimates whose credible interval holds the prescribed GD,
            both ends included (`metrics.interval_coverage`).
        latched_at_s: time of the estimate whose fault latched safety mode (the Simplex's
            ``after_fault="latch"``), s; NaN if none did.
    """

    gd_errors: tuple[GDError, ...]
    detection_delay_m: tuple[float, ...]
    fast_on_rough_m: float
    traversal_time_s: float
    wall_time_s: float
    latency_median_s: float
    latency_max_s: float
    ok_fraction: float
    coverage: float = np.nan
    latched_at_s: float = np.nan

    @property
    def real_time_factor(self) -> float:
        """Simulated seconds per wall-clock second (NaN where no wall-clock time was
        measured)."""
        return self.traversal_time_s / self.wall_time_s if self.wall_time_s > 0 else np.nan

    def rmse(self, gd: float) -> float:
        """RMSE of the estimates on the parts with prescribed GD `gd` (NaN where those parts
        hold no estimate, e.g. shorter than the first block); the GD matches to a relative
        1e-6, so a GD that went through float32 (300.1 as 300.1000061) finds its parts.
        ControlError for a `gd` that no part of the track has, or that is not a finite number
        (inf lay within the relative tolerance of every part: the first part's RMSE)."""
        if not is_real(gd):
            raise ControlError(f"gd must be a real number, got {gd!r} ({type(gd).__name__})")
        if not np.isfinite(gd):
            raise ControlError(f"gd must be finite, got {gd!r}")
        gd = float(gd)
        track = np.array([e.gd for e in self.gd_errors], dtype=float)
        if track.size:
            off = np.abs(track - gd)
            i = int(np.argmin(off))  # the nearest, should two lie within the tolerance
            if off[i] <= _GD_RTOL * abs(gd):
                return self.gd_errors[i].rmse
        track_gds = ", ".join(gd_key(e.gd) for e in self.gd_errors)
        raise ControlError(
            f"no part of the track has prescribed GD {gd_key(gd)}; its GDs: {track_gds}"
        )

    def as_dict(self) -> dict:
        """JSON-able summary (`strict_json`: a value that is not finite, e.g. ``latched_at_s``
        of a run that never latched or the RMSE of a part without estimates, is None). The
        parts are keyed by their GD as ``%g`` ("300"), or all its digits where ``%g`` would
        not read back as it (two GDs that differ never share a key)."""
        summary = {
            "rmse": {gd_key(e.gd): e.rmse for e in self.gd_errors},  # (keys that differ)
            "n_estimates": {gd_key(e.gd): e.n for e in self.gd_errors},
            "detection_delay_m": list(self.detection_delay_m),
            "fast_on_rough_m": self.fast_on_rough_m,
            "traversal_time_s": self.traversal_time_s,
            "wall_time_s": self.wall_time_s,
            "real_time_factor": self.real_time_factor,
            "latency_median_s": self.latency_median_s,
            "latency_max_s": self.latency_max_s,
            "ok_fraction": self.ok_fraction,
            "coverage": self.coverage,
            "latched_at_s": self.latched_at_s,
        }
        return strict_json(summary)


@dataclass(frozen=True, eq=False)
class ClosedLoopResult:
    """Traces and metrics of one closed-loop run.

    Per BCR update (length k): ``time`` s, ``position`` m, ``gd_mean``, ``gd_lo``, ``gd_hi`` (the
    credible interval; NaN when there is no estimate), ``gd_true`` (prescribed GD at the position),
    ``status`` (str), ``reason`` (str), ``domain_edge`` (str: the edge of the emulator's GD
    domain the data favour, "" for none; `Estimate.domain_edge`), ``prob_change`` (P(a change
    within the BCR's recent_change_m)), ``command`` (m/s), ``mode`` ("performance"/"safety"),
    ``latency_s``.
    Per sensor sample (length n): ``sample_time``, ``sample_position``, ``sample_speed``,
    ``sample_accel`` (the measured front-axle acceleration, m/s^2, before injected faults).
    ``settings``: what ran: ``model`` (the vehicle), ``noise_std``, ``seed``, ``bcr``,
    ``simplex``, ``faults``, ``substeps``.
    """

    time: np.ndarray
    position: np.ndarray
    gd_mean: np.ndarray
    gd_lo: np.ndarray
    gd_hi: np.ndarray
    gd_true: np.ndarray
    status: np.ndarray
    reason: np.ndarray
    domain_edge: np.ndarray
    prob_change: np.ndarray
    command: np.ndarray
    mode: np.ndarray
    latency_s: np.ndarray
    sample_time: np.ndarray
    sample_position: np.ndarray
    sample_speed: np.ndarray
    sample_accel: np.ndarray
    metrics: LoopMetrics
    settings: dict = field(default_factory=dict)

    def __repr__(self) -> str:
        """One line: the estimates, the span driven, the statuses and the samples (`run_text`);
        not the arrays (a dataclass's repr printed them: 21,000 characters for a 50 m run)."""
        text = run_text(self.status, self.sample_time, self.sample_position, "sensor")
        return f"ClosedLoopResult({text})"


def _run_seed(seed) -> int | None:
    """The seed a run uses and records: None, an integer >= 0, or one drawn from a numpy
    Generator (as gpmsa's calls take one), so that ``seed=`` the recorded integer repeats the
    run; ControlError for anything else."""
    if seed is None:
        return None
    if isinstance(seed, np.random.Generator):
        return int(seed.integers(2**63))
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise ControlError(
            f"seed must be None or an integer >= 0, got {seed!r} (or a numpy Generator)"
        )
    return int(seed)


def _check_faults(faults) -> tuple[SensorFault, ...]:
    """The injected faults as a tuple; ControlError unless a sequence of `SensorFault`."""
    if isinstance(faults, SensorFault):
        raise ControlError("faults must be a sequence of SensorFault: pass [fault]")
    try:
        faults = tuple(faults)
    except TypeError as exc:
        raise ControlError(f"faults must be a sequence of SensorFault, got {faults!r}") from exc
    wrong = [f for f in faults if not isinstance(f, SensorFault)]
    if wrong:
        raise ControlError(f"faults must hold SensorFault objects, got {wrong[0]!r}")
    return faults


def _check_record_path(record) -> None:
    """ControlError before the drive when ``record`` is not a path, names a folder or a file
    that is not an earlier recording (`check_mcap_target`), or has no writable folder."""
    path = path_argument(record, "record", " of the .mcap file to write")
    check_mcap_target(path, "record")
    folder = next((p for p in path.absolute().parents if p.exists()), None)
    if folder is None or not folder.is_dir() or not os.access(folder, os.W_OK):
        raise ControlError(f"record={str(record)!r}: cannot write under {folder}")


def _within_simulated_noise(sensor: SensorLimits, noise_std: float) -> SensorLimits:
    """The sensor checks with a noise sd no larger than the simulated sensor's (None if 0)."""
    assumed = sensor.noise_sd_mps2
    if assumed is None or noise_std >= assumed:
        return sensor
    return replace(sensor, noise_sd_mps2=float(noise_std) if noise_std > 0 else None)


def simulated_sensor_settings(bcr: BCRSettings, noise_std: float) -> BCRSettings:
    """The BCR settings a loop over the simulated sensor uses: ``max_silence_s`` no longer than
    `EXACT_CLOCK_SILENCE` sample periods (the simulation's clock is exact) and the sensor checks'
    noise sd no larger than the simulated ``noise_std`` (m/s^2)."""
    return replace(
        bcr,
        max_silence_s=min(bcr.max_silence_s, EXACT_CLOCK_SILENCE / bcr.rate_hz),
        sensor=_within_simulated_noise(bcr.sensor, noise_std),
    )


def run_closed_loop(
    track,
    emulator,
    model=None,
    noise_std: float = 0.0,
    seed: int | np.integer | np.random.Generator | None = None,
    bcr: BCRSettings | None = None,
    simplex: Simplex | None = None,
    progress: bool = False,
    *,
    likelihood=None,
    faults: Sequence[SensorFault] = (),
    check: bool = True,
    max_time_s: float | None = None,
    record: str | os.PathLike | None = None,
    substeps: int = SUBSTEPS,
) -> ClosedLoopResult:
    """Drive `model` over `track` with the BCR estimating GD and the Simplex setting the speed.

    Args:
        track: a roadgen Track (prescribed GD per segment), longer than the vehicle's
            wheelbase (and its wheel radius): a shorter one is a ControlError.
        emulator: a gpmsa Emulator mapping (v, GD) to the BCR's observation (see
            `control.shipped_emulator`).
        model: vehicle model (default `vehicle.Jackal()`); must match the emulator's metadata.
        noise_std: accelerometer noise standard deviation, m/s^2 (Test Case B: 1.0).
        seed: seed (integer >= 0, or a numpy Generator to draw one from) of the measurement
            noise and of the injected faults; the integer is ``settings["seed"]``.
        bcr: BCR settings (default: `bcr_settings_for(emulator)`, the emulator's feature); the
            loop shortens ``max_silence_s`` to `EXACT_CLOCK_SILENCE` sample periods, since the
            simulation's clock is exact (a dropped sample at the end of an update is a fault
            at that update, not half a second later), and lowers the sensor checks' noise sd
            to the simulated ``noise_std`` where that is lower (a noise-free run with a noisy
            emulator has no noise floor to check).
        simplex: the controller (default `Simplex()`, the paper's band and speeds); its top and
            safe speeds must be within the vehicle's.
        progress: show a tqdm bar over the track length.
        likelihood: the BCR's prepared likelihood model for `emulator` (an `ObservationModel`
            for the change-point method, a `gpmsa.Calibrator` for the window methods), to save
            preparing one per run; one prepared for another emulator is refused
            (`check_likelihood`).
        faults: injected sensor faults (`SensorFault`).
        check: check the emulator against model, noise, feature, track and the Simplex's
            speeds (`check_emulator`).
        max_time_s: simulated time after which a vehicle that has not reached the end is an
            error, finite (default: 20 times the track length at the safe speed).
        record: write the run to this MCAP file for Foxglove (`control.record_run`: the
            accelerations, speed command and actual speed, the GD estimate with its interval,
            the mode and the true GD; needs the ``robot`` extra).
        substeps: the vehicle solver's steps per sample period (`vehicle.Simulation`; its
            `SolverStepWarning` names the number a stiff model needs).

    Returns:
        `ClosedLoopResult` with traces and `LoopMetrics`.
    """
    make = "roadgen.track(segments, seed=...) makes one of (length_m, GD) segments"
    check_instance(track, "track", roadgen.Track, hint=make)
    defaulted = model is None
    model = vehicle.Jackal() if defaulted else vehicle.models.check_model(model)
    _check_track_fits(track, model)
    simplex = Simplex() if simplex is None else simplex
    check_instance(simplex, "simplex", Simplex)
    if bcr is not None:
        check_instance(bcr, "bcr", BCRSettings)
    seed = _run_seed(seed)
    check_flags(check=check, progress=progress)
    noise_std = vehicle.sensor.check_noise(noise_std)
    substeps = vehicle.checks.integer("substeps", substeps, 1)  # before the emulator's checks
    faults = _check_faults(faults)
    if max_time_s is not None and not (is_real(max_time_s) and 0 < max_time_s < np.inf):
        raise ControlError(  # (inf: a vehicle that stands would never end the run)
            f"max_time_s must be None or a finite number > 0, s, got {max_time_s!r}"
        )
    if record is not None:  # without the robot extra, fail before the drive, not after it
        from control.robot.record import check_can_record, record_run

        _check_record_path(record)  # a wrong path is named with or without the extra
        check_can_record()
    recorded = "vehicle" in (getattr(emulator, "metadata", None) or {})
    if check:  # its inputs and GD unit first: the message below is of the vehicle alone
        check_emulator(emulator)  # (once: the checks below are `check_against`'s)
    if check and recorded:
        # first: a model left at its default says so, not that the Simplex is too fast for it
        try:
            check_against(emulator, model=model)
        except EmulatorMismatchError as exc:
            if not defaulted:
                raise
            raise EmulatorMismatchError(
                f"model= was not given, so the default vehicle.Jackal() would drive, but the "
                f"{exc}: pass model=control.emulator_vehicle(emulator), the vehicle it records"
            ) from None
    elif check and defaulted:
        warnings.warn(
            "model= was not given, so the default vehicle.Jackal() drives, and the emulator's "
            "metadata records no 'vehicle' to check it against: pass model=, the vehicle the "
            "emulator was trained for",
            ControlWarning,
            stacklevel=user_stacklevel(),
        )
    top = float(model.max_speed_mps)
    if simplex.v_max > top * (1 + 1e-12):
        v_max, top_text = numbers_text(simplex.v_max, top)
        raise ControlError(
            f"Simplex v_max = {v_max} m/s exceeds the vehicle's top speed {top_text} m/s"
        )
    bcr = simulated_sensor_settings(bcr_settings_for(emulator) if bcr is None else bcr, noise_std)
    if check:
        # (a default model without a record to check is warned of above)
        checked = None if defaulted and not recorded else model
        check_against(emulator, model=checked, noise_std=noise_std, bcr=bcr)
        _check_track_domain(emulator, track)
        check_against(emulator, simplex=simplex, bcr=bcr)  # (its method: ends checked)
    if likelihood is not None:
        check_likelihood(emulator, likelihood)
    estimator = BCR.from_emulator(emulator, bcr) if likelihood is None else BCR(likelihood, bcr)
    rng = np.random.default_rng(seed)
    noise_seed, fault_rng = rng.integers(2**63), np.random.default_rng(rng.integers(2**63))
    inject = FaultInjector(faults, fault_rng)
    sim = vehicle.Simulation(
        model, track, rate_hz=bcr.rate_hz, noise_std=noise_std, seed=int(noise_seed),
        substeps=substeps,
    )  # fmt: skip
    dt = bcr.samples_per_update / bcr.rate_hz
    limit = 20.0 * float(track.length_m) / simplex.v_safe if max_time_s is None else max_time_s

    rows: list[tuple[Estimate, object]] = []
    s_t, s_pos, s_spd, s_acc = [], [], [], []
    tic = _time.perf_counter()
    controller = simplex.start()
    command = controller.command(estimator.last)
    with progress_bar(  # (none without progress: no tqdm monitor thread beside later forks)
        progress, round(float(track.length_m)), None, "m", mininterval=0.1, leave=False
    ) as bar:
        while not sim.finished:
            if sim.time > limit:
                raise ControlError(_timeout_message(sim, track, simplex, limit))
            samples = sim.advance(dt, command.speed)
            if len(samples) == 0:
                break
            s_t.append(np.asarray(samples.t, dtype=float))
            s_pos.append(np.asarray(samples.position, dtype=float))
            s_spd.append(np.asarray(samples.speed, dtype=float))
            s_acc.append(np.asarray(samples.accel_front, dtype=float))
            observed = inject(samples.t, samples.position, samples.accel_front, samples.speed)
            estimate = estimator.update(*observed, now=float(samples.t[-1]))
            command = controller.command(estimate)
            rows.append((estimate, command))
            bar.update(max(0, round(float(s_pos[-1][-1])) - bar.n))
    wall = _time.perf_counter() - tic

    ests = [e for e, _ in rows]
    # the position of each update is the vehicle's (an estimate may carry a stale position
    # when its samples were faulty)
    position = np.array([p[-1] for p in s_pos])
    gd_mean = np.array([e.gd_mean for e in ests])
    gd_lo = np.array([e.interval[0] for e in ests])
    gd_hi = np.array([e.interval[1] for e in ests])
    sample_time = np.concatenate(s_t) if s_t else np.empty(0)
    sample_position = np.concatenate(s_pos) if s_pos else np.empty(0)
    sample_speed = np.concatenate(s_spd) if s_spd else np.empty(0)
    sample_accel = np.concatenate(s_acc) if s_acc else np.empty(0)
    latencies = np.array([e.latency_s for e in ests if e.ok])
    seg_gd = np.array([gd for _, gd in track.segments], dtype=float)
    gd_true = seg_gd[segment_index(track, position)]
    ok = np.isfinite(gd_mean)
    metrics = LoopMetrics(
        gd_errors=gd_errors(track, position, gd_mean),
        detection_delay_m=detection_delays(track, position, gd_mean),
        fast_on_rough_m=fast_on_rough_m(
            track, sample_position, sample_speed, simplex.gd_max, simplex.v_safe
        ),
        traversal_time_s=float(sample_time[-1]) if sample_time.size else 0.0,
        wall_time_s=wall,
        latency_median_s=float(np.median(latencies)) if latencies.size else np.nan,
        latency_max_s=float(np.max(latencies)) if latencies.size else np.nan,
        ok_fraction=float(np.mean(ok)) if ests else 0.0,
        coverage=interval_coverage(gd_mean, gd_lo, gd_hi, gd_true),
        latched_at_s=controller.latched_by.time if controller.latched else np.nan,
    )
    result = ClosedLoopResult(
        time=np.array([t[-1] for t in s_t]),
        position=position,
        gd_mean=gd_mean,
        gd_lo=gd_lo,
        gd_hi=gd_hi,
        gd_true=gd_true,
        status=np.array([e.status for e in ests]),
        reason=np.array([e.reason for e in ests], dtype=object),
        domain_edge=np.array([e.domain_edge for e in ests], dtype=object),
        prob_change=np.array([e.prob_change for e in ests]),
        command=np.array([c.speed for _, c in rows]),
        mode=np.array([c.mode for _, c in rows]),
        latency_s=np.array([e.latency_s for e in ests]),
        sample_time=sample_time,
        sample_position=sample_position,
        sample_speed=sample_speed,
        sample_accel=sample_accel,
        metrics=metrics,
        settings={
            "model": model,
            "noise_std": noise_std,
            "seed": seed,
            "bcr": bcr,
            "simplex": simplex,
            "faults": tuple(faults),
            "substeps": substeps,
        },
    )
    if record is not None:
        record_run(result, record)
    return result


def _check_track_fits(track, model) -> None:
    """ControlError before the drive for a track that the vehicle cannot drive: one shorter than
    its wheel radius (the tyres follow the road enveloped by the wheel) or not longer than its
    wheelbase (both axles stand on it)."""
    length, radius, base = map(float, (track.length_m, model.wheel_radius_m, model.wheelbase_m))
    if length < radius:
        why = "shorter than the vehicle's wheel radius"
    elif not length > base:
        why = "not longer than the vehicle's wheelbase"
    else:
        return
    length_text, need_text, base_text = numbers_text(
        length, radius if length < radius else base, base
    )
    raise ControlError(
        f"track is {length_text} m long, {why} {need_text} m: the vehicle cannot drive it; "
        f"lengthen the track (to more than the wheelbase, {base_text} m)"
    )


def _check_track_domain(emulator, track) -> None:
    """`check_against` of ``track``: a GD outside the emulator's domain is an
    `EmulatorMismatchError` that says how to drive it anyway."""
    try:
        check_against(emulator, track=track)
    except EmulatorMismatchError as exc:
        raise EmulatorMismatchError(
            f"{exc}: check=False drives it anyway (it skips every check of the emulator; "
            "docs/closed-loop.md, Guards, says what the estimate does beyond the domain)"
        ) from None


def _timeout_message(sim, track, simplex: Simplex, limit: float) -> str:
    """Why a run passed its time limit ``limit`` (s): a limit shorter than the drive at v_max, or
    a vehicle that stood or crawled."""
    fastest = float(track.length_m) / simplex.v_max
    where = f"{sim.position:.1f} of {track.length_m:.1f} m after {sim.time:.3g} s"
    if limit < fastest:
        return (f"max_time_s = {limit:g} s ended the run at {where}: the track takes at least "
                f"{fastest:.3g} s at v_max")  # fmt: skip
    return f"the vehicle stood or crawled: {where} (max_time_s = {limit:g})"
