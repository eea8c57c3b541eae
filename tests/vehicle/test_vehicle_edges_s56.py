"""Edges of the road input and the design found in audit s56: a road shorter than the wheel that
envelopes it, and scipy's LatinHypercube before 1.15 (``seed=``, no ``rng=``)."""

import numpy as np
import pytest

import roadgen
import vehicle
from vehicle.road_input import RoadInput


@pytest.fixture(scope="module")
def short_road() -> roadgen.Profile:
    """A 0.2 m road: shorter than the HalfCar's 0.3 m wheel and its 2.6 m wheelbase."""
    return roadgen.iso8608_profile(0.2, gd=400, seed=0)


def test_road_shorter_than_the_wheel_raises_vehicle_error_naming_both(short_road):
    with pytest.raises(vehicle.VehicleError, match=r"road length 0\.198 m .*wheel_radius_m=0\.3 m"):
        RoadInput(short_road, 0.3)


@pytest.mark.parametrize(
    "run",
    [
        lambda road: vehicle.simulate(vehicle.HalfCar(), road, 1.0),
        lambda road: vehicle.Simulation(vehicle.HalfCar(), road),
        lambda road: vehicle.linear_response(vehicle.HalfCar(), road, 1.0, 5),
    ],
    ids=["simulate", "Simulation", "linear_response"],
)
def test_public_functions_refuse_a_road_shorter_than_the_wheel_with_vehicle_error(short_road, run):
    with pytest.raises(vehicle.VehicleError, match="shorter than the wheel radius"):
        run(short_road)


def test_road_as_long_as_the_wheel_is_still_enveloped():
    road = roadgen.iso8608_profile(0.3, gd=400, seed=0)  # length 0.3 m to the grid: 0.3 m wheel
    r = road.length_m
    env = RoadInput(road, r)
    np.testing.assert_array_equal(env.heights(road.x), roadgen.wheel_envelope(road, r).z)
