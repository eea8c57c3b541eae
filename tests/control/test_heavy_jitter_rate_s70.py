"""An IMU's rate under heavy stamp jitter (session 70).

Before: the nominal rate was the median step, which jitter biases: a 120 Hz IMU whose stamps
jitter by sd 4 ms read 124.6 Hz with its stamps in order (113 Hz without), and the replay
refused it with a `BagError` about resampling from 124.8 Hz. Now, where the steps spread
widely (`condition.HEAVY_JITTER_STEPS`), the rate is the mean step, which jitter does not
bias: the IMU is taken for 120 Hz and fed as recorded, with the note that its stamps were not
re-stamped (the BCR then reports their steps as sensor faults). Exact and lightly jittered
stamps keep the median step, bit for bit."""

import numpy as np
import pytest

import roadgen
import vehicle
from control.robot import condition

P = 1 / 120


def _stamps(sd_s, n=4800, seed=0, drop=()):
    true = 50.0 + np.arange(n) * P * (1 + 40e-6)
    t = true + np.random.default_rng(seed).normal(0.0, sd_s, n)
    return np.delete(t, list(drop))


def _median_step(t):
    step = np.diff(t)
    return float(np.median(step[step > 0]))


@pytest.mark.parametrize("sd_ms", [3.0, 4.0, 6.0])
def test_heavy_jitter_reads_the_clocks_rate(sd_ms):
    t = _stamps(sd_ms * 1e-3)
    for stamps in (np.sort(t), t):  # in stamp order (as the replay orders them) or not
        assert abs(1 / _median_step(stamps) / 120 - 1) > 0.02 or sd_ms == 3.0  # before
        assert 1 / condition.nominal_period(stamps) == pytest.approx(120, rel=1e-3)
    paused = np.concatenate([np.sort(t), np.sort(t)[-1] + 30 + np.sort(t) - t.min()])
    assert 1 / condition.nominal_period(paused) == pytest.approx(120, rel=1e-3)  # a pause
    stepped = np.sort(t)
    stepped[2400:] -= 20.0  # a clock step back
    assert 1 / condition.nominal_period(stepped) == pytest.approx(120, rel=1e-3)


@pytest.mark.parametrize("sd_ms", [0.0, 0.2, 1.0, 1.39, 2.0])
def test_exact_and_light_jitter_keep_the_median_step(sd_ms):
    for t in (_stamps(sd_ms * 1e-3), _stamps(sd_ms * 1e-3, drop=range(100, 4800, 50))):
        t = np.sort(t)
        assert condition.nominal_period(t) == _median_step(t)
    exact_125 = np.delete(np.arange(4800) / 125, range(0, 4800, 25))  # 4 % dropped
    assert condition.nominal_period(exact_125) == _median_step(exact_125)


def test_a_120_hz_imu_with_4_ms_of_jitter_replays_as_recorded(tmp_path, emulator_b, likelihood_b):
    pytest.importorskip("rosbags")
    pytest.importorskip("mcap")
    from control.robot import replay_bag, write_sensor_bag

    trace = vehicle.simulate(
        vehicle.Jackal(), roadgen.track([(6, 400)], seed=2), 1.5, noise_std=1.0, seed=2
    )
    t = trace.t + 1.0
    jittered = t + np.random.default_rng(1).normal(0.0, 4e-3, t.size)
    bag = write_sensor_bag(
        tmp_path / "bag", jittered, trace.accel_front_measured, t, trace.position, trace.speed
    )
    # before: BagError "gives no sample at 120 Hz: resampling its 124.8 Hz needs runs ..."
    r = replay_bag(bag, emulator_b, likelihood=likelihood_b)
    assert not r.resampling.resampled and r.resampling.rate_in_hz == pytest.approx(120, rel=2e-3)
    assert r.imu.rate_hz == pytest.approx(120, rel=2e-3)
    assert "were not re-stamped" in r.imu.note and not r.restamping.restamped
    assert set(r.status) == {"sensor_fault"}  # the stamps as recorded: steps read as faults
