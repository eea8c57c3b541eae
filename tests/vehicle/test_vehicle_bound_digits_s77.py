"""A value just past its bound, or a bound computed an ulp from a round number, reads apart
from the bound in vehicle's messages (``roadgen.errors.distinct_texts``)."""

import warnings

import numpy as np
import pytest

import roadgen
import vehicle
from vehicle import campaign, checks, design, exudyn_models, kinematics, linear
from vehicle.errors import SimulationDivergedError, SolverStepWarning, VehicleError
from vehicle.road_input import RoadInput

BELOW_36 = 12 * 0.3  # 3.5999999999999996: the length of a 3.6 m road at dx_m = 0.3


@pytest.fixture(scope="module")
def road() -> roadgen.Profile:
    r = roadgen.iso8608_profile(3.6, 10.0, 0.3, seed=0, lead_in_m=0.0)
    assert r.length_m == BELOW_36
    return r


def _diverged(accel: float) -> None:
    one, zero = np.array([accel]), np.zeros(1)
    states = exudyn_models.States(zero, one, zero, zero, zero, zero, zero, zero, zero)
    exudyn_models._check_range(states, vehicle.Jackal(), zero, zero)


CASES = {
    "simulate start_m": (
        lambda r: vehicle.simulate(vehicle.Jackal(), r, 1.0, start_m=3.6),
        "start_m=3.6 is out of range: allowed [0, 3.5999999999999996) m",
    ),
    "wheel radius": (
        lambda r: RoadInput(r, wheel_radius_m=3.6),
        "road length 3.5999999999999996 m is shorter than the wheel radius wheel_radius_m=3.6 m",
    ),
    "linear_response end": (
        lambda r: vehicle.linear.linear_response(vehicle.Jackal(), r, 1.2, 360, start_m=2e-9),
        "take the front axle to 3.6000000020000003 m, past the road's end at 3.5999999999999996 m",
    ),
    "grid step": (
        lambda r: checks.grid_step("dx_m", 1.0, 1.5 - 2**-52, "road_length_m"),
        "dx_m=1.0 is out of range: allowed [1e-09, 0.9999999999999999] m",
    ),
    "design speed": (
        lambda r: design.check_design(
            np.array([[2.0, 300.0]]), vehicle.Jackal(max_speed_mps=np.nextafter(2.0, 0.0))
        ),
        "design[0] has v=2.0 m/s: allowed (0, 1.9999999999999998] m/s",
    ),
    "speed": (
        lambda r: kinematics.check_speed("speed", 2.0, 1.999999999),
        "speed=2.0 m/s is out of range: allowed (0, 1.999999999] m/s",
    ),
    "drive duration": (
        lambda r: kinematics.schedule_grid(1.0, "time", 0.0, 3600.4, 0.01, 2.0),
        "the drive takes 3600.4 s: allowed <= 3600 s",
    ),
    "campaign drive duration": (
        lambda r: campaign._check_drives(  # a drive 0.438 s past MAX_DRIVE_S
            np.array([[1.0, 300.0]]), [3600.7], vehicle.Jackal(), 0.1, 1.0
        ),
        "in 3600.438 s: simulate allows drives of <= 3600 s",
    ),
}


@pytest.mark.parametrize("name", CASES)
def test_value_reads_apart_from_its_bound(name: str, road: roadgen.Profile) -> None:
    call, text = CASES[name]
    with pytest.raises(VehicleError) as info:
        call(road)
    assert text in str(info.value)


def test_diverged_accel_reads_apart_from_its_limit() -> None:
    with pytest.raises(SimulationDivergedError) as info:
        _diverged(10004.0)
    assert "max |accel| 10004.0 m/s^2 (limit 10000)" in str(info.value)
    with pytest.raises(SimulationDivergedError) as info:
        _diverged(25000.0)  # an ordinary message: three digits, as before
    assert "max |accel| 2.5e+04 m/s^2 (limit 10000)" in str(info.value)


def test_step_warning_omega_h_reads_apart_from_its_limit() -> None:
    model = vehicle.Jackal()
    omega = linear.highest_mode_rad_s(model)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        linear.warn_if_step_too_coarse(model, omega / (linear.MAX_OMEGA_H * 1.0001), 1)
        linear.warn_if_step_too_coarse(model, omega / 0.5, 1)  # ordinary: two decimals
    texts = [str(w.message) for w in caught if issubclass(w.category, SolverStepWarning)]
    assert "(omega h = 0.2500" in texts[0] and "> 0.25)" in texts[0]
    assert "(omega h = 0.50 > 0.25)" in texts[1]
