"""The closed loop and the Simplex with odd but valid settings: a request it cannot drive is
refused before the drive, naming the setting and the remedy."""

import pytest

import control
import roadgen


@pytest.mark.parametrize(
    ("length_m", "shown", "why"),
    [
        (0.05, "0.048", "wheel radius"),  # before: vehicle's "or envelope=False", no such option
        (0.2, "0.198", "wheelbase"),  # before: a VehicleError, not a ControlError
    ],
)
def test_a_track_too_short_for_the_vehicle_is_refused_with_its_remedy(
    emulator_a, length_m, shown, why
):
    track = roadgen.track([(length_m, 300)], seed=1, lead_in_m=0.0)
    model = control.emulator_vehicle(emulator_a)
    with pytest.raises(control.ControlError, match="track") as err:
        control.run_closed_loop(track, emulator_a, model=model, seed=1)
    message = str(err.value)
    assert f"{shown} m" in message and why in message and "lengthen the track" in message
    assert "envelope" not in message  # (run_closed_loop has no such option)


def test_a_track_just_longer_than_the_wheelbase_drives(emulator_a):
    track = roadgen.track([(0.3, 300)], seed=1, lead_in_m=0.0)
    result = control.run_closed_loop(
        track, emulator_a, model=control.emulator_vehicle(emulator_a), seed=1
    )
    assert result.sample_position[-1] == pytest.approx(track.length_m, abs=0.01)
    assert result.metrics.gd_errors[0].n == 0  # shorter than one block: no estimate


@pytest.mark.parametrize("law", ["linear", "switch"])
def test_a_band_of_one_gd_says_what_to_give(law):
    with pytest.raises(control.ControlError, match=r"gd_min must be < gd_max") as err:
        control.Simplex(gd_min=300, gd_max=300, law=law)
    assert "law='switch'" in str(err.value) and "gd_max alone" in str(err.value)
