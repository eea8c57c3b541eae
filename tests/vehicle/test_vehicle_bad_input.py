"""Bad types and shapes (bools, strings, complex numbers, ragged or non-numeric arrays) raise
VehicleError naming the argument before anything is simulated; numpy integers, floats, bools
and 0-d arrays are accepted where Python ones are."""

import json
from concurrent.futures import Executor

import numpy as np
import pytest

import roadgen
import vehicle

J = vehicle.Jackal()


class Heights:
    """A road-like object (z, dx_m) that is not a roadgen Road."""

    def __init__(self, z, dx_m):
        self.z, self.dx_m = z, dx_m


class NoRunExecutor(Executor):
    """Fails the test if a campaign gets as far as submitting a run."""

    def submit(self, *args, **kwargs):
        raise AssertionError("a run was submitted")


@pytest.fixture(scope="module")
def road() -> roadgen.Profile:
    return roadgen.iso8608_profile(5.0, gd=300, seed=0, lead_in_m=0.5)


@pytest.mark.parametrize(
    ("cls", "field", "value", "match"),
    [
        (vehicle.Jackal, "mass_kg", True, r"must be a real number \(got bool\)"),
        (vehicle.Jackal, "b1_m", "0.12", r"must be a real number \(got str\)"),
        (vehicle.Jackal, "tyre_damping_ns_per_m", 1j, r"must be a real number \(got complex\)"),
        (vehicle.Jackal, "mass_kg", None, r"must be a real number \(got NoneType\)"),
        (vehicle.Jackal, "wheels_per_axle", 2.5, r"must be an integer >= 1 \(got float\)"),
        (vehicle.Jackal, "wheels_per_axle", True, r"must be an integer >= 1 \(got bool\)"),
        (vehicle.Jackal, "wheels_per_axle", 0, "is out of range: allowed integers >= 1"),
        (vehicle.Jackal, "lift_off", "no", r"must be True or False \(got str\)"),
        (vehicle.Jackal, "lift_off", 0, r"must be True or False \(got int\)"),
        (vehicle.HalfCar, "sprung_mass_kg", True, r"must be a real number \(got bool\)"),
        (vehicle.HalfCar, "lift_off", None, r"must be True or False \(got NoneType\)"),
        (vehicle.Jackal, "mass_kg", 10**400, r"<an integer of 1329 bits> is out of range"),
    ],
)
def test_model_fields_of_the_wrong_type_raise(cls, field, value, match):
    with pytest.raises(vehicle.VehicleError, match=rf"^{cls.__name__}\.{field}=.*{match}"):
        cls(**{field: value})


def test_model_fields_take_numpy_numbers_and_store_python_ones():
    m = vehicle.Jackal(mass_kg=np.int64(20), b1_m=np.float32(0.125),
                       tyre_damping_ns_per_m=np.array(30.0), wheels_per_axle=np.int64(2),
                       lift_off=np.bool_(False))  # fmt: skip
    assert m == vehicle.Jackal(mass_kg=20.0, b1_m=0.125, wheels_per_axle=2, lift_off=False)
    assert type(m.mass_kg) is float and type(m.wheels_per_axle) is int and m.lift_off is False
    assert vehicle.from_description(json.loads(json.dumps(m.describe()))) == m


@pytest.mark.parametrize(
    ("description", "match"),
    [
        ({"model": ["Jackal"]}, r"model must be one of \['HalfCar', 'Jackal'\]"),
        ({"model": "Jackal", "lift_off": "no"}, r"^Jackal.lift_off='no' must be True or False"),
        ({"model": "HalfCar", "b1_m": "1"}, r"^HalfCar.b1_m='1' must be a real number"),
    ],
)
def test_descriptions_with_bad_values_raise(description, match):
    with pytest.raises(vehicle.VehicleError, match=match):
        vehicle.from_description(description)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"rate_hz": True}, r"^rate_hz=True must be a real number \(got bool\)"),
        ({"rate_hz": "120"}, r"^rate_hz='120' must be a real number \(got str\)"),
        ({"rate_hz": np.inf}, r"^rate_hz=inf must be finite"),
        ({"noise_std": True}, r"^noise_std=True must be a real number"),
        ({"noise_std": np.nan}, r"^noise_std=nan must be finite"),
        ({"noise_std": 1e154}, r"^noise_std=1e\+154 is out of range: allowed \[0, 1e\+100\] m/s"),
        ({"start_m": "a"}, r"^start_m='a' must be a real number \(got str\)"),
        ({"start_m": True}, r"^start_m=True must be a real number"),
        ({"start_m": [1.0]}, r"^start_m=\[1.0\] must be a real number \(got list\)"),
        ({"end_m": "4"}, r"^end_m='4' must be a real number"),
        ({"end_m": 1j}, r"^end_m=1j must be a real number \(got complex\)"),
        ({"substeps": True}, r"^substeps=True must be an integer >= 1 \(got bool\)"),
        ({"substeps": 5.0}, r"^substeps=5.0 must be an integer >= 1 \(got float\)"),
        ({"substeps": 0}, r"^substeps=0 is out of range: allowed integers >= 1"),
        ({"envelope": "no"}, r"^envelope='no' must be True or False \(got str\)"),
        ({"envelope": 1}, r"^envelope=1 must be True or False \(got int\)"),
        ({"speed_of": np.array(["time", "x"])}, r"^speed_of=.* is not allowed"),
        ({"speed_of": None}, r"^speed_of=None is not allowed"),
        ({"speed": True}, r"^speed=True must be a number \(m/s\), a callable .*\(got bool\)"),
        ({"speed": "1"}, r"^speed='1' must be a number \(m/s\)"),
        ({"speed": np.array([1.0])}, r"^speed=array\(\[1.\]\) must be a number \(m/s\)"),
        ({"speed": (["0", "5"], [1, 1])}, r"^speed points must be an array of real numbers"),
        ({"speed": ([0, 5], [[1], [1, 2]])}, r"^speed values must be an array of real numbers"),
        ({"speed": ([0, 5], [1j, 1j])}, r"^speed values must be an array of real numbers"),
        ({"speed": ([0, 5], [True, True])}, r"^speed values must be an array of real numbers"),
    ],
)
def test_bad_simulate_arguments_raise_before_the_drive(road, kwargs, match):
    with pytest.raises(vehicle.VehicleError, match=match):
        vehicle.simulate(J, road, **({"speed": 1.0} | kwargs))


@pytest.mark.parametrize("speed_of", ["time", "position"])
@pytest.mark.parametrize(
    ("speed", "match"),
    [
        (lambda x: None, r"=None must be a real number \(got NoneType\)"),
        (lambda x: "1", r"='1' must be a real number \(got str\)"),
        (lambda x: 1 + 0j, r"=\(1\+0j\) must be a real number \(got complex\)"),
        (lambda x: np.ones(2), r"=array\(\[1., 1.\]\) must be a real number \(got ndarray\)"),
        (lambda x: True, r"=True must be a real number \(got bool\)"),
    ],
)
def test_speed_functions_must_return_real_numbers(road, speed_of, speed, match):
    with pytest.raises(vehicle.VehicleError, match=r"^speed\([-+.e\d]+\)" + match):
        vehicle.simulate(J, road, speed, speed_of=speed_of)


def test_a_scalar_speed_function_is_read_point_by_point(road):
    """A function that only takes one number (it branches on it) is called per point."""
    scalar = vehicle.simulate(J, road, lambda t: 1.0 if t < 1.0 else 1.5)
    vector = vehicle.simulate(J, road, lambda t: np.where(t < 1.0, 1.0, 1.5))
    np.testing.assert_array_equal(scalar.speed, vector.speed)


@pytest.mark.parametrize(
    ("road_like", "match"),
    [
        (Heights(["0"] * 9, 1.0), r"^road.z must be an array of real numbers, got dtype <U1"),
        (Heights([[0.0], [1.0, 2.0]], 1.0), r"^road.z must be an array of real numbers: "),
        (Heights(np.zeros(9), "1"), r"^road.dx_m='1' must be a real number \(got str\)"),
        (Heights(np.zeros(9), True), r"^road.dx_m=True must be a real number \(got bool\)"),
        (Heights(np.zeros(2), 1.0), r"^road.z has shape \(2,\): need \(N,\) heights with N >= 3"),
        (Heights(np.array([0.0, np.nan, 0.0]), 1.0), r"^road.z contains NaN or inf"),
        (None, r"^road=NoneType must have heights z"),
    ],
)
def test_road_like_objects_with_bad_fields_raise(road_like, match):
    with pytest.raises(vehicle.VehicleError, match=match):
        vehicle.simulate(J, road_like, 1.0, envelope=False)
    with pytest.raises(vehicle.VehicleError, match=r"^road=\w+ cannot be enveloped"):
        vehicle.simulate(J, road_like, 1.0)


def test_numpy_numbers_drive_like_python_ones(road):
    ref = vehicle.simulate(J, road, 2.0, rate_hz=120.0, noise_std=1.0, seed=1, start_m=0.5,
                           end_m=4.0, substeps=3, envelope=True)  # fmt: skip
    got = vehicle.simulate(J, road, np.float32(2.0), rate_hz=np.int64(120), noise_std=np.array(1.0),
                           seed=np.int64(1), start_m=np.float64(0.5), end_m=np.int64(4),
                           substeps=np.int64(3), envelope=np.bool_(True))  # fmt: skip
    np.testing.assert_array_equal(got.accel_front_measured, ref.accel_front_measured)
    sim = vehicle.Simulation(J, road, rate_hz=np.int64(120), start_m=np.int64(1),
                             substeps=np.int64(3), envelope=np.bool_(False))  # fmt: skip
    assert len(sim.advance(np.int64(1), np.int64(1))) == 120


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"rate_hz": "120"}, r"^rate_hz='120' must be a real number"),
        ({"rate_hz": 5e-324}, r"^rate_hz=5e-324 Hz is out of range: its sample period 1/rate"),
        ({"noise_std": True}, r"^noise_std=True must be a real number"),
        ({"noise_std": 1e308}, r"^noise_std=1e\+308 is out of range: allowed \[0, 1e\+100\]"),
        ({"start_m": "1"}, r"^start_m='1' must be a real number \(got str\)"),
        ({"start_m": None}, r"^start_m=None must be a real number"),
        ({"substeps": 2.5}, r"^substeps=2.5 must be an integer"),
        ({"envelope": None}, r"^envelope=None must be True or False"),
    ],
)
def test_bad_simulation_arguments_raise(road, kwargs, match):
    with pytest.raises(vehicle.VehicleError, match=match):
        vehicle.Simulation(J, road, **kwargs)


@pytest.mark.parametrize(
    ("dt", "speed", "match"),
    [
        (True, 1.0, r"^dt=True must be a real number \(got bool\)"),
        ("0.5", 1.0, r"^dt='0.5' must be a real number"),
        (np.inf, 1.0, r"^dt=inf must be finite"),
        (0.5, "1", r"^speed='1' must be a real number \(got str\)"),
        (0.5, True, r"^speed=True must be a real number \(got bool\)"),
        (0.5, 1j, r"^speed=1j must be a real number \(got complex\)"),
        (0.5, np.array([1.0, 1.0]), r"^speed=array\(\[1., 1.\]\) must be a real number"),
    ],
)
def test_bad_advance_arguments_raise(road, dt, speed, match):
    sim = vehicle.Simulation(J, road)
    with pytest.raises(vehicle.VehicleError, match=match):
        sim.advance(dt, speed)
    assert sim.time == 0.0


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"n": np.nan}, r"^n=nan must be an integer >= 1 \(got float\)"),
        ({"n": "5"}, r"^n='5' must be an integer >= 1"),
        ({"v_range": ("0.5", "2")}, r"^v_range\[0\]='0.5' must be a real number \(got str\)"),
        ({"v_range": (True, 2.0)}, r"^v_range\[0\]=True must be a real number \(got bool\)"),
        ({"gd_range": (200.0, 600j)}, r"^gd_range\[1\]=600j must be a real number"),
        ({"gd_range": "ab"}, r"^gd_range='ab' must be a pair \(low, high\)"),
    ],
)
def test_bad_design_arguments_raise(kwargs, match):
    with pytest.raises(vehicle.VehicleError, match=match):
        vehicle.lhs_design(**({"n": 5, "seed": 0} | kwargs))


def test_design_sizes_and_ranges_take_numpy_numbers():
    ref = vehicle.lhs_design(5, (0.5, 2.0), seed=0)
    got = vehicle.lhs_design(np.int64(5), (np.float32(0.5), np.int64(2)), seed=0)
    np.testing.assert_array_equal(got, ref)


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"design": [["1", "300"]]}, vehicle.VehicleError, r"^design must be an array of real"),
        ({"design": [[1.0, 300.0], [1.0]]}, vehicle.VehicleError, r"^design must be an array"),
        ({"design": [[1j, 300.0]]}, vehicle.VehicleError, r"^design must be an array of real"),
        ({"road_length_m": "21"}, vehicle.VehicleError, r"^road_length_m='21' must be a real"),
        ({"road_length_m": np.nan}, vehicle.VehicleError, r"^road_length_m=nan must be finite"),
        ({"dx_m": 0.0}, vehicle.VehicleError, r"^dx_m=0.0 is out of range: allowed \[1e-09, 14\]"),
        ({"dx_m": 1e-12}, vehicle.VehicleError, r"^dx_m=1e-12 is out of range: allowed \[1e-09"),
        ({"dx_m": 15.0}, vehicle.VehicleError, r"^dx_m=15.0 is out of .* road_length_m / 1.5"),
        ({"dx_m": 2e6}, vehicle.VehicleError, r"^dx_m=2000000.0 is out of range: allowed \[1e-"),
        ({"dx_m": np.inf}, vehicle.VehicleError, r"^dx_m=inf must be finite"),
        ({"dx_m": None}, vehicle.VehicleError, r"^dx_m=None must be a real number"),
        ({"lead_in_m": -1.0}, vehicle.VehicleError, r"^lead_in_m=-1.0 is out of range"),
        ({"lead_in_m": "1"}, vehicle.VehicleError, r"^lead_in_m='1' must be a real number"),
        ({"band": ("1", "2")}, vehicle.VehicleError, r"^band\[0\]='1' must be a real number"),
        ({"band": (0.0, 2.0)}, vehicle.VehicleError, r"^band=\(0.0, 2.0\) is out of range"),
        ({"band": 5}, vehicle.VehicleError, r"^band=5 must be a pair"),
        (  # the caller's name for the length (it named roadgen's length_m before session 84)
            {"band": (0.01, 1.0)},
            roadgen.RoadgenError,
            r"^road_length_m=21 is too short for band=.* needs road_length_m >= 99.996 m",
        ),
        ({"rate_hz": "120"}, vehicle.VehicleError, r"^rate_hz='120' must be a real number"),
        ({"rate_hz": np.inf}, vehicle.VehicleError, r"^rate_hz=inf must be finite"),
        ({"noise_std": "1"}, vehicle.VehicleError, r"^noise_std='1' must be a real number"),
        ({"noise_std": np.nan}, vehicle.VehicleError, r"^noise_std=nan must be finite"),
        ({"noise_std": 2e154}, vehicle.VehicleError, r"^noise_std=2e\+154 is out of range"),
        ({"window": 100.0}, vehicle.VehicleError, r"^window=100.0 must be an integer >= 2"),
        ({"substeps": True}, vehicle.VehicleError, r"^substeps=True must be an integer >= 1"),
        ({"substeps": -1}, vehicle.VehicleError, r"^substeps=-1 is out of range"),
        ({"keep_s": "1"}, vehicle.VehicleError, r"^keep_s='1' must be a real number"),
        ({"progress": "no"}, vehicle.VehicleError, r"^progress='no' must be True or False"),
        ({"cache_dir": 5}, vehicle.VehicleError, r"^cache_dir=5 must be a folder path"),
        ({"cache_dir": "a\0b"}, vehicle.VehicleError, r"^cache_dir='a\\x00b' .* a NUL byte"),
        ({"cache_dir": ""}, vehicle.VehicleError, r"^cache_dir='' must be a folder path, got the"),
        ({"executor": 5}, vehicle.VehicleError, r"^executor=5 must be None or an Executor"),
        ({"executor": "pool"}, vehicle.VehicleError, r"^executor='pool' must be None or an"),
        ({"design": [[True, 300.0]]}, vehicle.VehicleError, r"^design must be .*, got a bool"),
        ({"design": np.array([[True, True]])}, vehicle.VehicleError, r"^design .* dtype bool"),
        ({"keep_s": 0.004}, vehicle.VehicleError, r"^keep_s=0.004 s keeps 0 samples at rate_hz"),
    ],
)
def test_bad_campaign_arguments_raise_before_any_run(kwargs, error, match):
    args = {"design": np.array([[1.0, 300.0]]), "road_length_m": 21.0, "progress": False,
            "executor": NoRunExecutor()} | kwargs  # fmt: skip
    with pytest.raises(error, match=match):
        vehicle.run_campaign(**args)


@pytest.mark.parametrize("path", [5, None, ["c.npz"]])
def test_campaign_files_need_a_path(path):
    with pytest.raises(vehicle.VehicleError, match=r"^path=.* must be a file path"):
        vehicle.load_campaign(path)
    empty = vehicle.Campaign(*(np.zeros(0),) * 8, settings={})
    with pytest.raises(vehicle.VehicleError, match=r"^path=.* must be a file path"):
        empty.save(path)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"model": "car"}, r"^model='car' is not allowed"),
        ({"speed": True}, r"^speed=True must be a real number \(got bool\)"),
        ({"speed": "1"}, r"^speed='1' must be a real number"),
        ({"speed": -1.0}, r"^speed=-1.0 m/s is out of range"),
        ({"speed": 0.0}, r"^speed=0.0 m/s is out of range"),
        ({"n_samples": 2.5}, r"^n_samples=2.5 must be an integer >= 1"),
        ({"n_samples": 0}, r"^n_samples=0 is out of range: allowed integers >= 1"),
        ({"n_samples": 10**12}, r"needs about .* GiB of memory.*vehicle.checks.MAX_MEMORY_BYTES"),
        ({"rate_hz": "120"}, r"^rate_hz='120' must be a real number"),
        ({"rate_hz": -1.0}, r"^rate_hz=-1.0 is out of range: allowed \(0, inf\) Hz"),
        ({"start_m": np.nan}, r"^start_m=nan must be finite"),
        ({"start_m": "1"}, r"^start_m='1' must be a real number"),
        ({"oversample": 0}, r"^oversample=0 is out of range: allowed integers >= 1"),
        ({"oversample": 2.0}, r"^oversample=2.0 must be an integer"),
        ({"envelope": "no"}, r"^envelope='no' must be True or False"),
        ({"road": None}, r"^road=NoneType cannot be enveloped"),
    ],
)
def test_bad_linear_response_arguments_raise(road, kwargs, match):
    args = {"model": J, "road": road, "speed": 1.0, "n_samples": 10} | kwargs
    with pytest.raises(vehicle.VehicleError, match=match):
        vehicle.linear_response(**args)


def test_linear_model_refuses_what_is_not_a_model():
    with pytest.raises(vehicle.VehicleError, match=r"^model=None is not allowed"):
        vehicle.linear_model(None)
