"""The closed loop with the shipped emulators: traces, metrics, faults, mismatch guards."""

import warnings

import numpy as np
import pytest

import control
import roadgen
import vehicle
from control import (
    BCRSettings,
    ControlError,
    ControlWarning,
    EmulatorMismatchError,
    SensorFault,
    run_closed_loop,
)


@pytest.fixture(scope="module")
def emulator_a():
    return control.shipped_emulator("A")


@pytest.fixture(scope="module")
def calibrator_a(emulator_a):
    import gpmsa

    return gpmsa.Calibrator(emulator_a)


@pytest.fixture(scope="module")
def short_run(emulator_a, calibrator_a):
    track = roadgen.track([(25, 300), (25, 500)], seed=3)
    return track, run_closed_loop(track, emulator_a, seed=3, calibrator=calibrator_a)


def test_the_loop_drives_to_the_end_and_scores_itself(short_run):
    track, r = short_run
    assert r.sample_position[-1] > track.length_m - 0.1
    assert r.status[0] == "filling" and r.mode[0] == "safety"  # no estimate yet: safe speed
    ok = r.status == "ok"
    assert ok.sum() > 10
    assert np.all((r.command >= 1.0) & (r.command <= 2.0))
    assert np.all(r.gd_lo[ok] <= r.gd_mean[ok]) and np.all(r.gd_mean[ok] <= r.gd_hi[ok])
    # The estimate rises on the rough part (last 15 m, after the window has left the smooth part).
    smooth = ok & (r.position < 25)
    rough = ok & (r.position > 35)
    assert r.gd_mean[rough].mean() > r.gd_mean[smooth].mean() + 50
    m = r.metrics
    assert m.traversal_time_s == pytest.approx(r.sample_time[-1])
    assert {e.gd for e in m.gd_errors} == {300.0, 500.0}
    assert m.rmse(300) == pytest.approx(np.sqrt(np.mean((r.gd_mean[smooth] - 300) ** 2)), rel=0.3)
    assert 0 < m.latency_median_s < 0.05
    assert len(m.detection_delay_m) == 1
    assert set(m.as_dict()) >= {"rmse", "detection_delay_m", "fast_on_rough_m", "real_time_factor"}


def test_safety_mode_whenever_the_estimate_exceeds_gd_max(short_run):
    _, r = short_run
    ok = r.status == "ok"
    assert np.all(r.mode[ok & (r.gd_mean > 350)] == "safety")
    assert np.all(r.mode[ok & (r.gd_mean <= 350)] == "performance")
    assert np.all(r.command[r.mode == "safety"] == 1.0)


@pytest.mark.parametrize("kind", ["nan", "drop"])
def test_a_sensor_fault_means_safety_mode_and_the_loop_recovers(emulator_a, calibrator_a, kind):
    track = roadgen.track([(40, 300)], seed=5)
    fault = SensorFault(start_s=14.0, duration_s=0.5, kind=kind)
    r = run_closed_loop(track, emulator_a, seed=5, calibrator=calibrator_a, faults=[fault])
    after = r.time >= 14.0
    i_fault = np.flatnonzero(after & (r.status == "sensor_fault"))
    assert i_fault.size == 1  # reported once, with its reason
    k = i_fault[0]
    assert r.mode[k] == "safety" and r.command[k] == 1.0
    refill = r.status[k + 1 : k + 8]
    assert set(refill) == {"filling"} and np.all(r.mode[k + 1 : k + 8] == "safety")
    assert "ok" in set(r.status[k + 8 :])  # a full clean window later it estimates again


def test_a_model_other_than_the_emulators_is_refused(emulator_a):
    track = roadgen.track([(20, 300)], seed=1)
    stiffer = vehicle.Jackal(tyre_stiffness_n_per_m=30_000.0)
    with pytest.raises(EmulatorMismatchError, match="made for vehicle"):
        run_closed_loop(track, emulator_a, model=stiffer)


def test_a_track_outside_the_gd_domain_is_refused(emulator_a):
    track = roadgen.track([(20, 300), (20, 800)], seed=1)
    with pytest.raises(EmulatorMismatchError, match=r"track GD \[800.0\] outside .* \[200, 600\]"):
        run_closed_loop(track, emulator_a)


def test_a_feature_other_than_the_emulators_is_refused(emulator_a):
    track = roadgen.track([(20, 300)], seed=1)
    with pytest.raises(
        EmulatorMismatchError, match="BCR buffer = 500 but .* window_samples = 1000"
    ):
        run_closed_loop(track, emulator_a, bcr=BCRSettings(buffer=500))


def test_a_noise_mismatch_warns():
    emu = control.shipped_emulator("A")
    with pytest.warns(ControlWarning, match="noise_std = 1 m/s\\^2 in the data"):
        control.check_emulator(emu, noise_std=1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        control.check_emulator(control.shipped_emulator("B"), noise_std=1.0)


def test_shipped_emulators_record_what_the_loop_checks():
    for case, noise in (("A", 0.0), ("B", 1.0)):
        meta = control.shipped_emulator(case).metadata
        assert meta["vehicle"] == vehicle.Jackal().describe()
        assert meta["noise_std"] == noise
        assert meta["feature"]["name"] == "log_var"
        assert meta["feature"]["window_samples"] == 1000 and meta["feature"]["rate_hz"] == 120.0
        assert meta["road"]["length_m"] == 21.0
    with pytest.raises(ControlError, match="case must be one of"):
        control.shipped_emulator("C")


def test_bad_fault_settings_raise():
    with pytest.raises(ControlError, match="kind must be"):
        SensorFault(1.0, 1.0, kind="spike")
    with pytest.raises(ControlError, match="duration_s must be > 0"):
        SensorFault(1.0, 0.0)
