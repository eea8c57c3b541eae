"""linear_response drives only where the road is, as simulate does (session 69).

Before, it read a flat road beyond the road's end (and before its start) and returned zeros
there without a word: 10,000 samples at 1 m/s on a 21 m road gave 62 m of silence.
"""

import numpy as np
import pytest

import roadgen
import vehicle


@pytest.fixture(scope="module")
def road() -> roadgen.Profile:
    return roadgen.iso8608_profile(4.0, gd=400, seed=0, lead_in_m=0.5)


def test_a_drive_past_the_roads_end_raises_naming_the_most_samples(road):
    # 1 m/s at 120 Hz from the wheelbase (0.262 m) to the end (4.002 m): 448 samples fit
    ref = vehicle.linear_response(vehicle.Jackal(lift_off=False), road, 1.0, 448)
    assert ref.accel_front.shape == (448,) and np.var(ref.accel_front[-100:]) > 1.0
    with pytest.raises(
        vehicle.VehicleError, match=r"^n_samples=449 .* past the road's end .*<= 448"
    ):
        vehicle.linear_response(vehicle.Jackal(lift_off=False), road, 1.0, 449)


@pytest.mark.parametrize("start_m", [-1.0, 4.002, 50.0])
def test_a_start_off_the_road_raises(road, start_m):
    with pytest.raises(
        vehicle.VehicleError, match=r"^start_m=.* is out of range: allowed \[0, 4\.002\)"
    ):
        vehicle.linear_response(vehicle.Jackal(), road, 1.0, 5, start_m=start_m)


def test_a_road_no_longer_than_the_wheelbase_raises():
    short = roadgen.iso8608_profile(2.0, gd=400, seed=0)  # HalfCar: wheelbase 2.6 m
    with pytest.raises(vehicle.VehicleError, match=r"not longer than the wheelbase 2\.6 m"):
        vehicle.linear_response(vehicle.HalfCar(), short, 1.0, 5, start_m=1.0)


def test_the_validation_drive_of_simulate_still_fits(road):
    model = vehicle.Jackal(lift_off=False)
    trace = vehicle.simulate(model, road, 0.7)
    ref = vehicle.linear_response(model, road, 0.7, len(trace))
    np.testing.assert_allclose(trace.t, ref.t, atol=1e-9)
