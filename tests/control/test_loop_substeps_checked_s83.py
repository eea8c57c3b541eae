"""run_closed_loop checks substeps= with its other arguments and records it as an int (session
83 review). Before: a bad substeps was named only once the emulator had been checked and the
BCR built (an emulator's error came first), and ``settings["substeps"]`` held the value as
given (np.int64(6))."""

import numpy as np
import pytest

import control
import roadgen
import vehicle


def test_a_bad_substeps_is_named_before_the_emulator_is_read():
    track = roadgen.track([(3.0, 300.0)], seed=1)
    with pytest.raises(vehicle.VehicleError, match="substeps=0 is out of range"):
        control.run_closed_loop(track, object(), seed=1, substeps=0)


class _Built(Exception):
    """Raised where the loop builds its simulation."""


def test_substeps_goes_on_as_an_int(monkeypatch):
    given = []

    def simulation(*args, substeps, **kwargs):
        given.append(substeps)  # (settings["substeps"] records the same value)
        raise _Built

    monkeypatch.setattr(vehicle, "Simulation", simulation)
    track = roadgen.track([(3.0, 300.0)], seed=1)
    with pytest.raises(_Built):
        control.run_closed_loop(
            track, control.shipped_emulator("A"), vehicle.Jackal(), seed=1, substeps=np.int64(6)
        )
    assert type(given[0]) is int and given[0] == 6
