"""Simulation: the steppable drive of the closed loop."""

import re

import numpy as np
import pytest

import roadgen
import vehicle


@pytest.fixture(scope="module")
def track():
    return roadgen.track([(4, 300), (4, 500)], seed=2)


def _drive(track, chunks, speed=1.5, model=None, **kwargs):
    sim = vehicle.Simulation(model or vehicle.Jackal(), track, **kwargs)
    out = []
    i = 0
    while not sim.finished:
        out.append(sim.advance(chunks[i % len(chunks)], speed))
        i += 1
    cat = {n: np.concatenate([getattr(s, n) for s in out]) for n in ("t", "position", "speed")}
    cat["accel"] = np.concatenate([s.accel_front_true for s in out])
    cat["measured"] = np.concatenate([s.accel_front for s in out])
    return sim, cat


def _rel_rms(a, b):
    return np.sqrt(np.mean((a - b) ** 2)) / np.sqrt(np.mean(b**2))


@pytest.mark.parametrize(("lift_off", "tol"), [(False, 1e-4), (True, 1e-2)])
def test_chunks_continue_the_integration(track, lift_off, tol):
    """Many short advances give the samples of long ones: the state carries over (a restart only
    recomputes the integrator's acceleration variable; with lift-off, small differences grow a
    little at the non-smooth contact events, still far below the step-size sensitivity)."""
    model = vehicle.Jackal(lift_off=lift_off)
    _, a = _drive(track, [0.1, 0.37, 1.0], model=model)
    _, b = _drive(track, [2.5], model=model)
    np.testing.assert_allclose(a["t"], b["t"], atol=1e-12)
    np.testing.assert_allclose(np.diff(a["t"]), 1 / 120, atol=1e-12)
    assert _rel_rms(a["accel"], b["accel"]) < tol
    assert abs(np.var(a["accel"]) / np.var(b["accel"]) - 1) < tol


def test_speed_ramps_at_the_acceleration_limit_and_stops_at_the_end(track):
    sim, a = _drive(track, [0.3], speed=2.0)
    limit = vehicle.Jackal().max_accel_mps2
    accel = np.diff(np.concatenate([[0.0], a["speed"]])) * 120
    assert np.max(accel) <= limit * (1 + 1e-9)
    assert np.isclose(a["speed"][0], limit / 120)  # from rest, one sample period at the limit
    assert np.isclose(a["speed"][-1], 2.0)
    assert a["position"][-1] <= track.length_m
    assert sim.finished and sim.position == a["position"][-1]
    assert len(sim.advance(0.5, 1.0)) == 0


def test_samples_report_noisy_and_true_acceleration(track):
    _, a = _drive(track, [0.5], noise_std=1.0, seed=3)
    noise = a["measured"] - a["accel"]
    assert abs(np.std(noise) - 1.0) < 0.1
    _, b = _drive(track, [0.5], noise_std=1.0, seed=3)
    np.testing.assert_array_equal(a["measured"], b["measured"])


def test_samples_report_the_rear_axle_with_its_own_noise(track):
    """The rear accelerometer: its noise-free value does not depend on the noise; its noise is
    N(0, 1), independent of the front one's and drawn from its own stream (the front's noise is
    that of seed 3 alone, as before the rear was read)."""
    got = {
        std: [vehicle.Simulation(vehicle.Jackal(), track, noise_std=std, seed=3).advance(3.0, 1.0)]
        for std in (0.0, 1.0)
    }
    clean, noisy = got[0.0][0], got[1.0][0]
    np.testing.assert_array_equal(noisy.accel_rear_true, clean.accel_rear_true)
    np.testing.assert_array_equal(clean.accel_rear, clean.accel_rear_true)
    assert np.std(noisy.accel_rear_true) > 0.1
    assert not np.allclose(noisy.accel_rear_true, noisy.accel_front_true)
    front_noise = noisy.accel_front - noisy.accel_front_true
    rear_noise = noisy.accel_rear - noisy.accel_rear_true
    np.testing.assert_allclose(
        front_noise, np.random.default_rng(3).normal(0.0, 1.0, front_noise.size), atol=1e-12
    )
    assert abs(np.std(rear_noise) - 1.0) < 0.1
    assert abs(np.corrcoef(rear_noise, front_noise)[0, 1]) < 0.15


def test_slowing_down_respects_the_limit(track):
    sim = vehicle.Simulation(vehicle.Jackal(), track, start_m=0.5)
    sim.advance(0.5, 2.0)
    s = sim.advance(0.05, 0.5)
    assert np.all(np.diff(np.concatenate([[2.0], s.speed])) * 120 >= -20.0 * (1 + 1e-9))
    assert sim.speed == pytest.approx(2.0 - 20.0 * 6 / 120)


@pytest.mark.parametrize(
    ("dt", "speed", "match"),
    [
        (0.5, -1.0, r"speed=-1.0 m/s is out of range: allowed \[0, 2\]"),
        (0.5, float("nan"), "speed=nan"),
        (0.5, 2.1, r"speed=2.1 m/s is out of range"),
        (0.0, 1.0, "dt=0.0"),
        (float("nan"), 1.0, "dt=nan"),
    ],
)
def test_bad_advance_raises(track, dt, speed, match):
    sim = vehicle.Simulation(vehicle.Jackal(), track)
    with pytest.raises(vehicle.VehicleError, match=match):
        sim.advance(dt, speed)


def test_bad_construction_raises(track):
    with pytest.raises(vehicle.VehicleError, match="rate_hz=0"):
        vehicle.Simulation(vehicle.Jackal(), track, rate_hz=0)
    with pytest.raises(vehicle.VehicleError, match="start_m=9"):
        vehicle.Simulation(vehicle.Jackal(), track, start_m=9.0)


def test_a_commanded_standstill_stops_the_vehicle_where_it_is(track):
    sim = vehicle.Simulation(vehicle.Jackal(), track)
    sim.advance(2.0, 1.0)
    moving = sim.position
    s = sim.advance(2.0, 0.0)  # brakes at the model's max_accel, then stands
    assert sim.speed == 0.0 and not sim.finished and len(s) == 240
    assert sim.position == pytest.approx(moving + 1.0**2 / (2 * vehicle.Jackal().max_accel_mps2))
    still = sim.advance(1.0, 0.0)
    assert np.all(still.position == sim.position) and np.all(still.speed == 0.0)
    stood = sim.position
    sim.advance(1.0, 1.0)
    assert sim.position > stood + 0.9  # and drives on


@pytest.mark.parametrize(
    ("short_of_end_m", "warm_up"),
    [(0.0087 + 0.975, True), (0.0005, False)],
    ids=["at speed", "from rest"],
)
def test_the_drive_loop_ends_when_no_sample_fits_before_the_end(short_of_end_m, warm_up):
    """Close to the end, the commanded speed's first sample may pass it although the current
    speed's would not: advance returns nothing, and finished turns True so the loop ends."""
    road = roadgen.track([(5, 400)], seed=0)
    sim = vehicle.Simulation(vehicle.Jackal(), road, start_m=road.length_m - short_of_end_m)
    if warm_up:
        assert len(sim.advance(1.0, 1.0)) == 120 and not sim.finished
    calls = 0
    while not sim.finished and calls < 10:
        sim.advance(0.5, 2.0)
        calls += 1
    assert sim.finished and calls == 1
    assert len(sim.advance(0.5, 2.0)) == 0 and sim.finished


def test_a_diverged_simulation_refuses_to_go_on():
    rough = roadgen.track([(2, 300), (3, 3e7), (5, 300)], seed=0, lead_in_m=0.5)
    sim = vehicle.Simulation(vehicle.Jackal(), rough, seed=0)
    for _ in range(3):
        sim.advance(0.5, 1.0)
    with pytest.raises(vehicle.SimulationDivergedError, match="states out of range"):
        sim.advance(0.5, 1.0)
    time, position = sim.time, sim.position
    for speed in (1.0, 0.0):  # the solver's state moved on inside the failed call: no samples
        with pytest.raises(vehicle.SimulationDivergedError, match="diverged at t = 1.5 s .*new"):
            sim.advance(1.0 / 120, speed)
    assert (sim.time, sim.position) == (time, position)


def test_a_huge_advance_while_standing_is_refused_by_the_memory_limit(track):
    """A standing vehicle never reaches the end, so dt alone sets the grid: one whose step count
    overflows a float is refused by the memory limit like any other (not an OverflowError), and
    the Simulation goes on."""
    sim = vehicle.Simulation(vehicle.Jackal(), track)
    for dt, steps in ((1e308, "inf"), (1e12, "6e+14")):
        what = re.escape(f"advance(dt={dt:g}) ({steps} steps) needs")
        with pytest.raises(vehicle.VehicleError, match=f"^{what}"):
            sim.advance(dt, 0.0)
    assert sim.time == 0.0 and len(sim.advance(0.1, 0.0)) == 12


def test_a_rate_too_low_for_any_substeps_warns_without_overflowing(track):
    """The step warning names the substeps that would do, or a higher rate_hz when none could."""
    with pytest.warns(
        vehicle.SolverStepWarning, match=r"1/\(1e-307 x 5\) s .*use a higher rate_hz"
    ):
        vehicle.Simulation(vehicle.Jackal(), track, rate_hz=1e-307)
