"""Objects shared by threads (session 80): each race forced by pausing one thread at the
point where another overtakes it, so that the tests do not depend on the scheduler.

- the one-thread BLAS limit of overlapping calls on two threads holds until the last leaves,
  and the process's BLAS count is restored after it (it was left on one thread for good);
- an emulator's factors at its point estimate are built once, whichever threads ask first;
- a lazily drawn Posterior draws once: threads that read ``samples`` meanwhile wait and get
  the same dict (a draw callable was called once per thread);
- a Calibrator's updates on two threads take turns, each with its own count (both had the
  first update's draws).
"""

from __future__ import annotations

import copy
import pickle
import threading
from pathlib import Path

import numpy as np
import pytest
from threadpoolctl import threadpool_info, threadpool_limits

import gpmsa
from gpmsa import _threads
from gpmsa.fitting.emulator import Emulator

WINDOW = Path(__file__).resolve().parents[2] / "control" / "emulators" / "jackal_A_window.gpmsa"
WAIT = 30.0  # s: a safety net against a hang, never reached when the test passes or fails


def _blas_threads() -> list[int]:
    return [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]


class _Arrivals:
    """Events by name, set once; ``wait`` fails the test rather than hang."""

    def __init__(self) -> None:
        self._events: dict[str, threading.Event] = {}
        self._guard = threading.Lock()

    def __getitem__(self, name: str) -> threading.Event:
        with self._guard:
            return self._events.setdefault(name, threading.Event())

    def wait(self, name: str) -> None:
        assert self[name].wait(WAIT), f"no {name!r} within {WAIT} s"


class _SignallingLock:
    """A lock that sets ``arrived`` when a thread other than ``first`` comes to take it."""

    def __init__(self, real, arrived: threading.Event, first: str) -> None:
        self._real, self._arrived, self._first = real, arrived, first

    def __enter__(self):
        if threading.current_thread().name != self._first:
            self._arrived.set()
        return self._real.__enter__()

    def __exit__(self, *exc):
        return self._real.__exit__(*exc)


def _run(name: str, fn, out: dict) -> threading.Thread:
    def work():
        try:
            out[name] = fn()
        except BaseException as exc:  # reported by the test
            out[name] = exc

    thread = threading.Thread(target=work, name=name)
    thread.start()
    return thread


def _join(*threads: threading.Thread) -> None:
    for thread in threads:
        thread.join(WAIT)
        assert not thread.is_alive(), f"{thread.name} did not finish"


@pytest.fixture(scope="module")
def window() -> Emulator:
    return gpmsa.load(WINDOW)


def test_overlapping_calls_keep_one_blas_thread_and_restore_the_count(window, monkeypatch):
    if not _blas_threads():
        pytest.skip("no BLAS library that threadpoolctl controls")
    ev = _Arrivals()
    seen = {}
    real = Emulator._predict_std

    def paused(self, *args, **kwargs):  # inside predict's one-thread region
        name = threading.current_thread().name
        if name == "A":
            ev["A inside"].set()
            ev.wait("A may go")
        elif name == "B":
            ev["B inside"].set()
            ev.wait("A has left")
            seen["B"] = _blas_threads()
        return real(self, *args, **kwargs)

    monkeypatch.setattr(Emulator, "_predict_std", paused)
    predict = lambda: window.predict([1.0], [300.0], draws=True, n_draws=1)  # noqa: E731
    out = {}
    with threadpool_limits(limits=2, user_api="blas"):  # the user's count: 2
        if set(_blas_threads()) != {2}:
            pytest.skip("this BLAS does not take two threads here")
        a = _run("A", predict, out)
        ev.wait("A inside")
        b = _run("B", predict, out)
        ev.wait("B inside")
        ev["A may go"].set()
        _join(a)
        ev["A has left"].set()
        _join(b)
        after = _blas_threads()
    assert set(seen["B"]) == {1}, "B's solves ran on the user's threads after A left"
    assert set(after) == {2}, "the process's BLAS was left on one thread"
    monkeypatch.setattr(Emulator, "_predict_std", real)
    alone = window.predict([1.0], [300.0], draws=True, n_draws=1)
    for res in (out["A"], out["B"]):
        assert not isinstance(res, BaseException), res
        np.testing.assert_array_equal(res[0], alone[0])
        np.testing.assert_array_equal(res[1], alone[1])


def test_an_emulators_point_factors_are_built_once(monkeypatch):
    emu = gpmsa.load(WINDOW)  # fresh: nothing cached
    ev = _Arrivals()
    calls = []
    real = Emulator._factor

    def slow(self, params):
        calls.append(threading.current_thread().name)
        if threading.current_thread().name == "A":
            ev["A building"].set()
            ev.wait("B arrived")
        else:
            ev["B arrived"].set()  # (a second build)
        return real(self, params)

    monkeypatch.setattr(Emulator, "_factor", slow)
    monkeypatch.setattr(_threads, "LAZY", _SignallingLock(_threads.LAZY, ev["B arrived"], "A"))
    out = {}
    a = _run("A", lambda: emu.predict([1.0], [300.0]), out)
    ev.wait("A building")
    b = _run("B", lambda: emu.predict([1.0], [300.0]), out)
    _join(a, b)
    assert calls == ["A"]
    np.testing.assert_array_equal(out["A"][0], out["B"][0])
    np.testing.assert_array_equal(out["A"][1], out["B"][1])


def test_a_lazy_posterior_draws_once_for_threads_that_read_it_meanwhile():
    ev = _Arrivals()
    calls = []
    rng = np.random.default_rng(0)  # a draw callable with state: each call other draws

    def draw():
        calls.append(threading.current_thread().name)
        if threading.current_thread().name == "A":
            ev["A drawing"].set()
            ev.wait("B arrived")
        else:
            ev["B arrived"].set()  # (a second draw)
        return {"a": rng.standard_normal(50)}

    post = gpmsa.Posterior(draw=draw, info={"names": ("a",)})
    if hasattr(post, "_drawing"):
        post._drawing = _SignallingLock(post._drawing, ev["B arrived"], "A")
    out = {}
    a = _run("A", lambda: post.samples, out)
    ev.wait("A drawing")
    b = _run("B", lambda: post.samples, out)
    _join(a, b)
    assert calls == ["A"]
    assert out["A"] is out["B"] is post.samples
    assert post.mean("a") == float(np.mean(out["A"]["a"]))


def test_updates_on_two_threads_take_turns_each_with_its_own_count(window, monkeypatch):
    cal = gpmsa.Calibrator(window, seed=3)
    serial = gpmsa.Calibrator(window, seed=3)
    first = serial.update([[1.0]], [[4.0]]).samples["GD"]
    second = serial.update([[1.0]], [[4.0]]).samples["GD"]
    assert not np.array_equal(first, second)
    ev = _Arrivals()
    real = gpmsa.Calibrator._posterior

    def paused(self, *args, **kwargs):
        if threading.current_thread().name == "A":
            ev["A updating"].set()
            ev.wait("B arrived")
        else:
            ev["B arrived"].set()  # (B's update ran beside A's)
        return real(self, *args, **kwargs)

    monkeypatch.setattr(gpmsa.Calibrator, "_posterior", paused)
    if hasattr(cal, "_updating"):
        cal._updating = _SignallingLock(cal._updating, ev["B arrived"], "A")
    out = {}
    a = _run("A", lambda: cal.update([[1.0]], [[4.0]]), out)
    ev.wait("A updating")
    b = _run("B", lambda: cal.update([[1.0]], [[4.0]]), out)
    _join(a, b)
    np.testing.assert_array_equal(out["A"].samples["GD"], first)
    np.testing.assert_array_equal(out["B"].samples["GD"], second)
    monkeypatch.undo()
    third = serial.update([[1.0]], [[4.0]]).samples["GD"]
    np.testing.assert_array_equal(cal.update([[1.0]], [[4.0]]).samples["GD"], third)


def test_a_calibrator_and_a_lazy_posterior_still_copy_and_pickle(window):
    cal = gpmsa.Calibrator(window, seed=4)
    post = cal.update([[1.0]], [[4.0]])
    for copied in (copy.deepcopy(cal), pickle.loads(pickle.dumps(cal))):
        a, b = copied.update([[1.2]], [[4.1]]), copy.deepcopy(cal).update([[1.2]], [[4.1]])
        np.testing.assert_array_equal(a.samples["GD"], b.samples["GD"])
        assert copied._updating is not cal._updating
    back = pickle.loads(pickle.dumps(post))
    np.testing.assert_array_equal(back.samples["GD"], post.samples["GD"])
