"""Session 76 (helper): (1) the static-level check's fault text gives the ratio with the digits
that tell it from the allowed band's edge (``gpmsa.errors.numbers_text``): before, a ratio
just past 0.93 read "0.93 of the static level ... (allowed 0.93-1.07 ...)"; (2) the replay's
check before its high-pass (`static_level_marks`) leaves out the samples the BCR drops for an
odometry gap (no position or speed), which restart the BCR's long span: before, its span ran on
across the gap and marked updates that the BCR, fed the same samples, found healthy."""

import numpy as np
import pytest

import control
from control.robot.condition import static_level_marks
from control.sensor_checks import SensorLimits, static_level, static_span_level

G = 9.80665
ON = SensorLimits(static_mps2=G)


def test_a_ratio_just_past_the_band_reads_past_it():
    why = static_span_level(G * (0.93 - 1e-9), ON)
    assert "is 0.929999999 of the static level 9.80665 m/s^2" in why
    assert "(allowed 0.93-1.07 over a span of 1000 (static_span) samples)" in why
    why = static_span_level(G * (1.07 + 1e-9), ON)
    assert "is 1.070000001 of the static level" in why and "(allowed 0.93-1.07 over" in why
    why = static_level(G * (0.8 - 1e-9), 125, ON)
    assert "is 0.799999999 of the static level" in why and "(allowed 0.8-1.2 over 125" in why


def test_an_ordinary_ratio_reads_as_before():
    why = static_span_level(G * 0.9, ON)
    assert why.startswith(
        "scale or tilt: the last 1000 samples' mean acceleration 8.826 m/s^2 is 0.9 of the "
        "static level 9.80665 m/s^2 a healthy axis reads (allowed 0.93-1.07 over a span of 1000 "
        "(static_span) samples): a sensor gain of about 0.9, or an axis tilted ~26 deg"
    )
    assert static_span_level(G * 0.95, ON) == ""  # within the band: no text is built


def _stream(n: int, gap: slice, gain: float = 0.9, seed: int = 5):
    """A drive at 1.5 m/s read by an axis of ``gain``, its odometry missing over ``gap``."""
    a = gain * (np.random.default_rng(seed).normal(0.0, 2.0, n) + G)
    t = np.arange(n) / 120.0
    pos, spd = 1.5 * t, np.full(n, 1.5)
    pos[gap], spd[gap] = np.nan, np.nan  # (as `odometry_at` gives them in a gap)
    return t, a, pos, spd


def _span_faults(bcr, t, a, pos, spd) -> set[int]:
    every, out = bcr.settings.samples_per_update, set()
    for k in range(0, t.size - every + 1, every):
        part = slice(k, k + every)
        if "last 1000 samples" in bcr.update(t[part], pos[part], a[part], spd[part]).reason:
            out.add(k + every - 1)
    return out


def test_across_an_odometry_gap_the_replay_spans_start_where_the_bcrs_do(new_bcr):
    t, a, pos, spd = _stream(120 * 30, slice(1500, 1560))
    faults = _span_faults(new_bcr("B", sensor=ON), t, a, pos, spd)
    assert faults and not any(1500 <= i < 1560 + 999 for i in faults)  # the span restarted
    kept = np.isfinite(pos) & np.isfinite(spd)
    marks = static_level_marks(a, ON, 42, 125, t, 120.0, kept)
    assert {i for i, why in marks.items() if "last 1000 samples" in why} == faults


def test_at_the_tolerance_edge_across_an_odometry_gap_the_verdicts_agree(new_bcr):
    # a gain whose spans' means straddle the 7% edge: some updates fault, some do not
    t, a, pos, spd = _stream(120 * 30, slice(1700, 1705), gain=0.93, seed=1)
    faults = _span_faults(new_bcr("B", sensor=ON), t, a, pos, spd)
    kept = np.isfinite(pos) & np.isfinite(spd)
    marks = static_level_marks(a, ON, 42, 125, t, 120.0, kept)
    assert {i for i, why in marks.items() if "last 1000 samples" in why} == faults
    assert faults and len(faults) < (t.size - 999) // 42  # (not every update)


def test_the_replay_restarts_its_span_after_an_odometry_gap(tmp_path, likelihood_a):
    pytest.importorskip("rosbags")
    pytest.importorskip("mcap")
    from control.robot import read_recording, write_sensor_bag
    from control.robot.replay import replay_recording

    n = 120 * 25
    t = 1.0 + np.arange(n) / 120.0
    odom = (t < 13.5) | (t > 14.5)  # no odometry for 1 s (> max_odometry_gap_s): a gap
    accel = 0.9 * (np.random.default_rng(1).normal(0.0, 2.0, n) + G)
    write_sensor_bag(
        tmp_path / "b", t, accel, t[odom], 1.5 * (t[odom] - 1.0), np.full(odom.sum(), 1.5)
    )
    settings = control.ReplaySettings(gravity="highpass", static_mps2=G)
    out = replay_recording(
        read_recording(tmp_path / "b"), likelihood_a.emulator, settings, likelihood=likelihood_a
    )
    span = out.time[[i for i, why in enumerate(out.reason) if "last 1000 samples" in why]]
    assert span.size and span.min() >= 999 / 120.0
    # the BCR drops the samples in the gap (no position or speed): the span fills again after
    assert not np.any((span > 12.5) & (span < 13.5 + 999 / 120.0)), span
    assert np.any(span >= 13.5 + 999 / 120.0)


def _block() -> np.ndarray:
    return np.random.default_rng(3).normal(0.0, 2.0, 125)


@pytest.mark.parametrize(
    ("patches", "says"),
    [
        ({"_most_lattice_like": lambda *a: (1e-10 * (1 - 1e-6), 0, 16, 0.01)},
         "(probability 9.99999e-11 for a healthy sensor, allowed 1e-10)"),
        ({"_most_lattice_like": lambda *a: (3e-12, 0, 16, 0.01)},
         "(probability 3e-12 for a healthy sensor, allowed 1e-10)"),
        ({"_level_within": lambda *a: False, "_level_jump": lambda *a: (400.0001, (0, 32))},
         "differs from the rest's by a factor 400.0001 (allowed 400)"),
        ({"_level_within": lambda *a: False, "_level_jump": lambda *a: (812.5, (0, 32))},
         "differs from the rest's by a factor 812 (allowed 400)"),
        ({"_short_levels_to_scan": lambda *a: [(16, 30.0)],
          "_short_level_drop": lambda *a: (30.00001, 5)},
         "is 1/30.00001 of the rest's and of the samples' before it (allowed 1/30 for 16"),
        ({"_short_levels_to_scan": lambda *a: [(16, 30.0)],
          "_short_level_drop": lambda *a: (45.25, 5)},
         "is 1/45.2 of the rest's and of the samples' before it (allowed 1/30 for 16"),
    ],
)  # fmt: skip
def test_a_signal_check_just_past_its_limit_reads_past_it(monkeypatch, patches, says):
    from control import sensor_checks

    for name, fn in patches.items():
        monkeypatch.setattr(sensor_checks, name, fn)
    assert says in sensor_checks.signal_fault(_block(), SensorLimits())


def test_a_speed_just_past_max_speed_reads_past_it():
    from control.sensor_checks import MAX_SPEED_MPS, stream_breaks, timing_fault

    t = np.arange(6) / 120.0
    for speed, says in ((MAX_SPEED_MPS * (1 + 1e-9), "50.00000005"), (73.21, "73.2")):
        spd = np.full(6, speed)
        why = timing_fault(t, speed * t, spd, 120.0, SensorLimits())
        assert why.startswith(f"out of range: |speed| reaches {says} m/s, beyond any ground")
        found = stream_breaks(t, speed * t, np.zeros(6), spd, np.nan, 120.0)[2]
        assert f"6 sample(s) with |speed| up to {says} m/s, beyond any" in found.reason(120.0)
