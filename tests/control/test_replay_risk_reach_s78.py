"""The replay checks its Simplex's reach with the BCR's method, as `run_closed_loop` does:
the paper's window method (each window alone) gets the bottom of the GD domain checked too, and
an emulator that records no feature is taken (`control.compat.check_simplex`)."""

import copy
import warnings

import pytest

import control
from control.compat import bcr_settings_for
from control.robot.replay import replay_bag
from control.shipped import shipped_emulator


def _replayed_warnings(tmp_path, emu, bcr):
    """The ControlWarnings the replay gives before it reads a recording (none is there)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with pytest.raises(control.ControlError):  # no recording at that path
            replay_bag(tmp_path / "none.mcap", emu, bcr=bcr, simplex=control.Simplex(risk=0.01))
    return [str(w.message) for w in caught if issubclass(w.category, control.ControlWarning)]


def test_a_window_method_replay_checks_the_bottom_and_the_default_method_does_not(tmp_path):
    emu = shipped_emulator("A", "window")
    (message,) = _replayed_warnings(tmp_path, emu, bcr_settings_for(emu, method="window"))
    assert message.startswith("Simplex gd_max = 350 lies below 446.1, the 0.99 posterior")
    assert _replayed_warnings(tmp_path, emu, bcr_settings_for(emu)) == []


def test_check_simplex_takes_an_emulator_that_records_no_feature():
    emu = shipped_emulator("A", "window")
    bare = copy.deepcopy(emu)
    del bare.metadata["feature"]
    with pytest.raises(control.EmulatorMismatchError, match="no 'feature'"):
        control.check_emulator(bare, bcr=bcr_settings_for(emu, method="window"))
    with pytest.warns(control.ControlWarning, match="lies below 446.1"):
        control.compat.check_simplex(bare, control.Simplex(risk=0.01),
                                     bcr_settings_for(emu, method="window"))  # fmt: skip
