"""Costs that grow with a stream's or a track's length, pinned without timing (session 85):
the fault injector visits only the faults near a batch, the metrics and the late-message
gap filling make a fixed number of numpy calls whatever the number of segments or gaps."""

from types import SimpleNamespace

import numpy as np

from control import detection_delays, gd_errors, metrics
from control.faults import FaultInjector, SensorFault
from control.robot import clock


class _Tally(np.ndarray):
    """An array that counts the elements the ufuncs on it go through (operators included)."""

    elements = 0

    def __array_ufunc__(self, ufunc, method, *inputs, **kwargs):
        _Tally.elements += max(np.size(x) for x in inputs)
        plain = [x.view(np.ndarray) if isinstance(x, _Tally) else x for x in inputs]
        if "out" in kwargs:
            kwargs["out"] = tuple(x.view(np.ndarray) for x in kwargs["out"])
        out = getattr(ufunc, method)(*plain, **kwargs)
        return out.view(_Tally) if isinstance(out, np.ndarray) else out


def _tallied(value):
    if isinstance(value, tuple):
        return tuple(_tallied(v) for v in value)
    return value.view(_Tally) if type(value) is np.ndarray else value


class _CountingNumpy:
    """numpy with each call of a function counted and the arrays it returns `_Tally`s (ufuncs,
    types and constants as they are)."""

    def __init__(self) -> None:
        self.calls = 0

    def __getattr__(self, name: str):
        obj = getattr(np, name)
        if not callable(obj) or isinstance(obj, type | np.ufunc):
            return obj

        def counted(*args, **kwargs):
            self.calls += 1
            return _tallied(obj(*args, **kwargs))

        return counted


class _CountedFault(SensorFault):
    """A SensorFault that counts the reads of its kind (every fault visited reads it)."""

    reads = 0

    def __getattribute__(self, name: str):
        if name == "kind":
            type(self).reads += 1
        return super().__getattribute__(name)


def test_the_fault_injector_visits_only_the_faults_near_each_batch(monkeypatch):
    # 400 faults, one every 10 s, and 20 batches of the first second: the old injector read
    # every fault per batch (8,000 reads), so a stream's cost grew with its length squared
    faults = [_CountedFault(10.0 * i + 0.5, 2.0, "noise", 1.0) for i in range(400)]
    many = FaultInjector(faults, np.random.default_rng(1))
    one = FaultInjector(faults[:1], np.random.default_rng(1))
    t = np.arange(120) / 120.0
    accel = np.random.default_rng(2).normal(size=t.size)
    monkeypatch.setattr(_CountedFault, "reads", 0)
    for k in range(0, t.size, 6):
        part = slice(k, k + 6)
        got = many(t[part], t[part], accel[part], t[part])
        want = one(t[part], t[part], accel[part], t[part])
        assert all(np.array_equal(a, b) for a, b in zip(got, want, strict=True))
    assert _CountedFault.reads < 100


def test_a_stuck_fault_far_ahead_still_holds_the_last_reading_before_it():
    faults = [SensorFault(10.0 * i + 0.5, 2.0, "noise", 1.0) for i in range(50)]
    faults.append(SensorFault(1000.0, 1.0, "stuck"))
    inj = FaultInjector(faults, np.random.default_rng(1))
    inj(np.array([0.1, 0.2]), np.zeros(2), np.array([3.0, 4.0]), np.zeros(2))
    out = inj(np.array([1000.0, 1000.5]), np.zeros(2), np.array([7.0, 8.0]), np.zeros(2))
    assert out[2].tolist() == [4.0, 4.0]


def _long_track(n_segments: int) -> SimpleNamespace:
    gds = [300.0 + 200.0 * (k % 2) + k for k in range(n_segments)]  # each GD its own
    return SimpleNamespace(
        segments=tuple((50.0, gd) for gd in gds),
        boundaries_m=tuple(50.0 * k for k in range(n_segments)),
        length_m=50.0 * n_segments,
    )


def test_the_metrics_make_a_fixed_number_of_numpy_calls_whatever_the_segments(monkeypatch):
    track = _long_track(400)
    pos = np.linspace(0.0, 50.0 * 400 - 1.0, 20_000)
    truth = np.array([gd for _, gd in track.segments])[(pos // 50).astype(int)]
    est = truth + np.where(np.arange(pos.size) % 3, 1.0, -1.0)
    counting = _CountingNumpy()
    monkeypatch.setattr(metrics, "np", counting)
    monkeypatch.setattr(_Tally, "elements", 0)
    errors = gd_errors(track, pos, est)
    # the old loop: a pass over every estimate per distinct GD (400 x 20,000 x 2 elements)
    assert _Tally.elements < 30 * pos.size
    delays = detection_delays(track, pos, est)
    assert _Tally.elements < 60 * pos.size
    assert len(errors) == 400 and all(e.rmse == 1.0 for e in errors)
    assert len(delays) == 399 and np.all(np.array(delays) < 0.5)


def test_late_messages_fill_many_gaps_with_a_fixed_number_of_numpy_calls(monkeypatch):
    period, gaps = 1 / 120, 300
    t = np.arange(20 * gaps) * period
    late = np.arange(gaps) * 20 + 10  # one in 20 received 3 messages late: a gap each
    received = np.arange(t.size, dtype=float)
    received[late] += 3.5
    t = t[np.argsort(received, kind="stable")]
    order = clock.stamp_order(t, 0.0)  # a window of 0: every late message left behind
    counting = _CountingNumpy()
    monkeypatch.setattr(clock, "np", counting)
    filled, moved = clock.into_gaps(t, order, period)
    assert counting.calls < 80  # the old loop: several calls per gap
    assert moved == gaps and np.all(np.diff(t[filled]) > 0)
