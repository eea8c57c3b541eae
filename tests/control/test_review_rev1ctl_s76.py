"""Review of session 75's static-level span (helper, session 76): the BCR's span mean is the
same sum as the replay's check before its high-pass (`static_level_marks`), so both give the
same verdict on the same raw stream, also at the tolerance's edge."""

import pickle

import numpy as np

from control.robot.condition import static_level_marks
from control.sensor_checks import SensorLimits, StaticSpan

G = 9.80665


def test_the_span_mean_is_the_stream_order_sum_of_its_samples():
    a = 0.93 * (np.random.default_rng(1).normal(0.0, 2.0, 3000) + G)
    for chunk in (1, 7, 42, 125, 1000, 2500):
        span = StaticSpan(1000)
        for k in range(0, a.size, chunk):
            span.push(a[k : k + chunk])
            end = min(k + chunk, a.size)
            if span.full:  # bit for bit the replay's sum of the newest 1,000 samples
                assert span.mean() == float(a[end - 1000 : end].sum() / 1000)


def test_the_bcr_and_the_replay_agree_at_the_edge_of_the_tolerance(new_bcr):
    n, every = 120 * 9, 42
    a = 0.93 * (np.random.default_rng(1).normal(0.0, 2.0, n) + G)
    t = np.arange(n) / 120.0
    # a level at which the mean of the span ending at sample 1049 lies at the 7% edge: the
    # samples' sum in the ring's slot order (9.005776856451279) read a fault there, the
    # stream order's (9.00577685645128, the replay's) did not
    limits = SensorLimits(static_mps2=9.683631028442235)
    bcr = new_bcr("B", sensor=limits)
    assert bcr.settings.samples_per_update == every
    marks = static_level_marks(a, limits, every, 125, t, 120.0)
    spd = np.full(n, 1.5)
    for k in range(0, n - every + 1, every):
        part = slice(k, k + every)
        est = bcr.update(t[part], 1.5 * t[part], a[part], spd[part])
        assert ("last 1000 samples" in est.reason) == (k + every - 1 in marks), k + every - 1


def test_a_span_pickled_in_session_75_still_reads_its_samples():
    a = np.random.default_rng(2).normal(G, 1.0, 1300)
    ring = np.empty(1000)
    ring[np.arange(300, 1300) % 1000] = a[300:]  # each sample once, at its place modulo 1000
    state = {"_ring": ring, "_next": 300, "_held": 1000, "_total": 0.0, "_exact": 0}
    span = StaticSpan.__new__(StaticSpan)
    getattr(span, "__setstate__", span.__dict__.update)(state)  # as pickle restores it
    span = pickle.loads(pickle.dumps(span))
    assert span.full and span.mean() == float(a[-1000:].sum() / 1000)
    span.push(a[:10])
    assert span.mean() == float(np.concatenate([a[-990:], a[:10]]).sum() / 1000)


def test_after_a_clock_step_back_the_replay_spans_start_where_the_bcrs_do(new_bcr):
    n, every = 120 * 36, 42
    a = 0.9 * (np.random.default_rng(5).normal(0.0, 2.0, n) + G)
    t = np.arange(n) / 120.0
    t[3116:] -= 0.3  # sample 3116 stamped backwards: the BCR drops it, its span restarts after
    limits = SensorLimits(static_mps2=G)
    marks = static_level_marks(a, limits, every, 125, t, 120.0)
    span = {i for i, why in marks.items() if "last 1000 samples" in why}
    bcr, faults, spd = new_bcr("B", sensor=limits), set(), np.full(n, 1.5)
    for k in range(0, n - every + 1, every):
        part = slice(k, k + every)
        if "last 1000 samples" in bcr.update(t[part], 1.5 * t[part], a[part], spd[part]).reason:
            faults.add(k + every - 1)
    assert 3116 + 999 not in faults and 3116 + 999 + every in faults  # (full 1,000 on)
    assert span == faults
