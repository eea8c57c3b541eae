"""Sensor checks at their documented limits (mutation testing found each one free): the
longest stuck run wherever it lies, exactly ``max_repeats`` repeats, a signal clipped at two
values, and a quantised one."""

import numpy as np
import pytest

from control.sensor_checks import SensorLimits, longest_repeat, signal_fault


@pytest.mark.parametrize(
    ("a", "run"),
    [
        ([1.0, 1.0, 1.0, 1.0, 2.0, 3.0], 4),  # at the start
        ([1.0, 2.0, 3.0, 3.0, 3.0], 3),  # at the end
        ([1.0, 2.0, 2.0, 3.0, 2.0], 2),  # inside
        ([5.0, 5.0, 5.0], 3),  # all one value
        ([1.0, 2.0, 3.0], 1),
        ([7.0], 1),
        ([], 0),
    ],
)
def test_longest_repeat_counts_the_longest_run_wherever_it_lies(a, run):
    assert longest_repeat(np.array(a)) == run


def noise(n: int = 400, seed: int = 3) -> np.ndarray:
    return np.random.default_rng(seed).normal(-9.81, 0.5, n)


@pytest.mark.parametrize("where", [0, 200, 392])
def test_max_repeats_identical_samples_are_allowed_one_more_is_a_stuck_sensor(where):
    # (the dead and lattice checks flag 6 such samples first: off here)
    limits = SensorLimits(dead_fraction=0.0, lattice_p=0.0)
    a = noise()
    a[where : where + limits.max_repeats] = a[where]
    assert signal_fault(a, limits) == ""
    if where + limits.max_repeats < a.size:
        a[where + limits.max_repeats] = a[where]
        assert signal_fault(a, limits).startswith("stuck sensor: 9 identical")


def test_a_signal_clipped_at_two_values_is_a_fault():
    limits = SensorLimits()
    a = np.clip(noise(), -10.3, -9.3)  # ~16% of the samples pile up at each rail
    assert signal_fault(a, limits).startswith("clipped signal")


def test_a_signal_on_few_values_is_quantised():
    a = np.round(noise(), 1)  # ~30 values 0.1 apart, 20 in the first 40 samples
    a = a[:40]  # fewer distinct values than half its samples
    distinct = np.unique(a).size
    assert distinct < 20
    reason = signal_fault(a, SensorLimits(dead_fraction=0.0, lattice_p=0.0, max_same=40))
    assert reason == f"quantised or clipped signal: {distinct} distinct values in 40 samples"


def test_half_as_many_distinct_values_as_samples_is_enough_in_a_short_block():
    """A block needs min(min_distinct, n // 2) distinct values: 40 samples on 20 values pass."""
    rng = np.random.default_rng(5)
    a = rng.permutation(np.repeat(-9.81 + np.linspace(-1.0, 1.0, 20), 2))
    assert np.unique(a).size == 20 and longest_repeat(a) <= 2
    reason = signal_fault(a, SensorLimits(dead_fraction=0.0, lattice_p=0.0, max_same=40))
    assert not reason.startswith("quantised or clipped"), reason
