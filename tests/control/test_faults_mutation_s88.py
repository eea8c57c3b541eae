"""Mutation testing of `control.faults` (session 88): each fault kind's effect on a small batch,
sample by sample, and the edges of a fault's span and of its settings."""

from __future__ import annotations

import numpy as np
import pytest

from control import ControlError, SensorFault
from control.faults import FaultInjector

T = np.arange(10) * 0.1  # samples at 0.0, 0.1, ..., 0.9 s
ACC = np.array([1.0, -2.0, 3.0, -4.0, 5.0, -6.0, 7.0, -8.0, 9.0, -10.0])
POS = np.arange(10) * 0.2
SPEED = np.full(10, 2.0)


def apply(*faults, seed=0, t=T, acc=ACC):
    return FaultInjector(list(faults), np.random.default_rng(seed))(t, POS, acc, SPEED)


def test_a_fault_hits_from_its_start_up_to_but_not_at_its_end():
    t, pos, acc, spd = apply(SensorFault(0.2, 0.3, "nan"))  # [0.2, 0.5): samples 2, 3, 4
    np.testing.assert_array_equal(np.isnan(acc), np.isin(np.arange(10), [2, 3, 4]))
    np.testing.assert_array_equal(t, T)
    np.testing.assert_array_equal(pos, POS)
    np.testing.assert_array_equal(spd, SPEED)


@pytest.mark.parametrize(
    ("kind", "magnitude", "hit"),
    [
        ("scale", 0.5, [0.5, -1.0, 1.5]),
        ("clip", 2.5, [1.0, -2.0, 2.5]),
        ("quantize", 2.0, [0.0, -2.0, 4.0]),  # round half to even: 0.5 -> 0, 1.5 -> 2
        ("stuck", 1.0, [1.0, 1.0, 1.0]),  # the first reading, none before
    ],
)
def test_each_deterministic_fault_changes_exactly_the_samples_it_hits(kind, magnitude, hit):
    _, _, acc, _ = apply(SensorFault(0.0, 0.25, kind, magnitude))  # samples 0, 1, 2
    np.testing.assert_array_equal(acc[:3], hit)
    np.testing.assert_array_equal(acc[3:], ACC[3:])


def test_a_stuck_fault_holds_the_reading_before_it():
    _, _, acc, _ = apply(SensorFault(0.35, 0.3, "stuck"))  # samples 4, 5, 6 hold sample 3
    np.testing.assert_array_equal(acc, [1, -2, 3, -4, -4, -4, -4, -8, 9, -10])


def test_drop_removes_the_samples_it_hits_from_every_array():
    t, pos, acc, spd = apply(SensorFault(0.15, 0.2, "drop"))  # samples 2, 3
    keep = [0, 1, 4, 5, 6, 7, 8, 9]
    np.testing.assert_array_equal(t, T[keep])
    np.testing.assert_array_equal(pos, POS[keep])
    np.testing.assert_array_equal(acc, ACC[keep])
    np.testing.assert_array_equal(spd, SPEED[keep])


def test_time_and_position_faults_touch_their_own_array_alone():
    t, pos, acc, _ = apply(SensorFault(0.15, 0.2, "time_nan"))
    np.testing.assert_array_equal(np.isnan(t), np.isin(np.arange(10), [2, 3]))
    np.testing.assert_array_equal(acc, ACC)
    t, pos, acc, _ = apply(SensorFault(0.15, 0.2, "position_nan"))
    np.testing.assert_array_equal(np.isnan(pos), np.isin(np.arange(10), [2, 3]))
    np.testing.assert_array_equal(t, T)
    np.testing.assert_array_equal(acc, ACC)


def test_spikes_alternate_in_sign_every_spacing_samples_from_the_faults_first():
    _, _, acc, _ = apply(SensorFault(0.0, 1.0, "spike", 3.0))
    expected = ACC.copy()
    expected[[0, 3, 6, 9]] = [-1e6, 1e6, -1e6, 1e6]
    np.testing.assert_array_equal(acc, expected)
    _, _, acc, _ = apply(SensorFault(0.0, 1.0, "spike", 2.6))  # rounded to 3
    np.testing.assert_array_equal(acc, expected)
    # counted across batches: the second batch goes on where the first stopped
    inject = FaultInjector([SensorFault(0.0, 1.0, "spike", 3.0)], np.random.default_rng(0))
    first = inject(T[:4], POS[:4], ACC[:4], SPEED[:4])[2]
    second = inject(T[4:], POS[4:], ACC[4:], SPEED[4:])[2]
    np.testing.assert_array_equal(np.concatenate([first, second]), expected)


def test_noise_adds_the_generators_normal_draws_of_sd_magnitude():
    _, _, acc, _ = apply(SensorFault(0.0, 0.25, "noise", 0.3), seed=7)
    draws = np.random.default_rng(7).normal(0.0, 0.3, 3)
    np.testing.assert_array_equal(acc[:3], ACC[:3] + draws)
    np.testing.assert_array_equal(acc[3:], ACC[3:])


def test_a_fault_after_or_before_the_batch_leaves_it_as_it_was():
    for fault in (SensorFault(1.0, 1.0, "nan"), SensorFault(0.0, 1e-9, "nan", 1.0)):
        _, _, acc, _ = apply(fault, t=T + 0.05)
        np.testing.assert_array_equal(acc, ACC)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"start_s": -1e-9, "duration_s": 1.0}, "start_s must be >= 0"),
        ({"start_s": 0.0, "duration_s": 0.0}, "duration_s must be > 0"),
        ({"start_s": 0.0, "duration_s": 1.0, "magnitude": 0.0}, "magnitude must be finite and > 0"),
        ({"start_s": 0.0, "duration_s": 1.0, "kind": "spike", "magnitude": 0.99}, "spacing >= 1"),
    ],
)
def test_settings_just_outside_their_range_are_refused(kwargs, match):
    with pytest.raises(ControlError, match=match):
        SensorFault(**kwargs)


def test_settings_at_the_edge_of_their_range_are_accepted():
    SensorFault(0.0, 1e-9)
    SensorFault(0.0, 1.0, "spike", 1.0)
    SensorFault(0.0, 1.0, "scale", 1e-300)


def test_a_long_spacing_is_counted_as_given_up_to_the_cap():
    n = 500
    t, acc = np.arange(n) * 0.01, np.zeros(n)
    inject = FaultInjector([SensorFault(0.0, 10.0, "spike", 200.0)], np.random.default_rng(0))
    out = inject(t, np.zeros(n), acc, np.zeros(n))[2]
    np.testing.assert_array_equal(np.flatnonzero(out), [0, 200, 400])
    np.testing.assert_array_equal(out[[0, 200, 400]], [-1e6, 1e6, -1e6])
    huge = FaultInjector([SensorFault(0.0, 10.0, "spike", 1e30)], np.random.default_rng(0))
    np.testing.assert_array_equal(np.flatnonzero(huge(t, np.zeros(n), acc, np.zeros(n))[2]), [0])


def test_a_spacing_of_one_spikes_every_sample_with_alternating_signs():
    for spacing in (1.0, 1.4):  # 1.4 rounds to 1
        _, _, acc, _ = apply(SensorFault(0.0, 0.35, "spike", spacing))  # samples 0-3
        np.testing.assert_array_equal(acc[:4], [-1e6, 1e6, -1e6, 1e6])
        np.testing.assert_array_equal(acc[4:], ACC[4:])
