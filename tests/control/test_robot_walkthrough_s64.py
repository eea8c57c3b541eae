"""A robotics engineer's walk through the BCR on a robot (session 64): the first block's
latency, time stamps in the wrong unit, what the BCR says before its first update, and how
an odometry that misreads the speed moves the estimate (docs/robot.md)."""

import pickle
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

import control
import roadgen

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def drive(emulator_a, likelihood_a):
    """30 m of GD 300 then 40 m of GD 500, closed loop (t, position, accel, speed)."""
    result = control.run_closed_loop(
        roadgen.track([(30, 300), (40, 500)], seed=3), emulator_a, seed=3, likelihood=likelihood_a
    )
    return (result.sample_time, result.sample_position, result.sample_accel,
            result.sample_speed)  # fmt: skip


def _feed(bcr, samples, chunk=42, **kw):
    t, p, a, s = samples
    return [bcr.update(t[i : i + chunk], p[i : i + chunk], a[i : i + chunk], s[i : i + chunk],
                       **kw) for i in range(0, t.size, chunk)]  # fmt: skip


FIRST_BLOCK = """
import pickle, sys, numpy as np, control
t, p, a, s = np.load(sys.argv[1]).values()
if sys.argv[2] == "restored":  # the BCR a robot saved, restored in a new process (no BCR
    with open(sys.argv[3], "rb") as f:  # built here first: its tables would mask the restore's)
        bcr = pickle.load(f)
    bcr.reset()
else:
    bcr = control.BCR.from_emulator(control.shipped_emulator("A"))
before, statuses = set(sys.modules), []
for k in range(0, t.size, 42):
    statuses.append(bcr.update(t[k:k + 42], p[k:k + 42], a[k:k + 42], s[k:k + 42]).status)
    if statuses[-1] == "ok":
        break
print(statuses[-1], " ".join(sorted(set(sys.modules) - before)))
"""


@pytest.mark.parametrize("how", ["new", "restored"])
def test_the_first_estimate_imports_nothing_inside_the_loop(drive, tmp_path, how):
    # Before: the first block imported scipy.signal (the DPSS tapers), 78-116 ms in that
    # update (p99 of the others ~1.5 ms); now the BCR's construction (or unpickling) pays it.
    t, p, a, s = drive
    np.savez(tmp_path / "drive.npz", t=t[:1200], p=p[:1200], a=a[:1200], s=s[:1200])
    saved = tmp_path / "bcr.pickle"
    if how == "restored":
        saved.write_bytes(pickle.dumps(control.BCR.from_emulator(control.shipped_emulator("A"))))
    script = tmp_path / "first_block.py"
    script.write_text(textwrap.dedent(FIRST_BLOCK))
    done = subprocess.run(
        [sys.executable, str(script), str(tmp_path / "drive.npz"), how, str(saved)],
        capture_output=True, text=True, env={"PYTHONPATH": str(ROOT), "PATH": ""}, timeout=300,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    status, *imported = done.stdout.split()
    assert status == "ok"
    assert imported == [], imported


@pytest.mark.parametrize(("factor", "unit"), [(1e9, "nanoseconds"), (1e3, "milliseconds")])
def test_time_stamps_in_another_unit_say_so(drive, new_bcr, factor, unit):
    t, p, a, s = drive
    bcr = new_bcr("A")
    out = _feed(bcr, (t[:420] * factor, p[:420], a[:420], s[:420]))
    assert all(e.status == "sensor_fault" for e in out)
    assert f"the time stamps are in {unit}: t must be seconds" in out[-1].reason, out[-1].reason


def test_an_honest_gap_is_not_called_a_unit(drive, new_bcr):
    t, p, a, s = drive
    late = t.copy()
    late[600:] += 2.0  # the sensor silent for 2 s
    reasons = [e.reason for e in _feed(new_bcr("A"), (late, p, a, s))]
    gap = [r for r in reasons if "a gap of 2.008 s" in r]
    assert gap and not any("time stamps are in" in r for r in reasons), gap


def test_before_the_first_update_the_reason_counts_the_samples(drive, new_bcr):
    # Before: "no samples yet" after 1, 2, ... 41 samples of a sample-by-sample feed.
    t, p, a, s = drive
    bcr = new_bcr("A")
    assert bcr.last.reason == "no samples yet"
    est = [bcr.update(t[k], p[k], a[k], s[k]) for k in range(3)]
    assert [e.reason for e in est] == [f"{k} of the first update's 42 samples" for k in (1, 2, 3)]
    bcr.resume(5.0)
    est = bcr.update(t[3], p[3], a[3], s[3])
    assert est.reason == "resumed (5 m moved while down); 1 of the first update's 42 samples"


def test_odometry_that_over_reads_the_speed_reads_rough_ground_smoother(drive, new_bcr):
    # docs/robot.md, "Odometry's speed": no check sees an odometry scale error (positions and
    # speeds agree), and the feature grows with speed, so an over-read reads smoother, an
    # under-read rougher.
    t, p, a, s = drive
    rough = {}
    for scale in (0.9, 1.0, 1.1):
        out = _feed(new_bcr("A"), (t, p * scale, a, s * scale))
        where = np.array([e.position / scale for e in out])
        on_500 = [e.gd_mean for e, x in zip(out, where, strict=True) if e.ok and x > 45]
        assert len(on_500) > 40
        rough[scale] = float(np.mean(on_500))
    assert rough[1.1] < 0.92 * rough[1.0] < 0.92 * rough[0.9], rough


class _Meddling:
    """A direction whose conversion to an array first asks the model about another block, as
    a BCR on another thread sharing the model may do between two steps of `level_score`."""

    def __init__(self, direction, model, other, v):
        self.direction, self.model, self.other, self.v = direction, model, other, v

    def __array__(self, dtype=None, copy=None):
        self.model.loglik(self.other, self.v)
        return np.asarray(self.direction, dtype=dtype)


def test_a_shared_model_scores_each_block_from_its_own_residual(drive, emulator_a):
    # Before: level_score read the model's last cached residual after its own call, so a
    # call in between (another thread's BCR) gave it that block's: 3 of 2,000 scores wrong
    # with two threads (sys.setswitchinterval(1e-6)); a wrong score can hide a quiet sensor.
    model = control.ObservationModel(emulator_a)
    spec = control.bcr_settings_for(emulator_a).feature
    _, _, a, _ = drive
    y = control.block_features(a[: 125 * 2].reshape(2, 125), spec)
    direction = np.r_[np.full(spec.dim - len(spec.quantiles), 2.0), y[0, -len(spec.quantiles) :]]
    alone = model.level_score(y[0], 1.5, direction)
    meddled = model.level_score(y[0], 1.5, _Meddling(direction, model, y[1], 1.7))
    assert meddled == alone
