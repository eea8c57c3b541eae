"""A steppable drive for the closed loop: ``Simulation.advance(dt, speed)`` continues in time."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vehicle import checks
from vehicle.errors import SimulationDivergedError
from vehicle.exudyn_models import ExudynVehicle
from vehicle.kinematics import Drive, check_speed, ramp_grid
from vehicle.linear import warn_if_step_too_coarse
from vehicle.models import Model, check_model
from vehicle.road_input import RoadInput
from vehicle.sensor import add_noise, check_noise, check_rate, contact_flags
from vehicle.simulate import SUBSTEPS, check_span


@dataclass(frozen=True, eq=False)
class Samples:
    """The samples of one ``advance`` call, arrays (n,) (n = 0 once the road has ended).

    t: s. position: front-axle road position, m. accel_front: measured front-axle vertical
    acceleration (noisy if noise_std > 0), m/s^2; accel_front_true: noise-free, m/s^2.
    speed: actual speed, m/s. contact: front tyre presses on the road. accel_rear,
    accel_rear_true: the same over the rear axle (a second accelerometer; its noise is
    independent of the front one's), m/s^2.
    """

    t: np.ndarray
    position: np.ndarray
    accel_front: np.ndarray
    accel_front_true: np.ndarray
    speed: np.ndarray
    contact: np.ndarray
    accel_rear: np.ndarray
    accel_rear_true: np.ndarray

    def __len__(self) -> int:
        return int(self.t.size)


class Simulation:
    """A vehicle driving along a track, integrated on demand (the Exudyn model is built once).
    After a `SimulationDivergedError`, or a KeyboardInterrupt (Ctrl-C) or any other exception
    raised inside an ``advance`` that took its arguments, it refuses every further ``advance``
    (its solver state, or its noise streams, moved on with samples the caller never got): make
    a new one. An ``advance`` refused for its arguments (`VehicleError`) changes nothing.

    The vehicle starts at rest on the road with its front axle at ``start_m`` (the rear axle,
    a wheelbase behind, reads a flat extension at the road's first height while it is before 0).
    The commanded speed of ``advance`` is a set-point: the actual speed ramps towards it at the
    model's ``max_accel_mps2`` and it must lie in [0, max_speed_mps]: 0 stops the vehicle, which
    then stands (samples keep coming, the position does not change) until a speed is commanded.

    Args:
        model: HalfCar or Jackal. track: roadgen Track or Profile. rate_hz: accelerometer rate, Hz.
        noise_std: accelerometer noise std, m/s^2, in [0, ``vehicle.sensor.MAX_NOISE_STD``].
        seed: seed or Generator of the noise (the rear accelerometer's noise comes from a
            generator spawned from it, so the front one's noise does not depend on whether the
            rear is read).
        start_m: initial front-axle position, m, in [0, track length).
        substeps: solver steps per sample period.
        envelope: the tyres follow the track enveloped by the model's wheel radius (as in the
            campaign); False: the raw heights.

    Attributes: time (s), position (front axle, m), speed (m/s), finished (no further sample
    fits before the end of the track: at the current speed, or at the speed last commanded, whose
    ``advance`` returned no samples), end_m (the track's length, m).

    It holds a running Exudyn solver and cannot be copied or pickled (``copy.copy``,
    ``copy.deepcopy``, ``pickle`` and a process pool's arguments raise a TypeError that says
    so): build another from the same arguments where it is needed (an integer seed gives the
    same samples).
    """

    def __reduce_ex__(self, protocol):
        """Refused: a shallow copy drove one solver from two objects, and a deep copy or a
        pickle raised Exudyn's "user function which cannot be copied"."""
        raise TypeError(
            "a vehicle.Simulation cannot be copied or pickled: it holds a running Exudyn "
            "solver. Build another where it is needed, vehicle.Simulation(model, track, "
            "rate_hz, noise_std, seed, start_m) with the same arguments (an integer seed gives "
            "the same samples), or send those arguments to the other process"
        )

    def __init__(
        self,
        model: Model,
        track,
        rate_hz: float = 120.0,
        noise_std: float = 0.0,
        seed: int | np.integer | np.random.Generator | None = None,
        start_m: float = 0.0,
        *,
        substeps: int = SUBSTEPS,
        envelope: bool = True,
    ) -> None:
        self.model = check_model(model)
        self.rate_hz = check_rate(rate_hz)
        self.noise_std = check_noise(noise_std)
        substeps = checks.integer("substeps", substeps, 1)
        self._rng = np.random.default_rng(checks.seed("seed", seed))
        self._rear_rng = self._rng.spawn(1)[0]  # draws nothing from the front's stream
        start = checks.real("start_m", start_m)
        envelope = checks.flag("envelope", envelope)
        self._road = RoadInput(track, model.wheel_radius_m if envelope else None)
        self.end_m = self._road.length_m
        check_span(model, self._road, start, self.end_m)
        warn_if_step_too_coarse(self.model, self.rate_hz, substeps)
        self._substeps = substeps
        self._h = 1.0 / (self.rate_hz * substeps)
        self.time = 0.0
        self.position = start
        self.speed = 0.0
        self._at_end = False  # the last advance found no sample before the end
        self._diverged = ""  # why an advance diverged: the solver's state is then no longer valid
        self._drive = Drive(0.0, self._h, np.full(2, self.position), np.zeros(2))
        self._vehicle = ExudynVehicle(model, self._road, self._drive, self.rate_hz, substeps)

    @property
    def finished(self) -> bool:
        """True once the front axle cannot advance another sample period before the end: at the
        current speed, or as last commanded (that ``advance`` returned no samples), so that
        ``while not sim.finished: sim.advance(dt, speed)`` ends. A vehicle standing short of
        the end is finished only if the speed last commanded takes it past the end within one
        sample period."""
        moving_past = self.speed > 0 and self.position + self.speed / self.rate_hz > self.end_m
        return self._at_end or moving_past

    def advance(self, dt: float, speed: float) -> Samples:
        """Drive for ``dt`` seconds (rounded to whole sample periods, at least one) towards the
        commanded ``speed`` (m/s) and return the new samples; fewer (or none) at the track's end.
        """
        if self._diverged:  # the solver moved on inside the failed call: its state is invalid
            raise SimulationDivergedError(
                f"this Simulation diverged at t = {self.time:.4g} s ({self._diverged}); make a "
                "new one"
            )
        dt = checks.positive("dt", dt, unit="s")
        v_set = checks.real("speed", speed)
        check_speed("speed", v_set, self.model.max_speed_mps, allow_stop=True)
        # no sample lies past the end: cap the grid at the time the end is surely reached
        # (a vehicle told to stop never reaches it: dt stands, within the memory limit)
        t_end = abs(v_set - self.speed) / self.model.max_accel_mps2 + (
            max(self.end_m - self.position, 0.0) / v_set if v_set > 0 else np.inf
        )
        n_real = max(1.0, min(dt, t_end + 2.0 / self.rate_hz) * self.rate_hz)  # inf: too many
        sub = self._substeps
        checks.memory(
            checks.BYTES_PER_STEP * n_real * sub, f"advance(dt={dt:g}) ({n_real * sub:.4g} steps)"
        )
        n = round(n_real)
        s, v = ramp_grid(
            self.position, self.speed, v_set, self.model.max_accel_mps2, self._h, n * sub
        )
        n_fit = int(np.count_nonzero(s[sub::sub] <= self.end_m + 1e-9))
        self._at_end = n_fit == 0
        if n_fit == 0:
            return _empty()
        try:
            return self._drive_on(s, v, n_fit)
        except SimulationDivergedError as exc:
            self._diverged = str(exc)
            raise
        except BaseException as exc:  # Ctrl-C: the solver stopped part way, as in a divergence
            # (or the samples were lost after it moved on: the noise streams drew part of them)
            self._diverged = f"interrupted ({type(exc).__name__})"
            raise

    def _drive_on(self, s: np.ndarray, v: np.ndarray, n_fit: int) -> Samples:
        """`advance`'s solve over the ramp ``s``, ``v`` (substeps) of ``n_fit`` samples."""
        sub = self._substeps
        self._drive.set(self.time, self._h, s[: n_fit * sub + 1], v[: n_fit * sub + 1])
        states = self._vehicle.integrate(self.time, n_fit)
        k = np.arange(1, n_fit + 1) * sub
        position, spd = s[k], v[k]
        samples = Samples(
            t=states.t,
            position=position,
            accel_front=add_noise(states.accel_front, self.noise_std, self._rng),
            accel_front_true=states.accel_front,
            speed=spd,
            contact=contact_flags(
                self.model, self._road, position, spd, states.z_front, states.zt_front, 0
            ),
            accel_rear=add_noise(states.accel_rear, self.noise_std, self._rear_rng),
            accel_rear_true=states.accel_rear,
        )
        self.time, self.position, self.speed = (
            float(states.t[-1]), float(position[-1]), float(spd[-1]))  # fmt: skip
        return samples


def _empty() -> Samples:
    e = np.zeros(0)
    return Samples(e, e, e, e, e, np.zeros(0, dtype=bool), e, e)
