"""The static-level check's long span (session 75): a gain of 0.9 scales gravity's reading to
0.9 g, which a 125-sample block's mean cannot tell from a drive's vertical motion (0.157 g), but
the mean of the last 1,000 samples can (0.021 g): `SensorLimits.static_span`, in the BCR (both
methods) and in the replay's check before its high-pass."""

import re

import numpy as np
import pytest

import control
from control.bcr import BCR, PAPER_WINDOW
from control.errors import ControlError
from control.robot.condition import static_level_marks
from control.sensor_checks import SensorLimits, StaticSpan, static_span_fault, static_span_level

G = 9.80665
ON = SensorLimits(static_mps2=G)


def _drive(n: int, seed: int = 1, sd: float = 2.0) -> np.ndarray:
    """A gravity-free stand-in for a drive's vertical accelerations (m/s^2)."""
    return np.random.default_rng(seed).normal(0.0, sd, n)


@pytest.mark.parametrize(
    ("field", "value", "says"),
    [
        ("static_span", -1, "static_span must be 0 (off) or an integer in [2, "),
        ("static_span", 1, "static_span must be 0 (off) or an integer in [2, "),
        ("static_span", 1 << 21, "static_span must be 0 (off) or an integer in [2, "),
        ("static_span", 1000.5, "static_span must be an integer"),
        ("static_span_tolerance", 0.0, "static_span_tolerance must lie in (0, 1)"),
        ("static_span_tolerance", 1.0, "static_span_tolerance must lie in (0, 1)"),
        ("static_span_tolerance", None, "static_span_tolerance must be a real number"),
    ],
)
def test_bad_span_settings_are_refused_naming_the_field(field, value, says):
    with pytest.raises(ControlError, match=re.escape(says)):
        SensorLimits(**{field: value})


def test_a_span_at_0_9_g_is_a_scale_fault_a_15_degree_slope_is_not():
    assert (ON.static_span, ON.static_span_tolerance) == (1000, 0.07)
    why = static_span_level(0.9 * G, ON)
    assert why.startswith("scale or tilt: the last 1000 samples' mean acceleration 8.826")
    assert "(allowed 0.93-1.07 over a span of 1000 (static_span) samples)" in why
    assert "a sensor gain of about 0.9" in why
    assert static_span_level(np.cos(np.radians(15)) * G, ON) == ""  # a long hill
    assert static_span_level(0.95 * G, ON) == ""  # as an 18-degree slope reads: not seen
    assert static_span_level(0.9 * G, SensorLimits()) == ""  # off by default
    assert static_span_level(0.9 * G, SensorLimits(static_mps2=G, static_span=0)) == ""


def test_the_mean_is_the_last_span_samples_in_any_chunking():
    a = _drive(5000, seed=3) + G
    spans = []
    for seed in (0, 1):
        cuts = np.sort(np.random.default_rng(seed).choice(a.size, 300, replace=False))
        span = StaticSpan(1000)
        for k, part in enumerate(np.split(a, cuts)):
            span.push(part)
            held = a[: cuts[k] if k < cuts.size else a.size][-1000:]
            assert span.full == (held.size == 1000)
            if span.full:
                assert span.mean() == pytest.approx(held.mean(), abs=1e-12)
        spans.append(span)
    assert spans[0].mean() == spans[1].mean()  # bit for bit
    spans[0].restart()
    assert not spans[0].full
    spans[0].push(a[:999])
    assert not spans[0].full and static_span_fault(spans[0], ON) == ""
    # wild values pass through (cancelling in one chunk): the mean is right once they have left
    wild = np.concatenate([a[:150], [1e300, -1e300], a[150:400]])
    span, held = StaticSpan(100), 0
    for part in np.array_split(wild, 40):
        span.push(part)
        held += part.size
        if held >= 252:
            assert span.mean() == pytest.approx(wild[held - 100 : held].mean(), abs=1e-12)


def _feed(bcr: BCR, accel: np.ndarray, speed=1.5, t0: float = 0.0):
    """Feed ``accel`` one update at a time at ``speed``; the estimates."""
    t = t0 + np.arange(accel.size) / 120.0
    spd = np.broadcast_to(np.asarray(speed, float), accel.shape)
    pos = np.concatenate([[0.0], np.cumsum(spd[1:]) / 120.0])
    every = bcr.settings.samples_per_update
    return [
        bcr.update(t[k : k + every], pos[k : k + every], accel[k : k + every], spd[k : k + every])
        for k in range(0, accel.size - every + 1, every)
    ]


def _span_faults(ests):
    return [e for e in ests if "the last 1000 samples" in e.reason]


def test_the_bcr_catches_a_gain_of_0_9_once_its_span_is_full(new_bcr):
    accel = 0.9 * (_drive(120 * 12) + G)
    ests = _feed(new_bcr("B", sensor=ON), accel)
    faults = _span_faults(ests)
    assert faults and all(e.status == "sensor_fault" for e in faults)
    assert min(e.time for e in faults) >= 999 / 120.0  # the span full (8.3 s)
    # every update from then on: the span is not restarted by its own fault
    assert [e.status for e in ests if e.time >= 999 / 120.0] == ["sensor_fault"] * len(faults)
    assert not any(e.status == "sensor_fault" for e in ests if e.time < 999 / 120.0)
    # the block's own check (20%) never sees it; nor does the check with the span off
    off = _feed(new_bcr("B", sensor=SensorLimits(static_mps2=G, static_span=0)), accel)
    assert "sensor_fault" not in [e.status for e in off]
    healthy = _feed(new_bcr("B", sensor=ON), accel / 0.9)
    assert "sensor_fault" not in [e.status for e in healthy]


def test_a_gain_that_drops_mid_run_is_caught_as_the_span_fills_with_it(new_bcr):
    accel = _drive(120 * 20) + G
    accel[120 * 8 :] *= 0.9  # from 8 s on
    ests = _feed(new_bcr("B", sensor=ON), accel)
    first = min(e.time for e in _span_faults(ests))
    assert 8.0 + 0.5 * 1000 / 120 < first < 8.0 + 1000 / 120  # within 8.3 s of its start


def test_a_break_restarts_the_span_a_standstill_does_not_need_one(new_bcr):
    accel = 0.9 * (_drive(120 * 20) + G)
    accel[600] = np.nan  # a dropped sample: the span starts again after it
    ests = _feed(new_bcr("B", sensor=ON), accel)
    faults = _span_faults(ests)
    assert faults and min(e.time for e in faults) >= (601 + 999) / 120.0
    # standing still (speed 0: no block is read), the axis reads the level itself
    still = 0.9 * (_drive(120 * 10, sd=0.05) + G)
    ests = _feed(new_bcr("B", sensor=ON), still, speed=0.0)
    assert _span_faults(ests) and _span_faults(ests)[0].status == "sensor_fault"
    healthy = _feed(new_bcr("B", sensor=ON), still / 0.9, speed=0.0)
    assert "sensor_fault" not in [e.status for e in healthy]
    # reset and resume forget the span
    bcr = new_bcr("B", sensor=ON)
    _feed(bcr, accel[601:1500])
    bcr.resume(0.0)
    assert not _span_faults(_feed(bcr, accel[601:1500], t0=100.0))


def test_the_verdict_does_not_depend_on_the_chunking(new_bcr):
    accel = 0.9 * (_drive(42 * 30, seed=4) + G)
    t = np.arange(accel.size) / 120.0
    pos, spd = 1.5 * t, np.full(accel.size, 1.5)
    every = new_bcr("B").settings.samples_per_update
    runs = []
    for chunk in (every, 7):
        bcr, out = new_bcr("B", sensor=ON), []
        for k in range(0, accel.size, chunk):
            part = slice(k, k + chunk)
            est = bcr.update(t[part], pos[part], accel[part], spd[part])
            if (k + chunk) % every == 0:
                out.append((est.status, est.reason))
        runs.append(out)
    assert runs[0] == runs[1] and any("last 1000 samples" in why for _, why in runs[0])


def test_the_window_methods_check_the_span_too(fake_calibrator):
    accel = 0.9 * (_drive(120 * 12) + G)
    bcr = BCR(fake_calibrator, method="window", feature=PAPER_WINDOW, sensor=ON)
    faults = _span_faults(_feed(bcr, accel))
    assert faults and min(e.time for e in faults) >= 999 / 120.0
    assert all(e.reason.endswith("; buffer restarted") for e in faults)


def test_the_replay_checks_the_span_before_the_high_pass():
    n = 120 * 16
    t = np.arange(n) / 120.0
    raw = 0.9 * (_drive(n) + G)
    marks = static_level_marks(raw, ON, 42, 125, t, 120.0)
    span = {i: why for i, why in marks.items() if "last 1000 samples" in why}
    assert span and min(span) >= 999
    assert all(why.endswith("(the signal before the high-pass)") for why in span.values())
    off = SensorLimits(static_mps2=G, static_span=0)
    assert not static_level_marks(raw, off, 42, 125, t, 120.0)
    assert not static_level_marks(raw / 0.9, ON, 42, 125, t, 120.0)
    gap = t.copy()
    gap[700:] += 1.0  # a gap before sample 700: the span starts again there
    marks = static_level_marks(raw, ON, 42, 125, gap, 120.0)
    assert marks and min(marks) >= 700 + 999


def test_replay_marks_the_span_fault_end_to_end(tmp_path, likelihood_a):
    pytest.importorskip("rosbags")
    pytest.importorskip("mcap")
    from control.robot import read_recording, write_sensor_bag
    from control.robot.replay import replay_recording

    n = 120 * 11
    t = 1.0 + np.arange(n) / 120.0
    write_sensor_bag(tmp_path / "b", t, 0.9 * (_drive(n) + G), t, 1.5 * (t - 1.0), np.full(n, 1.5))
    settings = control.ReplaySettings(gravity="highpass", static_mps2=G)
    out = replay_recording(
        read_recording(tmp_path / "b"), likelihood_a.emulator, settings, likelihood=likelihood_a
    )
    span = [i for i, why in enumerate(out.reason) if "last 1000 samples" in why]
    assert span and all(out.status[i] == "sensor_fault" for i in span)
    assert out.time[span[0]] >= 999 / 120.0 and "safety" in out.mode.tolist()
    assert any("block or span read a static level" in note for note in out.notes)


def test_a_bcr_pickled_before_the_span_restores_with_it(new_bcr):
    state = dict(new_bcr("B", sensor=ON).__dict__)
    state.pop("_span")  # as pickled before the long span
    old = object.__new__(BCR)
    old.__setstate__(state)
    assert _span_faults(_feed(old, 0.9 * (_drive(120 * 10) + G)))
