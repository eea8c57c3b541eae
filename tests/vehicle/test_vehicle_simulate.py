"""simulate(): the trace, the sensor, speed schedules, lift-off, bad input."""

import numpy as np
import pytest

import roadgen
import vehicle


@pytest.fixture(scope="module")
def jackal_trace(rough_road):
    return vehicle.simulate(vehicle.Jackal(), rough_road, 1.5, noise_std=1.0, seed=4)


def test_trace_samples_on_the_120_hz_grid_up_to_the_road_end(jackal_trace, rough_road):
    tr = jackal_trace
    k = np.arange(1, len(tr) + 1)
    np.testing.assert_allclose(tr.t, k / 120.0, atol=1e-12)
    wb = vehicle.Jackal().wheelbase_m
    np.testing.assert_allclose(tr.position, wb + 1.5 * tr.t, atol=1e-9)
    assert tr.position[-1] <= rough_road.length_m
    assert tr.position[-1] + 1.5 / 120 > rough_road.length_m
    np.testing.assert_allclose(tr.speed, 1.5)
    for name in ("accel_rear", "accel_front_measured", "heave", "pitch", "contact_front"):
        assert getattr(tr, name).shape == tr.t.shape


def test_noise_is_standard_normal_and_seeded(jackal_trace, rough_road):
    tr = jackal_trace
    noise = tr.accel_front_measured - tr.accel_front
    assert abs(np.std(noise) - 1.0) < 4 * (1 / np.sqrt(2 * noise.size))
    assert abs(np.mean(noise)) < 4 / np.sqrt(noise.size)
    again = vehicle.simulate(vehicle.Jackal(), rough_road, 1.5, noise_std=1.0, seed=4)
    np.testing.assert_array_equal(again.accel_front_measured, tr.accel_front_measured)
    other = vehicle.simulate(vehicle.Jackal(), rough_road, 1.5, noise_std=1.0, seed=5)
    assert not np.array_equal(other.accel_front_measured, tr.accel_front_measured)
    np.testing.assert_array_equal(other.accel_front, tr.accel_front)


def test_no_noise_means_measured_equals_true(rough_road):
    tr = vehicle.simulate(vehicle.Jackal(), rough_road, 1.0)
    np.testing.assert_array_equal(tr.accel_front_measured, tr.accel_front)


def test_flat_road_gives_no_acceleration(flat_road):
    tr = vehicle.simulate(vehicle.Jackal(), flat_road, 2.0)
    assert np.max(np.abs(tr.accel_front)) < 1e-5
    assert tr.contact_front.all() and tr.contact_rear.all()


def test_rougher_and_faster_shake_more(rough_road):
    slow = vehicle.simulate(vehicle.Jackal(), rough_road, 0.6)
    fast = vehicle.simulate(vehicle.Jackal(), rough_road, 1.8)
    assert np.var(fast.accel_front) > 1.5 * np.var(slow.accel_front)
    smooth = roadgen.iso8608_profile(12.0, gd=100, seed=3, lead_in_m=1.0)
    tr = vehicle.simulate(vehicle.Jackal(), smooth, 0.6)
    # same seed, same shape: heights scale with sqrt(GD), so bilateral f would scale with GD
    assert np.var(tr.accel_front) < 0.5 * np.var(slow.accel_front)


def test_lift_off_caps_the_tyre_force_and_changes_the_response():
    road = roadgen.iso8608_profile(8.0, gd=600, seed=1, lead_in_m=0.5)
    uni = vehicle.simulate(vehicle.Jackal(), road, 2.0)
    bi = vehicle.simulate(vehicle.Jackal(lift_off=False), road, 2.0)
    assert 0.02 < 1 - uni.contact_front.mean() < 0.8  # the wheel leaves the ground sometimes
    assert 1 - bi.contact_front.mean() > 0.02  # a bilateral tyre would have pulled there
    assert np.var(uni.accel_front) < 0.9 * np.var(bi.accel_front)


def test_envelope_lowers_the_response(rough_road):
    """The wheel bridges short bumps; bilateral, so lift-off cannot blur the comparison."""
    model = vehicle.Jackal(lift_off=False)
    env = vehicle.simulate(model, rough_road, 1.5)
    raw = vehicle.simulate(model, rough_road, 1.5, envelope=False)
    assert np.var(env.accel_front) < np.var(raw.accel_front)


def test_speed_schedules_of_time_position_and_arrays_agree(rough_road):
    wb = vehicle.Jackal().wheelbase_m
    by_time = vehicle.simulate(vehicle.Jackal(), rough_road, lambda t: 0.8 + 0.1 * t)
    arrays = vehicle.simulate(vehicle.Jackal(), rough_road, ([0.0, 100.0], [0.8, 10.8]))
    np.testing.assert_allclose(by_time.speed, 0.8 + 0.1 * by_time.t, rtol=1e-9)
    np.testing.assert_allclose(by_time.position, wb + 0.8 * by_time.t + 0.05 * by_time.t**2)
    np.testing.assert_allclose(arrays.accel_front, by_time.accel_front, atol=1e-6)
    # a schedule of position: v(s) = 1 + 0.05 (s - wb) passes each point at the analytic time
    by_pos = vehicle.simulate(
        vehicle.Jackal(), rough_road, lambda s: 1.0 + 0.05 * (s - wb), speed_of="position"
    )
    t_exact = np.log(1 + 0.05 * (by_pos.position - wb)) / 0.05
    np.testing.assert_allclose(by_pos.t, t_exact, atol=1e-4)
    np.testing.assert_allclose(by_pos.speed, 1.0 + 0.05 * (by_pos.position - wb), atol=1e-6)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"speed": 0.0}, "speed=0.0"),
        ({"speed": -1.0}, "speed=-1.0"),
        ({"speed": float("nan")}, "speed=nan"),
        ({"speed": 2.5}, r"allowed \(0, 2\] m/s"),
        ({"speed": lambda t: 1.0 - t}, "speed="),
        ({"speed": 1.0, "rate_hz": 0.0}, "rate_hz=0.0"),
        ({"speed": 1.0, "rate_hz": -120.0}, "rate_hz=-120.0"),
        ({"speed": 1.0, "noise_std": -1.0}, "noise_std=-1.0"),
        ({"speed": 1.0, "start_m": -0.1}, "start_m=-0.1"),
        ({"speed": 1.0, "end_m": 99.0}, "end_m=99.0"),
        ({"speed": 1.0, "speed_of": "distance"}, "speed_of='distance'"),
    ],
)
def test_bad_input_raises(rough_road, kwargs, match):
    with pytest.raises(vehicle.VehicleError, match=match):
        vehicle.simulate(vehicle.Jackal(), rough_road, **kwargs)


def test_road_shorter_than_wheelbase_raises():
    road = roadgen.iso8608_profile(0.2, gd=300, seed=0)
    with pytest.raises(vehicle.VehicleError, match="shorter than the wheelbase|not longer"):
        vehicle.simulate(vehicle.Jackal(), road, 1.0)


def test_road_without_heights_raises():
    with pytest.raises(vehicle.VehicleError, match="road="):
        vehicle.simulate(vehicle.Jackal(), [0.0, 1.0], 1.0, envelope=False)


def test_a_diverging_run_raises():
    road = roadgen.iso8608_profile(5.0, gd=1e9, seed=0, lead_in_m=0.5)  # ~20 m bumps
    with pytest.raises(vehicle.SimulationDivergedError, match="out of range"):
        vehicle.simulate(vehicle.Jackal(), road, 2.0)


def test_halfcar_lift_off_option():
    road = roadgen.iso8608_profile(30.0, gd=5000, seed=1, lead_in_m=2.0)
    uni = vehicle.simulate(vehicle.HalfCar(lift_off=True), road, 30.0)
    bi = vehicle.simulate(vehicle.HalfCar(), road, 30.0)
    assert 1 - bi.contact_front.mean() > 0.05
    assert np.var(uni.accel_front) < 0.8 * np.var(bi.accel_front)


def test_unknown_model_raises(rough_road):
    with pytest.raises(vehicle.VehicleError, match="model='car'"):
        vehicle.simulate("car", rough_road, 1.0)


@pytest.mark.parametrize(
    ("model", "speed"),
    [(vehicle.Jackal(), 2.0), (vehicle.HalfCar(), 10.0)],
    ids=["Jackal", "HalfCar"],
)
@pytest.mark.parametrize(
    ("length", "height"),
    [(3.0, lambda x: np.full_like(x, 1.5)), (60.0, lambda x: 0.03 * x)],
    ids=["1.5 m offset", "3% grade"],
)
def test_a_road_far_above_zero_is_no_divergence(model, speed, length, height):
    """The divergence bound is on the displacement from the road under the wheels, not from 0:
    the body follows a road 1.5 m up, or 1.8 m up a 60 m grade, to its static equilibrium."""
    x = np.arange(0.0, length + 0.003, 0.006)
    road = roadgen.Road(x=x, z=height(x), dx_m=0.006)
    tr = vehicle.simulate(model, road, speed)
    assert tr.position[-1] > length - speed / 120
    under_body = height(tr.position - model.b1_m)
    assert np.max(np.abs(tr.heave - under_body)[len(tr) // 2 :]) < 0.02


def test_a_solver_step_too_coarse_for_the_stiffest_mode_warns_naming_the_substeps(rough_road):
    """Tyres 50x the default put a mode at 75 Hz: at 5 substeps the acceleration's variance
    came out half the true one, silently. The default models sit well inside the limit."""
    import warnings

    stiff = vehicle.Jackal(tyre_stiffness_n_per_m=1e6, lift_off=False)
    with pytest.warns(vehicle.SolverStepWarning, match=r"\(74.86 Hz\).*use substeps >= 16"):
        vehicle.simulate(stiff, rough_road, 1.0)
    with pytest.warns(vehicle.SolverStepWarning, match="use substeps >= 16"):
        vehicle.Simulation(stiff, rough_road)
    with warnings.catch_warnings():
        warnings.simplefilter("error", vehicle.SolverStepWarning)
        vehicle.simulate(stiff, rough_road, 1.0, substeps=16)
        for model in (vehicle.Jackal(), vehicle.HalfCar()):
            vehicle.simulate(model, rough_road, 1.0)


def test_the_largest_noise_std_keeps_the_measured_variance_finite(rough_road):
    """noise_std up to vehicle.MAX_NOISE_STD: f, the measured accelerations' variance, stays
    finite (1e154 overflowed it to inf, and 1e308 the samples themselves)."""
    limit = vehicle.sensor.MAX_NOISE_STD
    trace = vehicle.simulate(vehicle.Jackal(), rough_road, 2.0, noise_std=limit, seed=0)
    for accel in (trace.accel_front_measured, trace.accel_rear_measured):
        assert np.all(np.isfinite(accel)) and np.isfinite(np.var(accel))
    with pytest.raises(vehicle.VehicleError, match=r"^noise_std=1e\+154 is out of range"):
        vehicle.simulate(vehicle.Jackal(), rough_road, 2.0, noise_std=1e154)
