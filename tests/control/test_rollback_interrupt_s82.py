"""Review of 74b0889 (session 82): a second interrupt that lands inside a BCR's roll-back (Ctrl-C
twice), and an interrupt that lands in a FaultInjector batch after its generator drew, still
leave the object as it was before the call: fed the same samples again, it continues as a twin
that never saw the call, bit for bit."""

import sys

import numpy as np
import pytest
from control_doubles import FakeBlockModel, stream

import control
import control.faults as faults
from control.bcr import BCR

CHUNK = 50
PARTS = stream(lambda s: np.where(s < 9.0, 300.0, 600.0), 1.5, 8.0, seed=1)
CHUNKS = [tuple(a[k : k + CHUNK] for a in PARTS) for k in range(0, PARTS[0].size, CHUNK)]


class _Stop(KeyboardInterrupt):
    """The test's interrupt."""


def _numbers(e: control.Estimate) -> tuple:
    return e.status, e.reason, e.gd_mean, e.gd_sd, e.interval, e.time, e.data_time


def _interrupt_in_restore(nth: int):
    """A tracer raising `_Stop` at the ``nth`` event (its call, then each line) of the first
    `BCR._restore`; ``fired`` says whether it did."""
    seen, fired = [0], []

    def tracer(frame, event, arg):
        if frame.f_code is not BCR._restore.__code__ or fired:
            return None

        def local(frame, event, arg):
            if event in ("call", "line") and not fired:
                seen[0] += 1
                if seen[0] == nth:
                    fired.append(nth)
                    raise _Stop
            return local

        return local(frame, event, arg)

    return tracer, fired


def _model_error(*args):
    raise control.ControlError("the model's error")


@pytest.mark.parametrize("call", ["update", "resume"])
def test_a_second_interrupt_inside_the_roll_back_leaves_the_bcr_as_it_was(monkeypatch, call):
    """Before: landing as it began, nothing was rolled back (the chunk fed again read as
    repeated stamps, a "sensor_fault"); just after ``__dict__.clear()``, the BCR was left
    without a single attribute (``'BCR' object has no attribute 'model'`` at the next update);
    further on, a filter without ``_mass``, or phases that kept the failed call's block (the
    estimates after it differed from the twin's). Each of its places (22) is tried."""
    nth, landed = 1, []
    while True:
        bcr, twin = BCR(FakeBlockModel()), BCR(FakeBlockModel())
        for part in CHUNKS[:9]:
            bcr.update(*part), twin.update(*part)
        tracer, fired = _interrupt_in_restore(nth)
        with monkeypatch.context() as patch:
            if call == "update":  # an error of the model's, then Ctrl-C inside the roll-back
                patch.setattr(bcr.model, "loglik", _model_error)
                previous = sys.gettrace()  # a coverage or debugger tracer, restored after
                sys.settrace(tracer)
                try:
                    with pytest.raises((_Stop, control.ControlError)) as raised:
                        for at in range(9, len(CHUNKS)):  # the first call that reaches loglik
                            bcr.update(*CHUNKS[at])
                            twin.update(*CHUNKS[at])
                finally:
                    sys.settrace(previous)
            else:
                patch.setattr(bcr._phases[2].filter, "relocate", _model_error)
                previous = sys.gettrace()
                sys.settrace(tracer)
                try:
                    with pytest.raises((_Stop, control.ControlError)) as raised:
                        bcr.resume(3.0)
                finally:
                    sys.settrace(previous)
                at = 9
        if call == "resume":
            bcr.resume(3.0), twin.resume(3.0)
        if not fired:
            break
        assert raised.type is _Stop
        landed.append(nth)
        got = [_numbers(bcr.update(*part)) for part in CHUNKS[at : at + 8]]
        assert got == [_numbers(twin.update(*part)) for part in CHUNKS[at : at + 8]], nth
        assert sum(g[0] == "ok" for g in got) >= 4  # estimates to compare
        nth += 1
    assert len(landed) >= 10, landed  # every place inside it was tried


class _Numpy:
    """numpy, whose ``clip`` raises `_Stop` at its first call (the interrupt landing in the
    batch's last fault, after the noise was drawn; session 83: the injector no longer calls
    numpy once the faults are applied)."""

    def __init__(self):
        self.calls = 0

    def __getattr__(self, name):
        return getattr(np, name)

    def clip(self, *args):
        self.calls += 1
        if self.calls == 1:
            raise _Stop
        return np.clip(*args)


def test_an_interrupt_after_the_faults_were_applied_leaves_the_injector_as_it_was(monkeypatch):
    """Before: the noise had been drawn (the generator moved on) but the spike counts not kept,
    so that the batch fed again drew other noise than the twin's."""
    kinds = [control.SensorFault(0.0, 10.0, "spike", 7.0),
             control.SensorFault(0.0, 10.0, "noise", 0.5),
             control.SensorFault(0.0, 10.0, "clip", 100.0)]  # fmt: skip
    t = np.arange(1, 241) / 120.0
    batches = [(t[k : k + 40], 0.5 * t[k : k + 40], np.sin(t[k : k + 40]), np.full(40, 0.5))
               for k in range(0, 240, 40)]  # fmt: skip
    injector = control.FaultInjector(kinds, np.random.default_rng(3))
    twin = control.FaultInjector(kinds, np.random.default_rng(3))
    injector(*batches[0]), twin(*batches[0])
    with monkeypatch.context() as patch:
        patch.setattr(faults, "np", _Numpy())
        with pytest.raises(_Stop):
            injector(*batches[1])
    for batch in batches[1:]:
        for got, want in zip(injector(*batch), twin(*batch), strict=True):
            np.testing.assert_array_equal(got, want)
