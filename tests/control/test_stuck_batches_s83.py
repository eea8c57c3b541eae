"""A stuck fault beside another fault read one value in one batch and another across two
(session 83, found by tests/control/test_faults_stateful_s83.py): where a stuck fault began at
a batch's first sample it held the newest reading of the batch before with every fault applied
(a scale fault listed after it too, so that the held value was scaled twice: 2.45 against
1.22 m/s^2 in one batch), and where it began inside a batch, that reading with only the faults
listed before it applied."""

import pickle

import numpy as np
import pytest

import control

T = np.arange(1, 361) / 120.0
BATCH = (T, 0.5 * T, np.sin(7.0 * T), np.full(T.size, 0.5))


def _accel(faults, cut: int) -> np.ndarray:
    inject = control.FaultInjector(faults, np.random.default_rng(0))
    parts = [inject(*(x[:cut] for x in BATCH)), inject(*(x[cut:] for x in BATCH))]
    return np.concatenate([p[2] for p in parts])


@pytest.mark.parametrize(
    "after",
    [
        control.SensorFault(0.0, 10.0, "scale", 2.0),
        control.SensorFault(0.0, 10.0, "noise", 0.1),
        control.SensorFault(0.9, 0.1, "drop"),
    ],
    ids=lambda f: f.kind,
)
def test_a_stuck_fault_holds_one_value_in_any_batches(after):
    faults = [control.SensorFault(1.0, 1.0, "stuck"), after]
    whole = control.FaultInjector(faults, np.random.default_rng(0))(*BATCH)[2]
    for cut in (60, 118, 119, 120, 200):  # sample 119 (t = 1.0 s) is the fault's first
        np.testing.assert_array_equal(_accel(faults, cut), whole)


def test_a_stuck_fault_holds_the_reading_before_it_in_either_order():
    """The stuck sensor holds its reading before the fault, 2 x the signal under a scale fault
    (listed before it, or after it, which then scales the held value)."""
    scale = control.SensorFault(0.0, 10.0, "scale", 2.0)
    stuck = control.SensorFault(1.0, 1.0, "stuck")
    for faults in ([scale, stuck], [stuck, scale]):
        for cut in (119, 200):
            acc = _accel(faults, cut)
            np.testing.assert_array_equal(acc[119:239], 2.0 * BATCH[2][118])


def test_a_copy_and_a_pickled_injector_hold_the_same_value():
    faults = [control.SensorFault(1.0, 1.0, "stuck"), control.SensorFault(0.0, 10.0, "scale", 2.0)]
    inject = control.FaultInjector(faults, np.random.default_rng(0))
    inject(*(x[:119] for x in BATCH))
    rest = tuple(x[119:] for x in BATCH)
    clone = pickle.loads(pickle.dumps(inject))
    np.testing.assert_array_equal(clone(*rest)[2], inject(*rest)[2])


def test_an_injector_pickled_before_holds_its_newest_reading():
    """One pickled before session 83 (its ``_last``: the newest reading) holds that reading."""
    stuck = [control.SensorFault(1.0, 1.0, "stuck")]
    state = control.FaultInjector(stuck, np.random.default_rng(0)).__dict__.copy()
    del state["_read"]
    state["_last"] = 0.25
    old = control.FaultInjector.__new__(control.FaultInjector)
    old.__setstate__(state)
    acc = old(*(x[119:] for x in BATCH))[2]
    np.testing.assert_array_equal(acc[:120], 0.25)
