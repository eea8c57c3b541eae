"""float32 time stamps too coarse for a 120 Hz stream are refused by name (they read as a timing
fault in every block, a sensor_fault whose reason did not name the type)."""

import numpy as np
import pytest

import control
from control.bcr import STAMP_RESOLUTION_S, _samples
from control.errors import ControlError
from control.shipped import shipped_emulator


@pytest.mark.parametrize("start", [1.7e9, 20_000.0])
def test_float32_stamps_coarser_than_a_millisecond_are_refused(start):
    t = (start + np.arange(240) / 120.0).astype(np.float32)
    with pytest.raises(ControlError, match=r"t is float32 and reaches .* s, where its stamps are "
                                           r".* s apart \(coarser than 0.001 s\)"):  # fmt: skip
        _samples("t", t)


def test_fine_float32_stamps_and_float32_samples_are_taken_at_their_values():
    t = (100.0 + np.arange(240) / 120.0).astype(np.float32)  # spacing 7.6e-6 s there
    assert np.spacing(np.float32(100.0)) < STAMP_RESOLUTION_S
    np.testing.assert_array_equal(_samples("t", t), t.astype(np.float64))
    big = (1.7e9 + np.arange(4)).astype(np.float32)  # not stamps: taken as given
    np.testing.assert_array_equal(_samples("accel", big), big.astype(np.float64))
    nan = np.array([np.nan, np.nan], dtype=np.float32)  # missing stamps: faults, not errors
    assert np.isnan(_samples("t", nan)).all()


def test_bcr_update_refuses_epoch_float32_stamps():
    bcr = control.BCR.from_emulator(shipped_emulator("B"))
    n = 125
    t = (1.7e9 + np.arange(n) / 120.0).astype(np.float32)
    with pytest.raises(ControlError, match="give the stamps as float64 seconds"):
        bcr.update(t, np.arange(n) / 120.0, np.zeros(n), np.ones(n))
