"""One drive over a road: ``simulate`` returns a sampled ``Trace``."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from roadgen.errors import distinct_texts
from vehicle import checks
from vehicle.errors import VehicleError
from vehicle.exudyn_models import ExudynVehicle
from vehicle.kinematics import Drive, SpeedSchedule, schedule_grid
from vehicle.linear import warn_if_step_too_coarse
from vehicle.models import Model, check_model
from vehicle.road_input import RoadInput
from vehicle.sensor import add_noise, check_noise, check_rate, contact_flags

SUBSTEPS = 5
"""Default solver steps per sample: h = 1/600 s at 120 Hz (converged, docs/vehicle-models.md)."""


@dataclass(frozen=True, eq=False)
class Trace:
    """A sampled drive; arrays (n,) at t = k / rate_hz, k = 1..n (the drive starts at t = 0).

    t: s. position: front-axle road position, m (the rear axle is at position - wheelbase).
    speed: m/s. accel_front, accel_rear: noise-free vertical axle accelerations, m/s^2.
    accel_front_measured, accel_rear_measured: the accelerometer with N(0, noise_std^2) noise
    (equal to the noise-free arrays when noise_std = 0). heave: body centre-of-mass vertical
    displacement, m; pitch: rad (front up positive). contact_front, contact_rear: tyre presses on
    the road. rate_hz, noise_std: sensor settings. model: ``model.describe()``.
    """

    t: np.ndarray
    position: np.ndarray
    speed: np.ndarray
    accel_front: np.ndarray
    accel_rear: np.ndarray
    accel_front_measured: np.ndarray
    accel_rear_measured: np.ndarray
    heave: np.ndarray
    pitch: np.ndarray
    contact_front: np.ndarray
    contact_rear: np.ndarray
    rate_hz: float
    noise_std: float
    model: dict

    def __len__(self) -> int:
        return int(self.t.size)


def check_span(model: Model, road: RoadInput, start_m: float, end_m: float) -> None:
    """Raise VehicleError unless the road is longer than the wheelbase and
    0 <= start_m < end_m <= road length."""
    wb = model.wheelbase_m
    if road.length_m <= wb:
        length, wb_text = distinct_texts(road.length_m, wb)
        raise VehicleError(
            f"road length {length} m is not longer than the wheelbase {wb_text} m: "
            "allowed lengths > wheelbase"
        )
    if not (math.isfinite(start_m) and 0.0 <= start_m < road.length_m):
        end = distinct_texts(start_m, road.length_m)[1]
        raise VehicleError(f"start_m={start_m!r} is out of range: allowed [0, {end}) m")
    if not (math.isfinite(end_m) and start_m < end_m <= road.length_m + 1e-9):
        start, end = distinct_texts(end_m, start_m, road.length_m)[1:]
        raise VehicleError(f"end_m={end_m!r} is out of range: allowed ({start}, {end}] m")


def simulate(
    model: Model,
    road,
    speed: SpeedSchedule,
    rate_hz: float = 120.0,
    noise_std: float = 0.0,
    seed: int | np.integer | np.random.Generator | None = None,
    *,
    speed_of: str = "time",
    start_m: float | None = None,
    end_m: float | None = None,
    substeps: int = SUBSTEPS,
    envelope: bool = True,
) -> Trace:
    """Drive ``model`` over ``road`` and sample its axle accelerometers at ``rate_hz``.

    The vehicle starts at rest on the road with its front axle at ``start_m`` (default: the
    wheelbase, so the rear axle starts at the road's beginning; a smaller start_m puts the rear
    axle on a flat extension at the road's first height) and drives at the scheduled speed from
    t = 0. The drive ends with the last sample before the front axle passes ``end_m`` (default:
    the road's end).

    Args:
        model: HalfCar or Jackal.
        road: roadgen Profile or Track (uniform grid ``dx_m``, heights ``z``).
        speed: constant speed (m/s); a callable ``speed(t)`` (``speed_of="time"``) or
            ``speed(s)`` of the front-axle position (``speed_of="position"``), vectorised or
            scalar; or a pair of arrays ``(points, speeds)`` read the same way (linear
            interpolation, constant beyond the ends). Every speed must lie in
            (0, model.max_speed_mps]. The schedule is followed exactly.
        rate_hz: accelerometer sample rate, Hz. noise_std: accelerometer noise std, m/s^2, in
            [0, ``vehicle.sensor.MAX_NOISE_STD``] (1e100). seed: seed or Generator of the noise.
        substeps: solver steps per sample period (fixed step 1 / (rate_hz * substeps)).
        envelope: the tyres follow the road enveloped by the model's wheel radius
            (``roadgen.wheel_envelope``); False: they follow the road's raw heights.
    Returns:
        Trace. Raises VehicleError on bad input (also a drive longer than
        ``vehicle.kinematics.MAX_DRIVE_S``, 3600 s), SimulationDivergedError if the run diverges.
    """
    return _simulate(
        model, road, speed, rate_hz, noise_std, seed, speed_of=speed_of, start_m=start_m,
        end_m=end_m, substeps=substeps, envelope=envelope,
    )  # fmt: skip


def _simulate(
    model: Model,
    road,
    speed: SpeedSchedule,
    rate_hz: float,
    noise_std: float,
    seed: int | np.integer | np.random.Generator | None,
    *,
    speed_of: str,
    start_m: float | None,
    end_m: float | None,
    substeps: int,
    envelope: bool,
    step_warning: bool = True,
) -> Trace:
    """`simulate`; ``step_warning=False``: no `SolverStepWarning` (a campaign's run: the
    campaign warned once, at the user's call, and a worker's would name concurrent.futures)."""
    check_model(model)
    rate = check_rate(rate_hz)
    noise = check_noise(noise_std)
    substeps = checks.integer("substeps", substeps, 1)
    rng = np.random.default_rng(checks.seed("seed", seed))
    envelope = checks.flag("envelope", envelope)
    start = model.wheelbase_m if start_m is None else checks.real("start_m", start_m)
    end = None if end_m is None else checks.real("end_m", end_m)
    road_in = RoadInput(road, model.wheel_radius_m if envelope else None)
    end = road_in.length_m if end is None else end
    check_span(model, road_in, start, end)
    h = 1.0 / (rate * substeps)
    s, v = schedule_grid(speed, speed_of, start, end, h, model.max_speed_mps)
    n_samples = (s.size - 1) // substeps
    if s[n_samples * substeps] > end:
        n_samples -= 1
    if n_samples < 1:
        raise VehicleError(
            f"the drive from {start:.6g} m to {end:.6g} m is shorter than one sample period "
            f"(1/{rate:g} s): use a longer road or a lower speed"
        )
    if step_warning:
        warn_if_step_too_coarse(model, rate, substeps)
    drive = Drive(0.0, h, s, v)
    states = ExudynVehicle(model, road_in, drive, rate, substeps).integrate(0.0, n_samples)
    position, spd = drive.positions(states.t), drive.speeds(states.t)
    wb = model.wheelbase_m
    return Trace(
        t=states.t,
        position=position,
        speed=spd,
        accel_front=states.accel_front,
        accel_rear=states.accel_rear,
        accel_front_measured=add_noise(states.accel_front, noise, rng),
        accel_rear_measured=add_noise(states.accel_rear, noise, rng),
        heave=states.heave,
        pitch=states.pitch,
        contact_front=contact_flags(
            model, road_in, position, spd, states.z_front, states.zt_front, 0
        ),
        contact_rear=contact_flags(
            model, road_in, position - wb, spd, states.z_rear, states.zt_rear, 1
        ),
        rate_hz=rate,
        noise_std=noise,
        model=model.describe(),
    )
