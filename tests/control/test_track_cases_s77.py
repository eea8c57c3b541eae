"""The closed loop on tracks the examples do not ship: a start from rest, short segments, GDs
outside the emulator's domain, and what a refused request says about how to get it."""

import pytest
from _robot_cases import start_from_rest

import control
import roadgen
from tests._examples import load_example


def test_a_start_from_rest_is_no_dead_sensor_for_the_window_method():
    # Before: the paper's method (window) read the first 0.05 s of a noise-free start, the robot
    # on the lead-in's flat ground, as a dead sensor and latched the Simplex in safety mode for
    # the whole run (examples/closed_loop.py --track 6:300 --first-seed 11, case A).
    bcr = control.BCR.from_emulator(control.shipped_emulator("A", "window"), method="window")
    t, position, accel, speed = start_from_rest(bcr.settings.samples_per_update)
    estimate = bcr.update(t, position, accel, speed)
    assert estimate.status == "filling", estimate.reason


def test_a_dead_stretch_at_a_steady_speed_is_still_a_fault_for_the_window_method():
    bcr = control.BCR.from_emulator(control.shipped_emulator("A", "window"), method="window")
    n = bcr.settings.samples_per_update
    t, position, accel, speed = start_from_rest(2 * n)
    bcr.update(t[:n], position[:n], accel[:n], speed[:n])
    accel[n + 10 : n + 16] = 0.5  # dead for 0.05 s at 1 m/s
    estimate = bcr.update(t[n:], position[n:], accel[n:], speed[n:])
    assert estimate.status == "sensor_fault" and "dead sensor" in estimate.reason


def test_a_track_outside_the_domain_says_how_to_drive_it_anyway():
    track = roadgen.track([(3, 150), (3, 300)], seed=1)
    with pytest.raises(control.EmulatorMismatchError, match=r"check=False drives it anyway"):
        control.run_closed_loop(track, control.shipped_emulator("A"), seed=1)


def test_segments_in_place_of_a_track_are_told_how_to_make_one():
    with pytest.raises(control.ControlError, match=r"roadgen\.track\(segments, seed="):
        control.run_closed_loop([(50, 300), (50, 500)], control.shipped_emulator("A"))


def test_a_profile_in_place_of_a_track_is_named_briefly():
    profile = roadgen.iso8608_profile(20.0, 300.0, seed=1)
    with pytest.raises(control.ControlError, match="got Profile") as info:
        control.run_closed_loop(profile, control.shipped_emulator("A"))
    assert len(str(info.value)) < 300, str(info.value)  # not the profile's arrays


@pytest.mark.parametrize(
    "text, shortest",
    [("20:500,0.5:300", "at least 1 m"), ("1:300,20:500", "at least 1.5 m"), ("0.5:300", "1 m")],
)
def test_a_segment_too_short_for_the_track_is_named_with_its_remedy(tmp_path, capsys, text,
                                                                    shortest):  # fmt: skip
    # Before: "blend_m=1 is out of range" or "lead_in_m=1 is out of range", arguments of
    # roadgen.track that the script does not take.
    with pytest.raises(SystemExit) as exit_info:
        load_example("closed_loop").main(["--out", str(tmp_path), "--track", text])
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    short = next(p for p in text.split(",") if float(p.split(":")[0]) < 1.5)
    assert f"segment {short!r}" in err and shortest in err and "_m=" not in err, err
