"""Overrides of the BCR's settings that are no BCRSettings field are named, with the way to set
a nested settings class's field (they were a bare TypeError from dataclasses.replace)."""

import pytest

import control
from control.errors import ControlError


@pytest.fixture(scope="module")
def emu():
    return control.shipped_emulator("A", "band")


@pytest.mark.parametrize(
    ("key", "hint"),
    [
        ("bogus", r"'bogus': no BCRSettings field \(its fields: feature, method"),
        ("mean_segment_m", r"pass changepoint=ChangePointSettings\(mean_segment_m=\.\.\.\)"),
        ("noise_sd_mps2", r"pass sensor=SensorLimits\(noise_sd_mps2=\.\.\.\)"),
    ],
)
def test_an_override_that_is_no_field_is_named(emu, key, hint):
    with pytest.raises(ControlError, match=hint):
        control.bcr_settings_for(emu, **{key: 1.0})
    with pytest.raises(ControlError, match=hint):
        control.BCR.from_emulator(emu, control.bcr_settings_for(emu), **{key: 1.0})
    model = control.BCR.from_emulator(emu).model
    with pytest.raises(ControlError, match=hint):
        control.BCR(model, control.bcr_settings_for(emu), **{key: 1.0})


def test_a_field_override_still_applies(emu):
    assert control.bcr_settings_for(emu, max_age_s=3.0).max_age_s == 3.0
    bcr = control.BCR.from_emulator(emu, control.bcr_settings_for(emu), max_age_s=4.0)
    assert bcr.settings.max_age_s == 4.0
