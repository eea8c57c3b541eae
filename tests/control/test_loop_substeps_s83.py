"""The advice of a stiff robot's SolverStepWarning ("use substeps >= N") can be followed from
the closed loop: `run_closed_loop(substeps=)` passes the solver's steps per sample to the
simulation (before, it had no such option)."""

import re
import warnings

import pytest

import control
import roadgen
import vehicle


def test_the_solver_warnings_substeps_followed_in_the_loop_silence_it():
    stiff = vehicle.Jackal(tyre_stiffness_n_per_m=1e6, lift_off=False)
    track = roadgen.track([(3.0, 300.0)], seed=1)
    emulator = control.shipped_emulator("A")
    with pytest.warns(vehicle.SolverStepWarning) as got:
        control.run_closed_loop(track, emulator, model=stiff, seed=1, check=False)
    need = int(re.search(r"substeps >= (\d+)", str(got[0].message)).group(1))
    with warnings.catch_warnings():
        warnings.simplefilter("error", vehicle.SolverStepWarning)
        result = control.run_closed_loop(
            track, emulator, model=stiff, seed=1, check=False, substeps=need
        )
    assert result.time.size > 0 and result.settings["substeps"] == need


def test_a_bad_substeps_is_named():
    track = roadgen.track([(3.0, 300.0)], seed=1)
    with pytest.raises(ValueError, match="substeps"):
        control.run_closed_loop(track, control.shipped_emulator("A"), seed=1, substeps=0)
