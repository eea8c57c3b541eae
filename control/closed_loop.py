"""The closed loop: vehicle -> BCR -> Simplex -> speed command -> vehicle; traces and metrics."""

from __future__ import annotations

import time as _time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from tqdm.auto import tqdm

import gpmsa
import vehicle
from control.bcr import BCR, BCRSettings
from control.compat import bcr_settings_for, check_emulator
from control.errors import ControlError
from control.estimate import Estimate
from control.metrics import GDError, detection_delays, fast_on_rough_m, gd_errors, segment_index
from control.simplex import Simplex


@dataclass(frozen=True)
class SensorFault:
    """An injected accelerometer fault.

    Attributes:
        start_s: time the fault begins, s.
        duration_s: how long it lasts, s.
        kind: "nan" (the samples read NaN) or "drop" (the samples never arrive).
    """

    start_s: float
    duration_s: float
    kind: str = "nan"

    def __post_init__(self) -> None:
        if not (np.isfinite(self.start_s) and self.start_s >= 0):
            raise ControlError(f"start_s must be >= 0, got {self.start_s}")
        if not (np.isfinite(self.duration_s) and self.duration_s > 0):
            raise ControlError(f"duration_s must be > 0, got {self.duration_s}")
        if self.kind not in ("nan", "drop"):
            raise ControlError(f"kind must be 'nan' or 'drop', got {self.kind!r}")


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
    """

    gd_errors: tuple[GDError, ...]
    detection_delay_m: tuple[float, ...]
    fast_on_rough_m: float
    traversal_time_s: float
    wall_time_s: float
    latency_median_s: float
    latency_max_s: float
    ok_fraction: float

    @property
    def real_time_factor(self) -> float:
        """Simulated seconds per wall-clock second."""
        return self.traversal_time_s / self.wall_time_s

    def rmse(self, gd: float) -> float:
        """RMSE of the estimates on the parts with prescribed GD `gd` (NaN if none)."""
        for e in self.gd_errors:
            if e.gd == gd:
                return e.rmse
        return np.nan

    def as_dict(self) -> dict:
        """JSON-able summary."""
        return {
            "rmse": {f"{e.gd:g}": e.rmse for e in self.gd_errors},
            "n_estimates": {f"{e.gd:g}": e.n for e in self.gd_errors},
            "detection_delay_m": list(self.detection_delay_m),
            "fast_on_rough_m": self.fast_on_rough_m,
            "traversal_time_s": self.traversal_time_s,
            "wall_time_s": self.wall_time_s,
            "real_time_factor": self.real_time_factor,
            "latency_median_s": self.latency_median_s,
            "latency_max_s": self.latency_max_s,
            "ok_fraction": self.ok_fraction,
        }


@dataclass(frozen=True, eq=False)
class ClosedLoopResult:
    """Traces and metrics of one closed-loop run.

    Per BCR update (length k): ``time`` s, ``position`` m, ``gd_mean``, ``gd_lo``, ``gd_hi`` (the
    credible interval; NaN when there is no estimate), ``gd_true`` (prescribed GD at the position),
    ``status`` (str), ``command`` (m/s), ``mode`` ("performance"/"safety"), ``latency_s``.
    Per sensor sample (length n): ``sample_time``, ``sample_position``, ``sample_speed``.
    """

    time: np.ndarray
    position: np.ndarray
    gd_mean: np.ndarray
    gd_lo: np.ndarray
    gd_hi: np.ndarray
    gd_true: np.ndarray
    status: np.ndarray
    command: np.ndarray
    mode: np.ndarray
    latency_s: np.ndarray
    sample_time: np.ndarray
    sample_position: np.ndarray
    sample_speed: np.ndarray
    metrics: LoopMetrics
    settings: dict = field(default_factory=dict)


def _apply_faults(samples, faults: Sequence[SensorFault]):
    """(t, position, accel, speed) of a sample batch with the faults applied."""
    t = np.asarray(samples.t, dtype=float)
    pos = np.asarray(samples.position, dtype=float)
    acc = np.array(samples.accel_front, dtype=float)
    spd = np.asarray(samples.speed, dtype=float)
    keep = np.ones(t.size, dtype=bool)
    for fault in faults:
        hit = (t >= fault.start_s) & (t < fault.start_s + fault.duration_s)
        if fault.kind == "nan":
            acc[hit] = np.nan
        else:
            keep &= ~hit
    return t[keep], pos[keep], acc[keep], spd[keep]


def run_closed_loop(
    track,
    emulator,
    model=None,
    noise_std: float = 0.0,
    seed: int | None = None,
    bcr: BCRSettings | None = None,
    simplex: Simplex | None = None,
    progress: bool = False,
    *,
    calibrator=None,
    faults: Sequence[SensorFault] = (),
    check: bool = True,
) -> ClosedLoopResult:
    """Drive `model` over `track` with the BCR estimating GD and the Simplex setting the speed.

    Args:
        track: a roadgen Track (prescribed GD per segment).
        emulator: a gpmsa Emulator mapping (v, GD) to the window observation (see
            `control.shipped_emulator`).
        model: vehicle model (default `vehicle.Jackal()`); must match the emulator's metadata.
        noise_std: accelerometer noise standard deviation, m/s^2 (Test Case B: 1.0).
        seed: seed of the measurement noise.
        bcr: BCR settings (default: matching the emulator's recorded feature).
        simplex: the controller (default `Simplex()`, the paper's band and speeds).
        progress: show a tqdm bar over the track length.
        calibrator: a prepared `gpmsa.Calibrator` for `emulator` (saves preparing one per run).
        faults: injected sensor faults (NaN or dropped samples).
        check: check the emulator against model, noise, feature and track (`check_emulator`).

    Returns:
        `ClosedLoopResult` with traces and `LoopMetrics`.
    """
    model = vehicle.Jackal() if model is None else model
    simplex = Simplex() if simplex is None else simplex
    bcr = bcr_settings_for(emulator) if bcr is None else bcr
    if check:
        check_emulator(emulator, model=model, noise_std=noise_std, bcr=bcr, track=track)
    calibrator = gpmsa.Calibrator(emulator) if calibrator is None else calibrator
    estimator = BCR.from_settings(calibrator, bcr)
    sim = vehicle.Simulation(model, track, rate_hz=bcr.rate_hz, noise_std=noise_std, seed=seed)
    dt = bcr.update_every / bcr.rate_hz

    rows: list[tuple[Estimate, object]] = []
    s_t, s_pos, s_spd = [], [], []
    tic = _time.perf_counter()
    command = simplex.command(estimator.last)
    bar = tqdm(total=round(float(track.length_m)), unit="m", disable=not progress, leave=False)
    while not sim.finished:
        samples = sim.advance(dt, command.speed)
        s_t.append(np.asarray(samples.t, dtype=float))
        s_pos.append(np.asarray(samples.position, dtype=float))
        s_spd.append(np.asarray(samples.speed, dtype=float))
        estimate = estimator.update(*_apply_faults(samples, faults))
        command = simplex.command(estimate)
        rows.append((estimate, command))
        if s_pos[-1].size:
            bar.update(max(0, round(float(s_pos[-1][-1])) - bar.n))
    bar.close()
    wall = _time.perf_counter() - tic

    ests = [e for e, _ in rows]
    position = np.array([e.position for e in ests])
    gd_mean = np.array([e.gd_mean for e in ests])
    sample_time = np.concatenate(s_t) if s_t else np.empty(0)
    sample_position = np.concatenate(s_pos) if s_pos else np.empty(0)
    sample_speed = np.concatenate(s_spd) if s_spd else np.empty(0)
    latencies = np.array([e.latency_s for e in ests if e.ok])
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
        ok_fraction=float(np.mean([e.ok for e in ests])) if ests else 0.0,
    )
    seg_gd = np.array([gd for _, gd in track.segments], dtype=float)
    return ClosedLoopResult(
        time=np.array([e.time for e in ests]),
        position=position,
        gd_mean=gd_mean,
        gd_lo=np.array([e.interval[0] for e in ests]),
        gd_hi=np.array([e.interval[1] for e in ests]),
        gd_true=seg_gd[segment_index(track, position)],
        status=np.array([e.status for e in ests]),
        command=np.array([c.speed for _, c in rows]),
        mode=np.array([c.mode for _, c in rows]),
        latency_s=np.array([e.latency_s for e in ests]),
        sample_time=sample_time,
        sample_position=sample_position,
        sample_speed=sample_speed,
        metrics=metrics,
        settings={
            "noise_std": noise_std,
            "seed": seed,
            "bcr": bcr,
            "simplex": simplex,
            "faults": tuple(faults),
        },
    )
