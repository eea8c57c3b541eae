"""Model parameter sets: description, derived quantities, bad parameters."""

import json
import math

import pytest

import vehicle
from vehicle.models import GRAVITY


@pytest.mark.parametrize("model", [vehicle.Jackal(), vehicle.HalfCar()])
def test_describe_is_json_and_names_every_parameter(model):
    d = model.describe()
    back = json.loads(json.dumps(d))
    assert back["model"] == type(model).__name__
    for name in model.__dataclass_fields__:
        assert back[name] == getattr(model, name)


def test_describe_distinguishes_tyre_parameters():
    assert vehicle.Jackal().describe() != vehicle.Jackal(tyre_stiffness_n_per_m=10e3).describe()


def test_jackal_static_loads_carry_the_weight_and_balance_the_moment():
    m = vehicle.Jackal()
    f1, f2 = m.static_tyre_loads_n
    assert math.isclose(f1 + f2, m.mass_kg * GRAVITY)
    assert math.isclose(f1 * m.b1_m, f2 * m.b2_m)
    assert math.isclose(m.wheelbase_m, 0.262)


def test_halfcar_static_loads_include_unsprung_masses():
    m = vehicle.HalfCar()
    total = m.sprung_mass_kg + m.unsprung_mass_front_kg + m.unsprung_mass_rear_kg
    assert math.isclose(sum(m.static_tyre_loads_n), total * GRAVITY)


@pytest.mark.parametrize(
    ("cls", "field", "value"),
    [
        (vehicle.Jackal, "mass_kg", -1.0),
        (vehicle.Jackal, "tyre_stiffness_n_per_m", float("nan")),
        (vehicle.Jackal, "tyre_damping_ns_per_m", -3.0),
        (vehicle.HalfCar, "b1_m", 0.0),
        (vehicle.HalfCar, "suspension_damping_front_ns_per_m", float("inf")),
    ],
)
def test_bad_parameters_raise(cls, field, value):
    with pytest.raises(vehicle.VehicleError, match=field):
        cls(**{field: value})


def test_models_are_frozen():
    with pytest.raises(AttributeError):
        vehicle.Jackal().mass_kg = 3.0


def test_a_description_makes_the_model_it_describes():
    for model in (vehicle.Jackal(mass_kg=21.5, lift_off=False), vehicle.HalfCar()):
        assert vehicle.from_description(model.describe()) == model
    assert vehicle.from_description({"model": "Jackal"}) == vehicle.Jackal()  # defaults
    for bad, match in (
        ({"model": "Tank"}, "model must be one of"),
        ({"model": "Jackal", "wings": 2}, r"Jackal has no parameter\(s\) \['wings'\]"),
        ([("model", "Jackal")], "a vehicle description is a dict"),
        ({"model": "Jackal", "mass_kg": -1.0}, "mass_kg"),
    ):
        with pytest.raises(vehicle.VehicleError, match=match):
            vehicle.from_description(bad)


@pytest.mark.parametrize(
    ("cls", "kwargs", "match"),
    [
        (vehicle.Jackal, {"b1_m": 1e308, "b2_m": 1e308}, r"^Jackal.wheelbase_m = b1_m \+ b2_m"),
        (vehicle.Jackal, {"wheels_per_axle": 10**400}, r"^Jackal.axle_stiffness_n_per_m = wheels"),
        (vehicle.Jackal, {"tyre_stiffness_n_per_m": 1e308}, r"^Jackal.axle_stiffness_n_per_m"),
        (vehicle.HalfCar, {"sprung_mass_kg": 1e308}, r"^HalfCar.static_tyre_loads_n = masses"),
    ],
)
def test_fields_whose_derived_quantities_overflow_raise(cls, kwargs, match):
    """Each field finite is not enough: a wheelbase, load or axle stiffness made of them must
    be a finite float too (not inf, NaN loads or an OverflowError later)."""
    with pytest.raises(vehicle.VehicleError, match=match + ".* overflows"):
        cls(**kwargs)


@pytest.mark.parametrize(
    ("model", "field"),
    [
        (vehicle.Jackal(pitch_inertia_kgm2=5e-324), "Jackal.pitch_inertia_kgm2=5e-324"),
        (vehicle.HalfCar(unsprung_mass_rear_kg=1e-310), "HalfCar.unsprung_mass_rear_kg=1e-310"),
    ],
)
def test_equations_of_motion_that_overflow_name_the_field(model, field):
    """A stiffness over a (tiny) mass or inertia that overflows is a VehicleError naming that
    field, not numpy's LinAlgError, wherever the linear model is used."""
    import roadgen

    road = roadgen.iso8608_profile(4.0, gd=400, seed=0)
    for call in (
        lambda: vehicle.Simulation(model, road),
        lambda: vehicle.linear_response(model, road, 1.0, 3),
    ):
        with pytest.raises(vehicle.VehicleError, match=rf"over {field} overflows"):
            call()
