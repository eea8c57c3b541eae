"""``run_closed_loop`` runs `check_emulator` once (before: 5 times with a recorded vehicle,
0.1-0.2 ms each, its checks of the emulator alone repeated in each), and a bad emulator and
vehicle combination still raises the error it raised first before."""

import copy
import warnings

import pytest

import control
import control.closed_loop as closed_loop
import roadgen
import vehicle
from control import PAPER_WINDOW

TRACK = roadgen.track([(6, 300), (10, 500)], seed=1)
OUTSIDE = roadgen.track([(6, 300), (10, 5000)], seed=1)  # GD 5000: outside the domain


def _emulator(**metadata):
    emu = copy.copy(control.shipped_emulator("A"))
    emu.metadata = {**emu.metadata, **metadata}
    return emu


HALF_CAR = {"vehicle": vehicle.HalfCar().describe()}
FIRST = [  # (emulator metadata, run_closed_loop keywords, track, the first error's match)
    ({**HALF_CAR, "feature": PAPER_WINDOW.to_dict()}, {"simplex": control.Simplex(v_max=2.5)},
     OUTSIDE, r"^the emulator's metadata records the feature 'log_var' of 1 output"),
    (HALF_CAR, {"simplex": control.Simplex(v_max=2.5)}, OUTSIDE, r"^model= was not given"),
    ({}, {"simplex": control.Simplex(v_max=2.5)}, OUTSIDE, r"Simplex v_max = 2.5 m/s exceeds"),
    ({}, {"simplex": control.Simplex(gd_max=5000, gd_min=250)}, OUTSIDE,
     r"track GD \[5000.0\] outside.*check=False drives it anyway"),
    ({}, {"simplex": control.Simplex(gd_max=5000, gd_min=250)}, TRACK, r"Simplex gd_max = 5000"),
]  # fmt: skip


@pytest.mark.parametrize(("meta", "kwargs", "track", "match"), FIRST)
def test_a_bad_combination_raises_the_same_first_error(meta, kwargs, track, match):
    with warnings.catch_warnings(), pytest.raises(control.ControlError, match=match):
        warnings.simplefilter("ignore", control.ControlWarning)
        control.run_closed_loop(track, _emulator(**meta), **kwargs)


def test_check_emulator_runs_once(monkeypatch):
    calls = []
    real = closed_loop.check_emulator

    def counted(*args, **kwargs):
        calls.append(kwargs)
        return real(*args, **kwargs)

    monkeypatch.setattr(closed_loop, "check_emulator", counted)
    emu = _emulator()
    with pytest.raises(control.ControlError, match="likelihood"):  # fails after the checks
        control.run_closed_loop(TRACK, emu, model=vehicle.Jackal(), likelihood=object())
    assert len(calls) == 1
