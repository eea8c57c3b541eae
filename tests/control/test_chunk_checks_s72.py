"""What the signal checks see with a small update_every (session 72).

The window methods check each update's new samples alone (10-60 samples for a small
``update_every``), the change-point method the newest 125-sample block at each update; the
limits were calibrated on 125-sample blocks. `benchmarks/sensor_checks.py --chunks` measures the
false alarms and the short gain drops found on what each method checks (docs/closed-loop.md,
"Guards"); these tests hold its model of the BCR (`window_spans`, `changepoint_spans`) to the
BCR itself, whatever chunks the caller feeds.
"""

import numpy as np
import pytest
from control_doubles import FakeBlockModel, FakeCalibrator, stream

import control.bcr
from control import BCR, PAPER_WINDOW
from tests._examples import load_benchmark

BENCH = load_benchmark("sensor_checks")


def _checked(monkeypatch, bcr, a, call_samples: int) -> list[np.ndarray]:
    """The accelerations `signal_fault` saw while ``bcr`` took a clean stream fed in calls of
    ``call_samples`` samples."""
    seen = []
    original = control.bcr.signal_fault

    def recording(accel, limits, **kw):
        seen.append(np.array(accel))
        return original(accel, limits, **kw)

    monkeypatch.setattr(control.bcr, "signal_fault", recording)
    t, p, _, v = stream(lambda x: np.full_like(np.asarray(x, float), 400.0), 1.5, a.size / 120.0)
    for k in range(0, a.size, call_samples):
        part = slice(k, k + call_samples)
        est = bcr.update(t[part], p[part], a[part], v[part])
        assert est.status != "sensor_fault", est.reason
    return seen


@pytest.mark.parametrize("every", [10, 20, 125])
@pytest.mark.parametrize("call_samples", [7, 125])
def test_the_window_methods_check_each_updates_new_samples_as_the_benchmark_cuts_them(
    monkeypatch, every, call_samples
):
    a = 10.0 * np.random.default_rng(every).standard_normal(600)
    bcr = BCR(FakeCalibrator(), method="window", feature=PAPER_WINDOW, update_every=every)
    seen = _checked(monkeypatch, bcr, a, call_samples)
    spans = BENCH.window_spans(a.size, every)
    assert len(seen) == len(spans)
    for got, (start, stop) in zip(seen, spans, strict=True):
        np.testing.assert_array_equal(got, a[start:stop])  # every sample checked once


@pytest.mark.parametrize("every", [20, 42, 125])
def test_the_changepoint_method_checks_the_newest_block_as_the_benchmark_cuts_it(
    monkeypatch, every
):
    a = 10.0 * np.random.default_rng(every).standard_normal(600)
    seen = _checked(monkeypatch, BCR(FakeBlockModel(), update_every=every), a, 13)
    spans = BENCH.changepoint_spans(a.size, every)
    assert len(seen) == len(spans) > 0
    for got, (start, stop) in zip(seen, spans, strict=True):
        np.testing.assert_array_equal(got, a[start:stop])  # 125 samples, ending at each update


def test_the_chunk_table_counts_a_drop_once_and_the_checks_of_every_span():
    rng = np.random.default_rng(3)
    drives = 10.0 * rng.standard_normal((2, 600))
    limits = control.SensorLimits()
    drops = [[(200, 30, 0.02)], [(300, 24, 0.025)]]  # inside one 125-sample chunk each
    cell = BENCH.chunk_row(drives, BENCH.window_spans(600, 125), limits, drops, True)
    assert cell.startswith("8 checks, 0 flagged, drops found 100.0%")
    cell = BENCH.chunk_row(drives, BENCH.window_spans(600, 10), limits, drops, True)
    # 10 new samples and the 115 before them: each drop read against the samples before it
    assert cell.startswith("120 checks, 0 flagged, drops found 100.0%"), cell
