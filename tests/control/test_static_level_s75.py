"""The static-level check (session 75): a real IMU reads gravity, +9.80665 m/s^2 on an upright
axis, and a sensor gain scales that static level too; `SensorLimits.static_mps2` flags a block
whose mean lies off it (a scale fault of 0.7 read as smoother ground, every estimate "ok"
before), in the BCR with gravity kept and in the replay before its high-pass."""

import warnings

import numpy as np
import pytest

import control
from control.errors import ControlError
from control.sensor_checks import STATIC_BLOCK, SensorLimits, signal_fault

G = 9.80665


def _drive(n: int, seed: int = 1) -> np.ndarray:
    """A gravity-free stand-in for a drive's vertical accelerations (m/s^2)."""
    return np.random.default_rng(seed).normal(0.0, 4.0, n)


@pytest.mark.parametrize(
    ("field", "value", "says"),
    [
        ("static_mps2", 0.0, "static_mps2 must be None or a level"),
        ("static_mps2", np.inf, "static_mps2 must be None or a level"),
        ("static_mps2", True, "static_mps2 must be a real number or None"),
        ("static_tolerance", 1.0, "static_tolerance must lie in (0, 1)"),
        ("static_tolerance", 0.0, "static_tolerance must lie in (0, 1)"),
        ("static_tolerance", None, "static_tolerance must be a real number"),
    ],
)
def test_bad_static_settings_are_refused_naming_the_field(field, value, says):
    with pytest.raises(ControlError, match=says.replace("(", r"\(").replace(")", r"\)")):
        SensorLimits(**{field: value})


def test_a_block_off_the_static_level_is_a_scale_fault():
    a = _drive(STATIC_BLOCK) + G
    on = SensorLimits(static_mps2=G)
    assert signal_fault(a, on) == ""
    assert signal_fault(1.15 * a, on) == ""  # within the tolerance (rough ground, a slope)
    why = signal_fault(0.7 * a, on)
    ratio = 0.7 * a.mean() / G  # (the block's own mean: about 0.7)
    assert why.startswith("scale or tilt") and f"is {ratio:.3g} of the static level 9.80665" in why
    assert f"a sensor gain of about {ratio:.2g}" in why
    assert "flipped" in signal_fault(-a, on)
    assert f"gain of about {1.3 * a.mean() / G:.2g}" in signal_fault(1.3 * a, on)
    # off by default: every existing result stays as it was
    assert SensorLimits().static_mps2 is None and signal_fault(0.7 * a, SensorLimits()) == ""
    # a shorter block's mean scatters more: its tolerance grows as STATIC_BLOCK / n
    assert signal_fault(0.7 * a[:42], on) == ""
    assert signal_fault(0.3 * a[:42], on) != ""


def _bcr_statuses(bcr: control.BCR, accel: np.ndarray, speed: float = 1.5):
    t = np.arange(accel.size) / 120.0
    every = bcr.settings.samples_per_update
    out = []
    for k in range(accel.size // every):
        part = slice(k * every, (k + 1) * every)
        out.append(bcr.update(t[part], speed * t[part], accel[part], np.full(every, speed)))
    return out


def test_the_bcr_flags_a_gain_that_drops_mid_run(new_bcr):
    accel = _drive(120 * 8) + G
    accel[480:] *= 0.7  # from 4 s on
    limits = SensorLimits(noise_sd_mps2=1.0, static_mps2=G)
    with_check = _bcr_statuses(new_bcr("B", sensor=limits), accel)
    faults = [e for e in with_check if e.status == "sensor_fault"]
    assert faults and all(e.reason.startswith("scale or tilt") for e in faults)
    assert min(e.time for e in faults) >= 4.0
    assert not any(e.status == "sensor_fault" for e in with_check if e.time < 4.0)
    without = _bcr_statuses(new_bcr("B"), accel)
    assert not any(e.status == "sensor_fault" for e in without)


@pytest.fixture(scope="module")
def recordings(tmp_path_factory):
    """Two 8 s recordings of an IMU reading gravity at 120 Hz: healthy, and its gain 0.7 from
    4 s on."""
    pytest.importorskip("rosbags")
    pytest.importorskip("mcap")
    from control.robot import read_recording, write_sensor_bag

    n = 120 * 8
    t = 1.0 + np.arange(n) / 120.0
    healthy = _drive(n) + G
    faulty = healthy.copy()
    faulty[n // 2 :] *= 0.7
    root = tmp_path_factory.mktemp("static")
    out = {}
    for name, accel in (("healthy", healthy), ("faulty", faulty)):
        write_sensor_bag(root / name, t, accel, t, 1.5 * (t - 1.0), np.full(n, 1.5))
        out[name] = read_recording(root / name)
    return out


@pytest.mark.parametrize(("case", "gravity"), [("B", "keep"), ("A", "highpass")])
def test_the_replay_flags_the_scale_fault_with_gravity_kept_or_high_passed(
    recordings, case, gravity, likelihood_a, likelihood_b
):
    from control.robot.replay import replay_recording

    model = {"A": likelihood_a, "B": likelihood_b}[case]

    def replay(name, static):
        settings = control.ReplaySettings(gravity=gravity, static_mps2=static)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", control.ControlWarning)  # (gravity kept, case A)
            return replay_recording(recordings[name], model.emulator, settings, likelihood=model)

    faulty = replay("faulty", G)
    scale = [i for i, why in enumerate(faulty.reason) if "scale or tilt" in why]
    assert scale and all(faulty.status[i] == "sensor_fault" for i in scale)
    assert faulty.time[scale[0]] >= 3.0 and "safety" in faulty.mode.tolist()
    if gravity == "highpass":  # checked before the filter: the reason says so
        assert "before the high-pass" in faulty.reason[scale[0]]
        assert any("static level" in note for note in faulty.notes)
    else:
        assert faulty.bcr.sensor.static_mps2 == G
    for name, static in (("healthy", G), ("faulty", None)):
        result = replay(name, static)
        assert not any("scale or tilt" in why for why in result.reason)
        assert "sensor_fault" not in result.status.tolist()


def test_replay_settings_refuse_a_bad_level_and_a_high_passed_bcr_check(emulator_b):
    from control.robot.replay import _check_fit

    with pytest.raises(ControlError, match="static_mps2 must be None or a level"):
        control.ReplaySettings(static_mps2=0.0)
    bcr = control.bcr_settings_for(emulator_b, sensor=SensorLimits(static_mps2=G))
    settings = control.ReplaySettings(gravity="highpass")
    with pytest.raises(ControlError, match="high-pass removes the static level"):
        _check_fit(settings, bcr, emulator_b, None, control.Simplex())


def test_the_cli_passes_the_static_level():
    pytest.importorskip("rosbags")
    from control.robot import cli

    args = cli.parser().parse_args(["bag", "--emulator", "B", "--static-mps2", "9.80665"])
    assert args.static_mps2 == G
    assert cli.parser().parse_args(["bag", "--emulator", "B"]).static_mps2 is None
