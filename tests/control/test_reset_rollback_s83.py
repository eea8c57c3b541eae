"""An interrupted ``BCR.reset()`` (a KeyboardInterrupt, or an error raised by what it calls)
leaves the BCR as it was before the call, as an interrupted ``update`` or ``resume`` does:
fed the next samples, it continues as a twin that was never reset, bit for bit.

Before: reset was not rolled back. An interrupt part way left some phases (or trackers)
back at the prior and others not, or the buffers emptied with the filters kept: the next
estimates differed from both the twin's and those after a whole reset (and one landing inside
the stream's fields left the BCR without some of them: an AttributeError at the next update)."""

import copy
import sys

import numpy as np
import pytest
from control_doubles import bcr_of, stream

import control
from control.feature import STANDARD_GRAVITY

CHUNK = 50
PARTS = stream(lambda s: np.where(s < 9.0, 300.0, 600.0), 1.5, 10.0, seed=1)


class _Stop(KeyboardInterrupt):
    """The test's interrupt."""


def _numbers(e: control.Estimate) -> str:
    """The estimate's fields, exactly (a repr: NaN reads as itself)."""
    return repr((e.status, e.reason, e.gd_mean, e.gd_sd, e.interval, e.prob_change, e.time,
                 e.position, e.data_time))  # fmt: skip


def _chunks(kind: str) -> list:
    t, p, a, v = PARTS
    a = a + STANDARD_GRAVITY if kind == "static span" else a
    return [(t[k : k + CHUNK], p[k : k + CHUNK], a[k : k + CHUNK], v[k : k + CHUNK])
            for k in range(0, t.size, CHUNK)]  # fmt: skip


def _interrupt_at(nth: int):
    """A tracer raising `_Stop` at the ``nth`` event (a call or a line, in any frame) after it
    is set; ``fired`` says whether it did."""
    seen, fired = [0], []

    def tracer(frame, event, arg):
        if event in ("call", "line") and not fired:
            seen[0] += 1
            if seen[0] == nth:
                fired.append(nth)
                raise _Stop
        return tracer

    return tracer, fired


def _interrupted_reset(bcr: control.BCR, nth: int) -> bool:
    """``bcr.reset()`` interrupted at its ``nth`` event; whether it was (False: it completed)."""
    tracer, fired = _interrupt_at(nth)
    previous = sys.gettrace()  # a coverage or debugger tracer, restored after
    sys.settrace(tracer)
    try:
        bcr.reset()
    except _Stop:
        pass
    finally:
        sys.settrace(previous)
    return bool(fired)


@pytest.mark.parametrize(("kind", "at"), [("changepoint", 12), ("static span", 12),
                                          ("filter", 20)])  # fmt: skip
def test_an_interrupted_reset_leaves_the_bcr_as_it_was(kind, at):
    """Each place inside reset (and what it calls) is tried, the twin a copy of the BCR (each
    estimate of its next 3 updates, over its 3 phases or trackers, compared)."""
    chunks = _chunks(kind)
    bcr = bcr_of(kind)
    for part in chunks[:at]:
        bcr.update(*part)
    twin = copy.copy(bcr)
    want = [_numbers(twin.update(*part)) for part in chunks[at : at + 3]]
    nth, differed = 1, []
    while True:
        broken = copy.copy(bcr)
        if not _interrupted_reset(broken, nth):
            break
        try:
            got = [_numbers(broken.update(*part)) for part in chunks[at : at + 3]]
        except AttributeError as exc:
            got = [repr(exc)]
        if got != want:
            differed.append(nth)
        nth += 1
    assert nth > 20  # the places tried
    assert differed == []


def test_a_model_error_inside_reset_leaves_the_bcr_as_it_was(monkeypatch):
    """An error raised by what reset calls (the last phase's filter) rolls it back too."""
    chunks = _chunks("changepoint")
    bcr, twin = bcr_of("changepoint"), bcr_of("changepoint")
    for part in chunks[:12]:
        bcr.update(*part), twin.update(*part)

    def fails():
        raise control.ControlError("the filter's error")

    with monkeypatch.context() as patch:
        patch.setattr(bcr._phases[2].filter, "reset", fails)
        with pytest.raises(control.ControlError, match="the filter's error"):
            bcr.reset()
    assert [_numbers(bcr.update(*p)) for p in chunks[12:]] == [
        _numbers(twin.update(*p)) for p in chunks[12:]
    ]
    bcr.reset(), twin.reset()  # a whole reset afterwards: as the twin's
    assert [_numbers(bcr.update(*p)) for p in chunks[:8]] == [
        _numbers(twin.update(*p)) for p in chunks[:8]
    ]
