"""Vehicle parameter sets: the paper's half-car (eq. 1) and the rigid-axle Clearpath Jackal.

Both are frozen dataclasses in SI units. Vertical motions are measured from the static equilibrium
(gravity only enters through the static tyre loads that bound the unilateral contact force).
A field that is not a finite real number in range (an integer for ``wheels_per_axle``, True or
False for ``lift_off``) raises VehicleError naming it, as do fields whose wheelbase, static loads
or axle stiffness overflow; numpy numbers are stored as Python ones.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from vehicle import checks
from vehicle.errors import VehicleError

GRAVITY = 9.81
"""Gravitational acceleration, m/s^2."""


def _check_fields(
    model: object,
    positive: tuple[str, ...],
    non_negative: tuple[str, ...] = (),
    counts: tuple[str, ...] = (),
) -> None:
    """Check a model's fields and store them as Python floats (``counts`` as ints, ``lift_off``
    as a bool), so that ``describe()`` is JSON-able whatever numbers were given: VehicleError
    naming ``Model.field`` for a value that is not a finite real number > 0 (``positive``) or
    >= 0 (``non_negative``), an integer >= 1 (``counts``) or, for lift_off, a bool."""
    cls = type(model).__name__
    for name in positive:
        value = checks.positive(f"{cls}.{name}", getattr(model, name))
        object.__setattr__(model, name, value)
    for name in non_negative:
        value = checks.non_negative(f"{cls}.{name}", getattr(model, name))
        object.__setattr__(model, name, value)
    for name in counts:
        object.__setattr__(model, name, checks.integer(f"{cls}.{name}", getattr(model, name), 1))
    object.__setattr__(model, "lift_off", checks.flag(f"{cls}.lift_off", model.lift_off))
    derived = {"wheelbase_m": "b1_m + b2_m", "static_tyre_loads_n": "masses x GRAVITY"}
    if counts:
        derived |= {
            "axle_stiffness_n_per_m": "wheels_per_axle x tyre_stiffness_n_per_m",
            "axle_damping_ns_per_m": "wheels_per_axle x tyre_damping_ns_per_m",
        }
    for name, made_of in derived.items():
        try:
            value = getattr(model, name)
            finite = all(math.isfinite(v) for v in (value if isinstance(value, tuple) else [value]))
        except OverflowError:  # an int too large for a float
            value, finite = "too large for a float", False
        if not finite:
            raise VehicleError(
                f"{cls}.{name} = {made_of} overflows ({value}): those fields are out of range"
            )


@dataclass(frozen=True)
class HalfCar:
    """Longitudinal half-car of the paper's eq. 1 (4 DOF: y1, y2, y3, phi3), textbook passenger car.

    Attributes (SI units):
        sprung_mass_kg: m3, body mass.
        pitch_inertia_kgm2: I3, body pitch inertia about its centre of mass.
        b1_m, b2_m: distances from the body's centre of mass to the front / rear suspension.
        unsprung_mass_front_kg, unsprung_mass_rear_kg: m1, m2 (wheel, brake, axle share).
        suspension_stiffness_front_n_per_m, suspension_stiffness_rear_n_per_m: K1, K2.
        suspension_damping_front_ns_per_m, suspension_damping_rear_ns_per_m: C1, C2.
        tyre_stiffness_n_per_m: kt1 = kt2 (per axle of the planar model).
        tyre_damping_ns_per_m: tyre damping per axle; eq. 1 has none (0).
        wheel_radius_m: used to envelope the road (a wheel cannot follow bumps smaller than itself).
        max_speed_mps, max_accel_mps2: validity limits of speed and of speed changes.
        lift_off: unilateral tyre contact (the tyre force never pulls); eq. 1 is linear (False).
    """

    sprung_mass_kg: float = 600.0
    pitch_inertia_kgm2: float = 1000.0
    b1_m: float = 1.2
    b2_m: float = 1.4
    unsprung_mass_front_kg: float = 45.0
    unsprung_mass_rear_kg: float = 45.0
    suspension_stiffness_front_n_per_m: float = 25_000.0
    suspension_stiffness_rear_n_per_m: float = 22_000.0
    suspension_damping_front_ns_per_m: float = 1_500.0
    suspension_damping_rear_ns_per_m: float = 1_500.0
    tyre_stiffness_n_per_m: float = 200_000.0
    tyre_damping_ns_per_m: float = 0.0
    wheel_radius_m: float = 0.3
    max_speed_mps: float = 40.0
    max_accel_mps2: float = 5.0
    lift_off: bool = False

    def __post_init__(self) -> None:
        _check_fields(
            self,
            positive=(
                "sprung_mass_kg", "pitch_inertia_kgm2", "b1_m", "b2_m", "unsprung_mass_front_kg",
                "unsprung_mass_rear_kg", "suspension_stiffness_front_n_per_m",
                "suspension_stiffness_rear_n_per_m", "tyre_stiffness_n_per_m", "wheel_radius_m",
                "max_speed_mps", "max_accel_mps2",
            ),
            non_negative=(
                "suspension_damping_front_ns_per_m", "suspension_damping_rear_ns_per_m",
                "tyre_damping_ns_per_m",
            ),
        )  # fmt: skip

    @property
    def name(self) -> str:
        return "HalfCar"

    @property
    def wheelbase_m(self) -> float:
        """Distance between the axles, b1 + b2, m."""
        return self.b1_m + self.b2_m

    @property
    def static_tyre_loads_n(self) -> tuple[float, float]:
        """Static vertical tyre force (front, rear), N: the most a unilateral tyre can lose."""
        m3 = self.sprung_mass_kg
        front = (m3 * self.b2_m / self.wheelbase_m + self.unsprung_mass_front_kg) * GRAVITY
        rear = (m3 * self.b1_m / self.wheelbase_m + self.unsprung_mass_rear_kg) * GRAVITY
        return front, rear

    def describe(self) -> dict:
        """JSON-able record of the model: its name and every parameter."""
        return {"model": self.name, **dataclasses.asdict(self)}


@dataclass(frozen=True)
class Jackal:
    """Clearpath Jackal as a rigid-axle planar rigid body (heave, pitch) on two tyre axles.

    Mass, inertia and geometry follow the public ``jackal_description`` URDF: chassis 16.523 kg
    (pitch inertia 0.3922 kg m^2, centre of mass 0.012 m ahead of the base), four 0.477 kg wheels of
    radius 0.098 m, wheelbase 0.262 m. Whole vehicle: 18.431 kg, pitch inertia 0.425 kg m^2 about
    its centre of mass, which lies b1 = 0.120 m behind the front and b2 = 0.142 m ahead of the rear
    axle. There is no suspension: the only compliance is the tyres.

    The tyre's vertical stiffness and damping are not published. The defaults (20 kN/m and
    30 N s/m per wheel; two wheels per axle in the planar model) are those of a small pneumatic
    robot tyre deflecting ~2 mm under its ~45 N static load; they put the heave and pitch modes at
    ~9.0 and ~10.6 Hz with ~5 % damping. f depends strongly on them (>10x over plausible ranges), so
    they are parameters and every emulator records them.

    Attributes (SI units):
        mass_kg, pitch_inertia_kgm2: whole vehicle, about its centre of mass.
        b1_m, b2_m: centre of mass to front / rear axle.
        tyre_stiffness_n_per_m, tyre_damping_ns_per_m: per wheel.
        wheels_per_axle: wheels lumped into one axle of the planar model.
        wheel_radius_m: used to envelope the road.
        max_speed_mps, max_accel_mps2: Jackal limits (2.0 m/s, 20 m/s^2).
        lift_off: unilateral tyre contact (on by default: a wheel can leave the ground).
    """

    mass_kg: float = 18.431
    pitch_inertia_kgm2: float = 0.425
    b1_m: float = 0.120
    b2_m: float = 0.142
    tyre_stiffness_n_per_m: float = 20_000.0
    tyre_damping_ns_per_m: float = 30.0
    wheels_per_axle: int = 2
    wheel_radius_m: float = 0.098
    max_speed_mps: float = 2.0
    max_accel_mps2: float = 20.0
    lift_off: bool = True

    def __post_init__(self) -> None:
        _check_fields(
            self,
            positive=(
                "mass_kg", "pitch_inertia_kgm2", "b1_m", "b2_m", "tyre_stiffness_n_per_m",
                "wheel_radius_m", "max_speed_mps", "max_accel_mps2",
            ),
            non_negative=("tyre_damping_ns_per_m",),
            counts=("wheels_per_axle",),
        )  # fmt: skip

    @property
    def name(self) -> str:
        return "Jackal"

    @property
    def wheelbase_m(self) -> float:
        """Distance between the axles, b1 + b2, m."""
        return self.b1_m + self.b2_m

    @property
    def axle_stiffness_n_per_m(self) -> float:
        """Tyre stiffness of one axle (all its wheels), N/m."""
        return self.wheels_per_axle * self.tyre_stiffness_n_per_m

    @property
    def axle_damping_ns_per_m(self) -> float:
        """Tyre damping of one axle (all its wheels), N s/m."""
        return self.wheels_per_axle * self.tyre_damping_ns_per_m

    @property
    def static_tyre_loads_n(self) -> tuple[float, float]:
        """Static vertical axle load (front, rear), N."""
        w = self.mass_kg * GRAVITY
        return w * self.b2_m / self.wheelbase_m, w * self.b1_m / self.wheelbase_m

    def describe(self) -> dict:
        """JSON-able record of the model: its name and every parameter."""
        return {"model": self.name, **dataclasses.asdict(self)}


Model = HalfCar | Jackal
"""Either vehicle model."""


def from_description(description: dict) -> Model:
    """The model that ``describe()`` recorded (e.g. an emulator's metadata "vehicle"): its
    "model" name and parameters; a parameter it lacks takes the default. VehicleError for an
    unknown model or parameter."""
    if not isinstance(description, dict):
        raise VehicleError(f"a vehicle description is a dict, got {type(description).__name__}")
    kinds = {"HalfCar": HalfCar, "Jackal": Jackal}
    params = dict(description)
    name = params.pop("model", None)
    if not isinstance(name, str) or name not in kinds:
        raise VehicleError(
            f"vehicle description: model must be one of {sorted(kinds)}, got {name!r}"
        )
    fields = {f.name for f in dataclasses.fields(kinds[name])}
    unknown = sorted(set(params) - fields)
    if unknown:
        raise VehicleError(f"vehicle description: {name} has no parameter(s) {unknown}")
    return kinds[name](**params)


def check_model(model: object) -> Model:
    """Return ``model`` or raise VehicleError unless it is a HalfCar or a Jackal."""
    if not isinstance(model, (HalfCar, Jackal)):
        raise VehicleError(f"model={model!r} is not allowed: use vehicle.Jackal or vehicle.HalfCar")
    return model
