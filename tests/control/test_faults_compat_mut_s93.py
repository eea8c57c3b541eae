"""Mutation testing of `control.faults` and `control.compat` (session 93): the sites session 88's
tests left, each pinned by an exact, hand-computed expectation."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from _reach_cases import block_emulator
from scipy import stats
from test_compat_mutation_s88 import emulator

from control import BlockScatter, EmulatorMismatchError, SensorFault
from control.compat import (
    _risk_text,
    check_likelihood,
    recorded_vehicle_mismatch,
    top_quantile_reach,
)
from control.faults import FaultInjector

T = np.arange(10) * 0.1  # samples at 0.0, 0.1, ..., 0.9 s
ACC = np.array([1.0, -2.0, 3.0, -4.0, 5.0, -6.0, 7.0, -8.0, 9.0, -10.0])
POS = np.arange(10) * 0.2
SPEED = np.full(10, 2.0)


def _accel(*faults: SensorFault) -> np.ndarray:
    return FaultInjector(list(faults), np.random.default_rng(0))(T, POS, ACC, SPEED)[2]


def test_a_spike_fault_of_default_magnitude_spikes_every_sample():
    # magnitude defaults to 1.0: a spacing of one sample, signs alternating from -1e6
    fault = SensorFault(0.0, 0.35, "spike")  # samples 0-3
    assert fault.magnitude == 1.0
    acc = _accel(fault)
    np.testing.assert_array_equal(acc[:4], [-1e6, 1e6, -1e6, 1e6])
    np.testing.assert_array_equal(acc[4:], ACC[4:])


def test_a_vehicle_parameter_on_one_side_alone_is_named_as_none_on_the_other():
    # a parameter only the emulator records, and one only the model describes, are differences
    model = SimpleNamespace(describe=lambda: {"model": "Rover", "wheel_m": 0.1})
    emu = emulator(vehicle={"model": "Rover", "mass_kg": 20.0})
    assert recorded_vehicle_mismatch(emu, model) == (
        "the recording was simulated with another vehicle than the emulator was made for "
        '(mass_kg: recording "(none)" vs emulator 20.0, '
        'wheel_m: recording 0.1 vs emulator "(none)")'
    )


def test_the_quantile_reach_is_the_lowest_over_the_speeds():
    # likelihood sd 50 in GD at 0.5 m/s, 100 at 2 m/s: the 0.9 quantiles of the posteriors cut at
    # 600 are the half-normal ones, 600 - sd * Phi^-1(0.55): 593.72 and 587.43
    emu = block_emulator()
    emu.metadata = {
        "block_scatter": BlockScatter(
            np.array([0.5, 2.0]), np.array([0.25, 1.0])[:, None, None]
        ).to_dict()
    }
    low = 600 - 100 * stats.norm.ppf(0.55)
    assert top_quantile_reach(emu, [0.5], 0.1) == pytest.approx(
        600 - 50 * stats.norm.ppf(0.55), abs=0.02
    )
    assert top_quantile_reach(emu, [0.5, 2.0], 0.1) == pytest.approx(low, abs=0.02)
    assert top_quantile_reach(emu, [2.0, 0.5], 0.1) == pytest.approx(low, abs=0.02)


def test_a_risk_is_written_with_at_most_six_significant_digits():
    # up: low rounded up at 2, 3, ... 6 digits (0.13, 0.124, 0.1235, 0.12346, 0.123457) until it
    # is at most high
    assert _risk_text(0.1234561, 0.1234571, True) == "0.123457"
    assert _risk_text(0.12345671, 0.12345679, True) is None  # 0.123457 > high: none serves
    assert _risk_text(0.12345671, 0.12345679, False) is None  # down: 0.123456 < low


def test_a_risk_rounded_up_to_1_is_no_risk_and_more_digits_are_tried():
    # 0.995 up at 2 digits reads 1.00, not in (0, 1); at 3 digits 0.995 itself
    assert _risk_text(0.995, 1.0, True) == "0.995"


def test_a_likelihood_whose_emulator_predicts_within_1e_12_relative_is_accepted():
    # predictions 1e-15 apart, relative (a round trip through a file): the same emulator
    emu = emulator(predict=lambda v, gd: np.asarray(gd, dtype=float) / 100.0)
    twin = emulator(predict=lambda v, gd: np.asarray(gd, dtype=float) / 100.0 * (1 + 1e-15))
    check_likelihood(emu, SimpleNamespace(emulator=twin))
    off = emulator(predict=lambda v, gd: np.asarray(gd, dtype=float) / 100.0 * (1 + 1e-11))
    with pytest.raises(EmulatorMismatchError, match="domains or predictions differ"):
        check_likelihood(emu, SimpleNamespace(emulator=off))
