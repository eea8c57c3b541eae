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


def test_a_low_gain_is_implausible_and_never_fast_on_rough_ground(new_bcr):
    trace = drive([(30.0, 300.0), (40.0, 500.0)], 1.5, 1.0, seed=5)
    rough = lambda steps: [c.speed for e, c in steps if e.position > 35.0]  # noqa: E731
    # without the check (the library before it): the GD-500 part read smooth, and fast
    unchecked, _ = run(new_bcr("B", quiet_blocks=0), trace, gain=0.7)
    assert max(rough(unchecked)) > Simplex().v_safe
    assert all(e.status == "ok" for e, _ in unchecked if e.position > 35.0)
    steps, simplex = run(new_bcr("B"), trace, gain=0.7)
    quiet = [e for e, _ in steps if e.status == "implausible" and "read quieter" in e.reason]
    assert quiet and quiet[0].position < 30.0  # found on the smooth part already
    assert max(rough(steps)) <= Simplex().v_safe
    assert simplex.latched and "read quieter" in simplex.latched_by.reason
    assert all(0.0 <= e.plausibility_p < 1e-6 for e in quiet)


def test_the_right_gain_reads_ok(new_bcr):
    trace = drive([(30.0, 300.0), (40.0, 500.0)], 1.5, 1.0, seed=5)
    steps, simplex = run(new_bcr("B"), trace)
    assert not any("read quieter" in e.reason for e, _ in steps)
    assert not simplex.latched


@pytest.mark.parametrize("case", ["A", "B"])
@pytest.mark.parametrize("speed", [1.0, 2.0])
def test_clean_drives_across_the_domain_never_read_quiet(new_bcr, case, speed):
    """GD 205-590, as the loop drives them (the Simplex's two speeds)."""
    segments = [(25.0, 205.0), (25.0, 300.0), (25.0, 450.0), (25.0, 590.0), (25.0, 230.0)]
    trace = drive(segments, speed, 1.0 if case == "B" else 0.0, seed=11)
    steps, _ = run(new_bcr(case), trace)
    assert sum(e.ok for e, _ in steps) > 0.8 * len(steps)
    assert not any("read quieter" in e.reason for e, _ in steps)


def test_the_level_score_has_the_sign_of_the_shift(likelihood_b):
    model = likelihood_b
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


class _OneQuietBlock(FakeBlockModel):
    """FakeBlockModel whose ``quiet``-th level score is far below any GD's (-100 sd)."""

    def __init__(self, quiet: int):
        super().__init__()
        self.quiet, self.scores = quiet, 0

    def level_score(self, y, v, direction):
        self.scores += 1
        score = super().level_score(y, v, direction)
        return -100.0 if self.scores == self.quiet else score


def test_a_block_a_fault_undoes_leaves_the_quiet_check_too():
    """A fault undoes the newest block of every phase (it may hold the fault's start): its
    information leaves the filter, and now its level score the quiet-signal check. Before, a
    block of -100 sd undone by the fault after it read 'quieter than any GD' for the next 16
    blocks of its phase."""
    from control_doubles import stream

    t, p, a, v = stream(lambda s: np.full_like(s, 400.0), 1.5, 60, seed=3)
    a = a.copy()
    a[20 * 125 + 60] = np.nan  # a fault in update 20: the block before (20th score) is undone
    bcr = BCR(_OneQuietBlock(quiet=20), update_every=125)
    ests = [bcr.update(t[k : k + 125], p[k : k + 125], a[k : k + 125], v[k : k + 125])
            for k in range(0, t.size, 125)]  # fmt: skip
    fault = next(i for i, e in enumerate(ests) if e.status == "sensor_fault")
    assert "undone" in ests[fault].reason
    assert ests[fault - 1].status == "implausible"  # the quiet block read quiet before the fault
    assert not any("read quieter" in e.reason for e in ests[fault:])
    assert all(e.ok for e in ests[fault + 2 :])


@pytest.mark.parametrize(
    "direction", [np.ones(3), np.full(10, np.nan), np.zeros(10), np.array(["a"] * 10)]
)
def test_level_score_names_a_bad_direction(likelihood_b, direction):
    """A direction of another length, non-finite or all zero gave a numpy error or NaN."""
    model = likelihood_b
    mean, _ = model._at(1.5)
    with pytest.raises(ControlError, match="direction must be"):
        model.level_score(mean[5], 1.5, direction)


class _ScoreOf(FakeBlockModel):
    def __init__(self, value):
        super().__init__()
        self.value = value

    def level_score(self, y, v, direction):
        return self.value


@pytest.mark.parametrize("value", [np.nan, -np.inf, np.inf, "low", None])
def test_a_model_whose_level_score_is_not_a_finite_number_is_named(value):
    """A NaN level score read 'implausible' with p = nan for the next 16 blocks of its phase,
    +inf switched the check off for them, silently."""
    from control_doubles import stream

    t, p, a, v = stream(lambda s: np.full_like(s, 400.0), 1.5, 3, seed=3)
    bcr = BCR(_ScoreOf(value), update_every=125)
    with pytest.raises(ControlError, match="level_score"):
        for k in range(0, t.size, 125):
            bcr.update(t[k : k + 125], p[k : k + 125], a[k : k + 125], v[k : k + 125])
    assert not bcr._phases[0].levels


def test_the_gain_direction_moves_only_the_quantiles_by_their_values():
    """d y / d log(gain): 2 for a log band power, the value for a quantile. A BCR subclass whose
    feature is longer than its FeatureSpec's (benchmarks/second_channel_loop.py appends a second
    channel's 8 band powers to the first's, quantiles=()) took the extra band powers for
    quantiles: their values (log powers, of either sign) as the direction."""
    seen = []
    model = FakeBlockModel()
    stub = SimpleNamespace(**{k: getattr(model, k) for k in ("gd", "speed_range", "emulator")},
                           loglik=model.loglik, plausibility=model.plausibility,
                           level_score=lambda y, v, d: seen.append(d) or 0.0)  # fmt: skip
    y = np.linspace(-4.0, 1.0, 16)
    BCR(stub, feature=control.FeatureSpec(quantiles=()))._level_score(y, 1.5)
    np.testing.assert_array_equal(seen[-1], np.full(16, 2.0))
    y = np.linspace(-4.0, 1.0, 10)  # the default feature: 8 band powers, 2 quantiles
    BCR(stub)._level_score(y, 1.5)
    np.testing.assert_array_equal(seen[-1], np.concatenate([np.full(8, 2.0), y[8:]]))
