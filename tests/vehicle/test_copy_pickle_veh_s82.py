"""Copies of the vehicle's objects (session 82): ``copy.copy`` of a Simulation drove one Exudyn
solver from two objects (the copy's samples moved the original's next ones), and
``copy.deepcopy`` or ``pickle`` raised Exudyn's "user function which cannot be copied"; the
records of arrays (Samples, Trace, Campaign) raised "truth value of an array is ambiguous"
from ``==`` against a copy, and TypeError from ``hash``."""

import copy
import pickle

import numpy as np
import pytest

import roadgen
import vehicle

REFUSED = r"a vehicle\.Simulation cannot be copied or pickled: it holds a running Exudyn solver"


def test_a_simulation_refuses_to_be_copied_or_pickled_naming_the_remedy():
    sim = vehicle.Simulation(vehicle.Jackal(), roadgen.track([(5, 300)], seed=1), seed=1)
    sim.advance(0.1, 0.5)
    for how in (copy.copy, copy.deepcopy, lambda s: pickle.dumps(s, 2),
                lambda s: pickle.dumps(s, pickle.HIGHEST_PROTOCOL)):  # fmt: skip
        with pytest.raises(TypeError, match=REFUSED) as caught:
            how(sim)
        assert "same arguments" in str(caught.value)
    again = vehicle.Simulation(vehicle.Jackal(), roadgen.track([(5, 300)], seed=1), seed=1)
    again.advance(0.1, 0.5)
    a, b = sim.advance(0.1, 0.5), again.advance(0.1, 0.5)  # the remedy: the same samples
    np.testing.assert_array_equal(a.accel_front, b.accel_front)


def test_records_of_arrays_compare_by_identity_and_hash():
    one = np.ones(2)
    samples = vehicle.Samples(*(np.arange(3.0),) * 8)
    camp = vehicle.Campaign(v=one, gd=one, seed=[1, 2], f_full=one, f_window=one,
                            f_full_noisy=one, f_window_noisy=one, status=["ok", "ok"],
                            settings={})  # fmt: skip
    for record in (samples, camp):
        twin = pickle.loads(pickle.dumps(record))
        assert record == record and record != twin and len({record, twin, copy.copy(record)}) == 3
    assert vehicle.Trace.__eq__ is object.__eq__ and vehicle.Trace.__hash__ is object.__hash__
