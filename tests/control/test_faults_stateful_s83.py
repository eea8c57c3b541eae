"""Random interleavings of a `FaultInjector`'s batches (hypothesis state machines, session 83):
batches of a recorded drive of any size, refused batches, ``copy.copy``, ``copy.deepcopy`` and
a pickle round trip, in any order, over random faults. After every batch: a twin fed only the
accepted batches gives the same samples bit for bit (a refused batch leaves no trace; a copy
continues as the original); a reference fed the same samples split in other batches gives the
same samples (the faults follow the sample time, not the batches)."""

from __future__ import annotations

import functools
import itertools

import numpy as np
import pytest
from hypothesis import strategies as st
from hypothesis.stateful import (
    RuleBasedStateMachine,
    initialize,
    rule,
)

import control
import roadgen
from tests._stateful import COPIES, run_machine

MAGNITUDE = {"spike": (1.0, 50.0), "noise": (0.01, 3.0), "scale": (0.1, 3.0),
             "quantize": (0.01, 1.0), "clip": (0.1, 5.0)}  # fmt: skip


@functools.cache
def drive() -> tuple[np.ndarray, ...]:
    """A short closed-loop drive (t, position, accel, speed at 120 Hz), recorded once."""
    track = roadgen.track([(8, 300), (8, 500)], seed=3)
    run = control.run_closed_loop(track, control.shipped_emulator("A"), seed=3)
    return run.sample_time, run.sample_position, run.sample_accel, run.sample_speed


@st.composite
def faults(draw) -> list[control.SensorFault]:
    out = []
    for _ in range(draw(st.integers(1, 3))):
        kind = draw(st.sampled_from(control.FAULT_KINDS))
        lo, hi = MAGNITUDE.get(kind, (1.0, 1.0))
        out.append(control.SensorFault(
            start_s=draw(st.floats(0.0, 12.0)), duration_s=draw(st.floats(0.01, 6.0)),
            kind=kind, magnitude=draw(st.floats(lo, hi))))  # fmt: skip
    return out


def same(a: tuple, b: tuple) -> bool:
    return all(np.array_equal(x, y, equal_nan=True) for x, y in zip(a, b, strict=True))


class InjectorMachine(RuleBasedStateMachine):
    steps = 0

    @initialize(chosen=faults(), seed=st.integers(0, 3))
    def start(self, chosen, seed: int) -> None:
        self.faults = chosen
        self.main = control.FaultInjector(chosen, np.random.default_rng(seed))
        self.twin = control.FaultInjector(chosen, np.random.default_rng(seed))
        self.ref = control.FaultInjector(chosen, np.random.default_rng(seed))
        # the reference's batches draw the noise in another order where two noise faults overlap
        self.chunked = sum(f.kind == "noise" for f in chosen) < 2
        self.k = 0

    def take(self, n: int) -> tuple[np.ndarray, ...]:
        """The drive's next ``n`` samples (it wraps round, its clock going on)."""
        t, p, a, v = drive()
        k = (self.k + np.arange(n)) % t.size
        laps = (self.k + np.arange(n)) // t.size
        self.k += n
        span = t[-1] - t[0] + 1 / 120.0
        return t[k] + laps * span, p[k] + laps * (p[-1] - p[0]), a[k], v[k]

    def apply(self, batch: tuple, cuts: list[int]) -> None:
        self.steps += 1
        got = self.main(*batch)
        assert same(got, self.twin(*batch))
        if self.chunked:
            edges = [0, *sorted(c for c in cuts if 0 < c < batch[0].size), batch[0].size]
            parts = [self.ref(*(x[a:b] for x in batch)) for a, b in itertools.pairwise(edges)]
            joined = tuple(np.concatenate(x) for x in zip(*parts, strict=True))
            assert same(got, joined), (self.faults, cuts)
        for x, y in zip(got, batch, strict=True):  # copies, never the caller's arrays
            assert not np.shares_memory(x, y)

    @rule(n=st.integers(0, 300), cuts=st.lists(st.integers(0, 300), max_size=4))
    def batch(self, n: int, cuts: list[int]) -> None:
        self.apply(self.take(n), cuts)

    @rule(kind=st.sampled_from(["length", "2d", "string", "none"]), n=st.integers(1, 50))
    def refused(self, kind: str, n: int) -> None:
        self.steps += 1
        k = self.k
        t, p, a, v = self.take(n)
        self.k = k
        with pytest.raises(control.ControlError):
            if kind == "length":
                self.main(t, p, a[1:], v)
            elif kind == "2d":
                self.main(t, p, a[:, None], v)
            elif kind == "string":
                self.main(t, p, ["a"] * a.size, v)
            else:
                self.main(t, None, a, v)

    @rule(how=st.sampled_from(sorted(COPIES)), keep_copy=st.booleans(), n=st.integers(1, 300))
    def copied(self, how: str, keep_copy: bool, n: int) -> None:
        clone = COPIES[how](self.main)
        batch = self.take(n)
        first = clone(*batch)
        got = self.main(*batch)
        assert same(first, got) and same(got, self.twin(*batch))
        if self.chunked:
            assert same(got, self.ref(*batch))
        else:
            self.ref(*batch)
        if keep_copy:
            self.main = clone


def run(max_examples: int, steps: int = 30, derandomize: bool = True) -> None:
    run_machine(InjectorMachine, max_examples, steps, derandomize)


def test_fault_injector_random_interleavings():
    run(max_examples=40)
