"""Random interleavings of a BCR's calls (hypothesis state machines, session 83): good and bad
chunks of a recorded closed-loop drive, refused calls, calls that raise part way, ``resume``,
``reset``, ``copy.copy``, ``copy.deepcopy`` and a pickle round trip, in any order. After every
step: a twin fed only the accepted calls, in the same chunks, gives the same estimate bit for
bit (a refused or interrupted call leaves no trace; a copy continues as the original); a
reference fed the same samples in chunks that end on update boundaries made the same estimates
(the chunking does not matter; a call returns the gravest fault it made, else the newest
estimate); every estimate's fields are consistent."""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
from hypothesis import strategies as st
from hypothesis.stateful import (
    RuleBasedStateMachine,
    initialize,
    invariant,
    rule,
)

import control
import gpmsa
import roadgen
from control.estimate import graver_fault
from tests._stateful import COPIES, run_machine

METHODS = ("changepoint", "window", "filter")


@functools.cache
def drive() -> tuple[np.ndarray, ...]:
    """A short closed-loop drive (t, position, accel, speed at 120 Hz; 28 s over GD 300, 500),
    recorded once."""
    track = roadgen.track([(15, 300), (15, 500)], seed=1)
    run = control.run_closed_loop(track, control.shipped_emulator("A"), seed=1)
    return run.sample_time, run.sample_position, run.sample_accel, run.sample_speed


@functools.cache
def model(method: str):
    """The model a BCR of ``method`` runs on (prepared once; BCRs share it, read-only)."""
    if method == "changepoint":
        return control.ObservationModel(control.shipped_emulator("A"))
    return gpmsa.Calibrator(control.shipped_emulator("A", kind="window"))


def new_bcr(method: str, **overrides) -> control.BCR:
    m = model(method)
    return control.BCR(m, control.bcr_settings_for(m.emulator, method=method, **overrides))


def numbers(e: control.Estimate) -> tuple:
    """What an estimate says, NaN == NaN (latency aside: wall-clock time)."""
    feature = () if e.feature is None else tuple(np.asarray(e.feature).tolist())
    values = (e.time, e.position, e.gd_mean, e.gd_sd, *e.interval, e.speed, e.prob_change,
              e.data_time, e.plausibility_p, *feature)  # fmt: skip
    return (e.status, e.reason, e.domain_edge, tuple(repr(float(v)) for v in values))


def check_fields(e: control.Estimate, method: str) -> None:
    """The documented contract of one estimate's fields."""
    assert e.status in control.STATUSES
    if not e.ok:
        assert e.reason, e
        assert math.isnan(e.gd_mean) and e.posterior is None
        return
    lo, hi = e.interval
    assert np.isfinite([e.gd_mean, e.gd_sd, lo, hi]).all(), e
    assert e.gd_sd >= 0 and lo <= e.gd_mean <= hi, e
    for gd in (250.0, 350.0, 500.0):
        assert 0.0 <= e.prob_above(gd) <= 1.0
    if method == "changepoint":
        assert 0.0 <= e.prob_change <= 1.0, e
    else:
        assert math.isnan(e.prob_change)


class _Raising:
    """A model that raises at its ``at``-th call of the likelihood (an error part way)."""

    def __init__(self, inner, at: int) -> None:
        self._inner, self._left = inner, at

    def __getattr__(self, name):
        value = getattr(self._inner, name)
        if name not in ("loglik", "plausibility", "log_likelihood_grid", "level_score"):
            return value

        def call(*args, **kwargs):
            self._left -= 1
            if self._left <= 0:
                raise RuntimeError("the model failed")
            return value(*args, **kwargs)

        return call


BAD_KINDS = ("nan_accel", "nan_t", "nan_pos", "nan_speed", "gap", "repeat", "backwards",
             "saturate", "spike", "dead", "fast")  # fmt: skip
REFUSED_KINDS = ("2d", "length", "string", "none", "ragged", "now_nan", "resume_neg",
                 "resume_str", "bool_now")  # fmt: skip


class BCRMachine(RuleBasedStateMachine):
    """The BCR under random interleavings (see the module docstring)."""

    steps = 0

    @initialize(method=st.sampled_from(METHODS), every=st.sampled_from([None, 30, 63]))
    def start(self, method: str, every: int | None) -> None:
        if method != "changepoint" and every is not None:
            every = {30: 125, 63: 250}[every]
        self.method = method
        self.main = new_bcr(method, update_every=every)
        self.twin = new_bcr(method, update_every=every)
        self.ref = new_bcr(method, update_every=every)
        self.every = self.main.settings.samples_per_update
        self.k = 0  # next sample of the drive
        self.shift = (0.0, 0.0)  # time and distance added to the drive's samples (wraps)
        self.last_chunk: tuple | None = None

    # --- the samples -------------------------------------------------------------------------

    def take(self, n: int) -> tuple[np.ndarray, ...]:
        """The drive's next ``n`` samples (it wraps round, on: later time and distance)."""
        t, p, a, v = drive()
        out = []
        while n > 0:
            if self.k >= t.size:
                dt = t[-1] + 1 / 120.0 - t[0]
                self.shift = (self.shift[0] + dt, self.shift[1] + p[-1] - p[0] + 0.01)
                self.k = 0
            stop = min(t.size, self.k + n)
            part = slice(self.k, stop)
            out.append((t[part] + self.shift[0], p[part] + self.shift[1], a[part].copy(), v[part]))
            n -= stop - self.k
            self.k = stop
        return tuple(np.concatenate(x) for x in zip(*out, strict=True))

    def feed(self, chunk: tuple[np.ndarray, ...]) -> control.Estimate:
        """An accepted call: main and twin alike, the reference in chunks that end where its
        updates do; main's result checked against both."""
        self.steps += 1
        got = self.main.update(*chunk)
        assert numbers(got) == numbers(self.twin.update(*chunk))
        made, start, n = [], 0, chunk[0].size
        while start < n:
            stop = min(n, start + self.every - self.ref._received)
            before = self.ref._n_updates
            est = self.ref.update(*(x[start:stop] for x in chunk))
            if self.ref._n_updates > before:
                made.append(self.ref.last)
                check_fields(self.ref.last, self.method)
            start = stop
        check_fields(got, self.method)
        assert numbers(self.main.last) == numbers(self.ref.last)
        fault = None
        for e in made:
            fault = graver_fault(fault, e)
        if fault is not None:
            assert numbers(got) == numbers(fault)
        elif n:
            assert numbers(got) == numbers(est)
        self.last_chunk = chunk
        return got

    # --- the rules ---------------------------------------------------------------------------

    @rule(n=st.integers(1, 400))
    def good(self, n: int) -> None:
        self.feed(self.take(n))

    @rule(kind=st.sampled_from(BAD_KINDS), n=st.integers(2, 300), data=st.data())
    def bad(self, kind: str, n: int, data) -> None:
        if kind == "gap":
            self.take(data.draw(st.integers(1, 200), label="dropped"))
        chunk = [x.copy() for x in self.take(n)]
        t, p, a, v = chunk
        i = data.draw(st.integers(0, n - 1), label="at")
        j = min(n, i + data.draw(st.integers(1, 60), label="width"))
        if kind == "repeat" and self.last_chunk is not None:
            chunk = [x.copy() for x in self.last_chunk]
        elif kind == "repeat":
            t[i:j] = t[i]
        elif kind == "backwards":
            t[i:j] -= 0.5
        elif kind.startswith("nan_"):
            {"nan_accel": a, "nan_t": t, "nan_pos": p, "nan_speed": v}[kind][i:j] = np.nan
        elif kind == "saturate":
            a[i:j] = np.clip(a[i:j], -2.0, 2.0)
        elif kind == "spike":
            a[i] = 1e6
        elif kind == "dead":
            a[i:j] = 0.0
        elif kind == "fast":
            v[i:j] = 50.0
        self.feed(tuple(chunk))

    @rule(kind=st.sampled_from(REFUSED_KINDS), n=st.integers(1, 50))
    def refused(self, kind: str, n: int) -> None:
        self.steps += 1
        place = self.k, self.shift
        t, p, a, v = self.take(n)
        self.k, self.shift = place  # (the samples come again)
        with pytest.raises(control.ControlError):
            if kind == "2d":
                self.main.update(t, p, a[:, None], v)
            elif kind == "length":
                self.main.update(t, p, a[:-1], v)
            elif kind == "string":
                self.main.update(t, p, ["x"] * n, v)
            elif kind == "none":
                self.main.update(t, None, a, v)
            elif kind == "ragged":
                self.main.update(t, p, [a.tolist(), [1.0]], v)
            elif kind == "now_nan":
                self.main.update(t, p, a, v, now=float("nan"))
            elif kind == "bool_now":
                self.main.update(t, p, a, v, now=True)
            elif kind == "resume_neg":
                self.main.resume(-1.0)
            else:
                self.main.resume("1")

    @rule(n=st.integers(1, 400), at=st.integers(1, 4))
    def interrupted(self, n: int, at: int) -> None:
        """A call whose model raises part way: the BCR as before it (then fed again)."""
        self.steps += 1
        t0, shift = self.k, self.shift
        chunk = self.take(n)
        inner = self.main.model
        self.main.model = _Raising(inner, at)
        try:
            self.main.update(*chunk)
        except RuntimeError:
            self.main.model = inner
            self.k, self.shift = t0, shift  # the samples come again
            return
        finally:
            self.main.model = inner
        # no model call: an accepted call; the others take it too
        self.twin.update(*chunk)
        start = 0
        while start < n:
            stop = min(n, start + self.every - self.ref._received)
            self.ref.update(*(x[start:stop] for x in chunk))
            start = stop
        assert numbers(self.main.last) == numbers(self.ref.last)

    @rule(moved=st.sampled_from([0.0, 0.3, 4.0, 50.0, math.inf]))
    def resume(self, moved: float) -> None:
        self.steps += 1
        for bcr in (self.main, self.twin, self.ref):
            bcr.resume(moved)

    @rule()
    def reset(self) -> None:
        self.steps += 1
        for bcr in (self.main, self.twin, self.ref):
            bcr.reset()

    @rule(how=st.sampled_from(sorted(COPIES)), keep_copy=st.booleans(), n=st.integers(1, 300))
    def copied(self, how: str, keep_copy: bool, n: int) -> None:
        """A copy continues as the original, and feeding it leaves the original as it was."""
        self.steps += 1
        clone = COPIES[how](self.main)
        chunk = self.take(n)
        first = numbers(clone.update(*chunk))
        assert first == numbers(self.feed(chunk))  # the original, after its copy moved on
        assert numbers(clone.last) == numbers(self.main.last)
        if keep_copy:
            self.main = clone

    @invariant()
    def same_as_twin(self) -> None:
        if hasattr(self, "main"):
            assert numbers(self.main.last) == numbers(self.twin.last)


def run(max_examples: int, steps: int = 30, derandomize: bool = True) -> None:
    run_machine(BCRMachine, max_examples, steps, derandomize)


def test_bcr_random_interleavings():
    run(max_examples=6)
