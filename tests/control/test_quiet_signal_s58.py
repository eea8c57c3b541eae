"""The quiet-signal check (`BCRSettings.quiet_blocks`): a sensor whose gain is low reads as
smoother ground, and on a noisy sensor no per-block check caught it: with emulator B and the
signal scaled by 0.7 the GD-500 part read about 224, every estimate "ok", and the Simplex drove
2.0 m/s there (docs/robot.md, "Scale"). The check sums each block's level score (its residual
at the best GD along the direction a lower gain moves the feature) over a phase's last blocks."""

from types import SimpleNamespace

import numpy as np
import pytest
from control_doubles import FakeBlockModel

import control
import roadgen
import vehicle
from control import BCR, BCRSettings, ControlError, Simplex
from control.bcr import MAX_QUIET_BLOCKS


@pytest.fixture(scope="module")
def emulator_b():
    return control.shipped_emulator("B")


def drive(segments, speed, noise, seed):
    """A constant-speed simulated drive over ``segments`` ((length m, GD), ...)."""
    track = roadgen.track(list(segments), seed=seed)
    return vehicle.simulate(vehicle.Jackal(), track, speed, noise_std=noise, seed=seed)


def run(bcr, trace, gain=1.0):
    """(estimate, Simplex command) of every update of ``bcr`` over ``trace``, its accelerations
    scaled by ``gain``, fed in 42-sample chunks (the BCR's updates)."""
    simplex = Simplex().start()
    out = []
    for a in range(0, trace.t.size, 42):
        s = slice(a, a + 42)
        est = bcr.update(trace.t[s], trace.position[s], gain * trace.accel_front_measured[s],
                         trace.speed[s])  # fmt: skip
        out.append((est, simplex.command(est)))
    return out, simplex


def test_a_low_gain_is_implausible_and_never_fast_on_rough_ground(emulator_b):
    trace = drive([(30.0, 300.0), (40.0, 500.0)], 1.5, 1.0, seed=5)
    rough = lambda steps: [c.speed for e, c in steps if e.position > 35.0]  # noqa: E731
    # without the check (the library before it): the GD-500 part read smooth, and fast
    unchecked, _ = run(BCR.from_emulator(emulator_b, quiet_blocks=0), trace, gain=0.7)
    assert max(rough(unchecked)) > Simplex().v_safe
    assert all(e.status == "ok" for e, _ in unchecked if e.position > 35.0)
    steps, simplex = run(BCR.from_emulator(emulator_b), trace, gain=0.7)
    quiet = [e for e, _ in steps if e.status == "implausible" and "read quieter" in e.reason]
    assert quiet and quiet[0].position < 30.0  # found on the smooth part already
    assert max(rough(steps)) <= Simplex().v_safe
    assert simplex.latched and "read quieter" in simplex.latched_by.reason
    assert all(0.0 <= e.plausibility_p < 1e-6 for e in quiet)


def test_the_right_gain_reads_ok(emulator_b):
    trace = drive([(30.0, 300.0), (40.0, 500.0)], 1.5, 1.0, seed=5)
    steps, simplex = run(BCR.from_emulator(emulator_b), trace)
    assert not any("read quieter" in e.reason for e, _ in steps)
    assert not simplex.latched


@pytest.mark.parametrize("case", ["A", "B"])
@pytest.mark.parametrize("speed", [1.0, 2.0])
def test_clean_drives_across_the_domain_never_read_quiet(case, speed):
    """GD 205-590, as the loop drives them (the Simplex's two speeds)."""
    emulator = control.shipped_emulator(case)
    segments = [(25.0, 205.0), (25.0, 300.0), (25.0, 450.0), (25.0, 590.0), (25.0, 230.0)]
    trace = drive(segments, speed, 1.0 if case == "B" else 0.0, seed=11)
    steps, _ = run(BCR.from_emulator(emulator), trace)
    assert sum(e.ok for e, _ in steps) > 0.8 * len(steps)
    assert not any("read quieter" in e.reason for e, _ in steps)


def test_the_level_score_has_the_sign_of_the_shift(emulator_b):
    model = control.ObservationModel(emulator_b)
    mean, _ = model._at(1.5)
    direction = np.concatenate([np.full(8, 2.0), mean[0, 8:]])
    assert model.level_score(mean[0] - 0.3 * direction, 1.5, direction) < -3.0  # below GD 200
    assert model.level_score(mean[-1] + 0.3 * direction, 1.5, direction) > 3.0  # above GD 600
    middle = mean[mean.shape[0] // 2]
    assert abs(model.level_score(middle, 1.5, direction)) < 1e-6


@pytest.mark.parametrize("value", [-1, 2.5, True, "16", MAX_QUIET_BLOCKS + 1])
def test_quiet_blocks_is_checked(value):
    with pytest.raises(ControlError, match="quiet_blocks must be an integer"):
        BCRSettings(quiet_blocks=value)


def test_a_model_without_a_level_score_names_the_setting_that_drops_the_check():
    model = FakeBlockModel()
    bare = SimpleNamespace(**{k: getattr(model, k) for k in ("gd", "speed_range", "emulator")},
                           loglik=model.loglik, plausibility=model.plausibility)  # fmt: skip
    with pytest.raises(ControlError, match=r"level_score.*quiet_blocks=0"):
        BCR(bare)
    assert BCR(bare, quiet_blocks=0).settings.quiet_blocks == 0
