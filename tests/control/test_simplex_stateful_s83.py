"""Random interleavings of a `SimplexRun`'s calls (hypothesis state machines, session 83):
estimates of every status (ok ones a BCR made on a recorded closed-loop drive), refused calls,
``reset``, ``copy.copy``, ``copy.deepcopy`` and a pickle round trip, in any order, with and
without the release dwell. After every command: never above v_max, at most v_safe in safety
mode, never faster on a fault, never faster than the law (but where "paper" latches), the latch
and the dwell as documented (an oracle kept by the test); a twin fed only the accepted calls
gives the same command, and so does a copy."""

from __future__ import annotations

import functools
import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import strategies as st
from hypothesis.stateful import (
    RuleBasedStateMachine,
    initialize,
    invariant,
    precondition,
    rule,
)

import control
import roadgen
from tests._stateful import COPIES, run_machine

NOT_OK = tuple(s for s in control.STATUSES if s != "ok")


@functools.cache
def ok_estimates() -> tuple[control.Estimate, ...]:
    """The ok estimates a BCR made on a short closed-loop drive (GD 300, then 500), recorded
    once."""
    emulator = control.shipped_emulator("A")
    track = roadgen.track([(12, 300), (12, 500)], seed=2)
    run = control.run_closed_loop(track, emulator, seed=2)
    bcr = control.BCR.from_emulator(emulator)
    out = []
    t, p, a, v = run.sample_time, run.sample_position, run.sample_accel, run.sample_speed
    for k in range(0, t.size, 42):
        est = bcr.update(t[k : k + 42], p[k : k + 42], a[k : k + 42], v[k : k + 42])
        if est.ok:
            out.append(est)
    return tuple(out)


def said(c: control.Command) -> tuple:
    return (repr(c.speed), c.mode, repr(c.gd_used), c.reason)


class Oracle:
    """What the docs say a run's mode is: the law's, latched in safety mode after a fault
    (``after_fault="latch"``), held in safety mode by the release dwell."""

    def __init__(self, simplex: control.Simplex) -> None:
        self.s = simplex
        self.latched = False
        self.performed = False  # commanded performance mode, or met a fault
        self.in_safety = True
        self.clear_from = None  # position of the first update of a row whose law read performance

    def mode(self, est: control.Estimate, law: control.Command) -> str:
        s = self.s
        fault = est.status == "sensor_fault" or (
            est.status == "implausible" and not est.plausibility_p >= s.latch_p
        )
        if fault and s.after_fault == "latch":
            self.latched = True
        if fault:
            self.performed = True
        if self.latched:
            self.clear_from, self.in_safety = None, True
            return "safety"
        if s.release_m == 0:
            return law.mode
        if law.mode == "safety" or not math.isfinite(est.position):
            self.clear_from = None
        elif self.clear_from is None:
            self.clear_from = est.position
        if law.mode == "safety":
            self.in_safety = True
            return "safety"
        clear = 0.0 if self.clear_from is None else est.position - self.clear_from
        if self.performed and self.in_safety and not clear >= s.release_m:
            return "safety"
        self.performed, self.in_safety = True, False
        return "performance"


class SimplexMachine(RuleBasedStateMachine):
    steps = 0

    @initialize(
        law=st.sampled_from(["linear", "paper", "switch"]),
        risk=st.sampled_from([None, 0.1]),
        after_fault=st.sampled_from(["latch", "resume"]),
        release_m=st.sampled_from([0.0, 0.5, 3.0]),
        step=st.sampled_from([0.1, 0.0]),
    )
    def start(self, law, risk, after_fault, release_m, step) -> None:
        self.simplex = control.Simplex(law=law, risk=risk, after_fault=after_fault,
                                       release_m=release_m, speed_step_mps=step)  # fmt: skip
        self.run = self.simplex.start()
        self.twin = self.simplex.start()
        self.oracle = Oracle(self.simplex)
        self.position, self.time = 0.0, 0.0
        self.previous: control.Command | None = None

    def estimate(self, data, status: str) -> control.Estimate:
        step = data.draw(st.sampled_from([0.0, 0.1, 0.35, 1.0, 2.5, math.nan]), label="step")
        if math.isfinite(step):
            self.position += step
        position = self.position if math.isfinite(step) else math.nan
        self.time += 0.35
        if status == "ok":
            pool = ok_estimates()
            est = pool[data.draw(st.integers(0, len(pool) - 1), label="which")]
            est = replace(est, time=self.time, position=position)
            gd = data.draw(st.sampled_from([None, 100.0, 260.0, 349.0, 351.0, 700.0]), label="gd")
            if gd is not None:
                est = replace(est, gd_mean=gd, interval=(min(gd, est.interval[0]),
                                                         max(gd, est.interval[1])))  # fmt: skip
            if data.draw(st.booleans(), label="no posterior"):
                est = replace(est, posterior=None)
            if data.draw(st.integers(0, 5), label="edge") == 0:
                est = replace(est, domain_edge="upper")
            return est
        p = math.nan
        if status == "implausible":
            p = data.draw(st.sampled_from([math.nan, 1e-20, 1e-12, 1e-9, 1e-7]), label="p")
        return control.Estimate(self.time, position, status, f"a {status} estimate",
                                plausibility_p=p)  # fmt: skip

    @rule(status=st.sampled_from(control.STATUSES + ("ok",) * 3), data=st.data())
    def command(self, status: str, data) -> None:
        self.steps += 1
        s = self.simplex
        est = self.estimate(data, status)
        law = s.command(est)
        c = self.run.command(est)
        assert said(c) == said(self.twin.command(est))
        assert 0.0 <= c.speed <= s.v_max and math.isfinite(c.speed)
        assert c.mode in ("performance", "safety")
        if c.mode == "safety":
            assert c.speed <= s.v_safe and c.reason
        if not (s.law == "paper" and self.run.latched):
            assert c.speed <= law.speed  # never faster than the law
        if not est.ok and s.law != "paper":
            assert c.speed == s.v_safe  # a fault, or no estimate: never faster than v_safe
            if self.previous is not None:
                assert c.speed <= self.previous.speed
        assert c.mode == self.oracle.mode(est, law), (c, law, vars(self.oracle))
        if c.mode == "performance":
            assert said(c) == said(law)
        assert self.run.latched == self.oracle.latched
        self.previous = c

    @rule(what=st.sampled_from([None, "ok", 1.0, ("ok",)]))
    def refused(self, what) -> None:
        self.steps += 1
        with pytest.raises(control.ControlError):
            self.run.command(what)

    @rule()
    def reset(self) -> None:
        self.steps += 1
        for run in (self.run, self.twin):
            run.reset()
        self.oracle.latched = False

    @precondition(lambda self: ok_estimates())
    @rule(how=st.sampled_from(sorted(COPIES)), keep_copy=st.booleans(), data=st.data())
    def copied(self, how: str, keep_copy: bool, data) -> None:
        self.steps += 1
        clone = COPIES[how](self.run)
        est = self.estimate(data, data.draw(st.sampled_from(control.STATUSES), label="status"))
        first = said(clone.command(est))
        law = self.simplex.command(est)
        c = self.run.command(est)
        assert first == said(c) == said(self.twin.command(est))
        assert c.mode == self.oracle.mode(est, law)
        self.previous = c
        if keep_copy:
            self.run = clone

    @invariant()
    def same_state(self) -> None:
        if hasattr(self, "run"):
            keys = ("clear_since_m", "in_safety", "performed")
            assert [getattr(self.run, k) for k in keys] == [getattr(self.twin, k) for k in keys]
            assert self.run.latched == self.twin.latched


def run(max_examples: int, steps: int = 40, derandomize: bool = True) -> None:
    run_machine(SimplexMachine, max_examples, steps, derandomize)


def test_simplex_run_random_interleavings():
    run(max_examples=30)


def test_the_estimates_pool_holds_both_modes():
    gd = np.array([e.gd_mean for e in ok_estimates()])
    assert (gd < 350).any() and (gd > 350).any()
