"""Review of the shared one-thread limit and the lazy Posterior's lock (session 80): a draw
callable that reads its own posterior fails clearly (it hung on the lock), a library whose
setter raises leaves no count behind, and a forked child inherits the limit without undoing
the parent's. Library controllers are stand-ins, so that no test depends on the host's BLAS;
a hang is turned into a failure by joining with a timeout."""

from __future__ import annotations

import os
import pickle
import threading

import numpy as np
import pytest

import gpmsa
from gpmsa import _threads
from gpmsa.errors import GPMSAError

WAIT = 10.0  # s: a safety net against a hang, never reached when the test passes or fails


class _Lib:
    """A stand-in library controller: its thread count, the counts set, and a setter that
    raises from the ``fail_at``-th call on (None: never)."""

    def __init__(self, name: str, n: int = 4, fail_get: bool = False, fail_at=None) -> None:
        self.filepath, self.n, self.sets = f"/fake/{name}-{os.getpid()}.so", n, []
        self.fail_get, self.fail_at = fail_get, fail_at

    def get_num_threads(self) -> int:
        if self.fail_get:
            raise RuntimeError("get failed")
        return self.n

    def set_num_threads(self, n: int) -> None:
        if self.fail_at is not None and len(self.sets) >= self.fail_at:
            raise RuntimeError("set failed")
        self.sets.append(n)
        self.n = n


def _in_thread(fn) -> dict:
    out: dict = {}

    def work():
        try:
            out["value"] = fn()
        except BaseException as exc:  # reported by the test
            out["error"] = exc

    thread = threading.Thread(target=work, daemon=True)  # a hung one does not hold pytest
    thread.start()
    thread.join(WAIT)
    assert not thread.is_alive(), "the call hung"
    return out


def test_a_draw_callable_that_reads_its_posterior_fails_clearly_rather_than_hang():
    post = None

    def draw():
        return {"a": np.full(3, post.mean("a"))}

    post = gpmsa.Posterior(draw=draw, info={"names": ("a",)})
    out = _in_thread(lambda: post.samples)
    assert isinstance(out.get("error"), GPMSAError), out
    assert "draw callable" in str(out["error"])
    post._draw = lambda: {"a": np.arange(3.0)}  # a later read draws again, and keeps them
    np.testing.assert_array_equal(_in_thread(lambda: post.samples)["value"]["a"], [0, 1, 2])
    back = pickle.loads(pickle.dumps(post))
    np.testing.assert_array_equal(back.samples["a"], [0, 1, 2])


def test_a_setter_that_raises_on_restore_leaves_no_count_behind():
    shared, own = _Lib("shared"), _Lib("own", n=3, fail_at=1)  # own: its restore raises
    with pytest.raises(RuntimeError, match="set failed"):
        with _threads._OneThread([shared], [own]):
            assert shared.n == own.n == 1
    assert shared.filepath not in _threads._held
    assert shared.n == 4 and shared.sets == [1, 4]


def test_a_failed_entry_leaves_no_count_behind():
    first, second = _Lib("first"), _Lib("second", fail_get=True)
    with pytest.raises(RuntimeError, match="get failed"):
        with _threads._OneThread([first, second], []):
            pass
    assert first.filepath not in _threads._held and second.filepath not in _threads._held
    assert first.n == 4
    shared, own = _Lib("shared2"), _Lib("own2", fail_get=True)
    with pytest.raises(RuntimeError, match="get failed"):
        with _threads._OneThread([shared], [own]):
            pass
    assert shared.filepath not in _threads._held and shared.n == 4


def test_nested_calls_and_an_error_in_the_block_restore_the_count_once():
    lib = _Lib("nested")
    with pytest.raises(ValueError):
        with _threads._OneThread([lib], []):
            with _threads._OneThread([lib], []):
                assert _threads._held[lib.filepath][0] == 2
            raise ValueError
    assert lib.filepath not in _threads._held and lib.sets == [1, 4]


@pytest.mark.skipif(not hasattr(os, "fork"), reason="no fork here")
def test_a_forked_child_keeps_the_parents_limit_and_leaves_its_count_alone():
    lib = _Lib("forked")
    r, w = os.pipe()
    with _threads._OneThread([lib], []):
        pid = os.fork()
        if pid == 0:  # the child: a worker's call enters and leaves the inherited limit
            code = 1
            try:
                assert _threads._lock.acquire(timeout=WAIT)  # re-made: free
                _threads._lock.release()
                with _threads._OneThread([lib], []):
                    pass
                ok = lib.sets == [1] and _threads._held[lib.filepath][0] == 1
                code = 0 if ok else 2
            finally:
                os.write(w, bytes([code]))
                os._exit(0)
        os.close(w)
        got = os.read(r, 1)
        os.close(r)
        os.waitpid(pid, 0)
    assert got == b"\x00", f"the child saw a wrong limit (code {got!r})"
    assert lib.filepath not in _threads._held and lib.sets == [1, 4]
