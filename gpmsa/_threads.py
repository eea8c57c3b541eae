"""What gpmsa's calls share across a process's threads: the one-thread BLAS limit, the lock of
lazily built caches.

A BLAS with a process-wide thread pool (OpenBLAS's pthreads build, as numpy's and scipy's wheels
ship it; MKL, BLIS) has one thread count for every thread of the process. A limit per call
(threadpoolctl's ``with threadpool_limits(1)``: save the count, set one, restore the saved
count) breaks where calls on two threads overlap: the second saves the first's one as the
original and restores it after the first has restored the user's count, which leaves the
process's BLAS on one thread for good, and the second call's last solves run on the user's
threads, ulps away from its serial result (threadpoolctl >= 3.6 also lets only one thread at a
time set OpenBLAS's count: the others' limits do nothing). `one_thread` counts the calls in
progress per library instead: the first to enter sets the count to one, the last to leave
restores the count that the first found, so that a call gives the numbers it gives alone,
on any thread. While any gpmsa call runs, such a library runs every thread's calls on one
thread. A library whose count is per thread (an OpenMP runtime; OpenBLAS on OpenMP threads) is
limited per call, in the calling thread, as before.

``LAZY`` guards what an object builds on first use and keeps (an emulator's factors at its
point estimate): built once, by the first thread that needs it, while the others wait.
Both locks are re-made in a forked child (one of the parent's threads may hold them).
"""

from __future__ import annotations

import os
import threading
from functools import cache

from threadpoolctl import ThreadpoolController

_lock = threading.Lock()
_held: dict[str, list] = {}
"""Per process-wide library (its file): [calls in progress, its controller, the count that the
first of them found]."""

LAZY = threading.RLock()
"""The lock of lazily built caches (re-entrant: a build may need another cache)."""


@cache
def blas_controller() -> ThreadpoolController:
    """The process's BLAS libraries (scanned once: a scan costs about a millisecond)."""
    return ThreadpoolController()


def one_thread(user_api: str | None = "blas") -> _OneThread:
    """A context that runs its block with ``user_api``'s libraries on one thread: "blas" (the
    BLAS of `blas_controller`, scanned once) or None (every library loaded now, BLAS and
    OpenMP: a fresh scan, as ``threadpoolctl.threadpool_limits(1)``). Calls in progress on
    several threads share one limit of a process-wide library (see the module docstring);
    calls nested in one thread enter and leave it too."""
    if user_api == "blas":
        return _OneThread(*_blas_libraries())
    libs = ThreadpoolController().lib_controllers
    return _OneThread([lc for lc in libs if not _per_thread(lc)],
                      [lc for lc in libs if _per_thread(lc)])  # fmt: skip


@cache
def _blas_libraries() -> tuple[list, list]:
    """`blas_controller`'s BLAS libraries: (process-wide, per-thread)."""
    libs = [lc for lc in blas_controller().lib_controllers if lc.user_api == "blas"]
    return [lc for lc in libs if not _per_thread(lc)], [lc for lc in libs if _per_thread(lc)]


def _per_thread(lc) -> bool:
    """Whether library controller ``lc``'s thread count is the calling thread's own."""
    return lc.internal_api == "openmp" or getattr(lc, "threading_layer", None) == "openmp"


class _OneThread:
    """`one_thread`'s context: process-wide libraries ``shared`` through the counts of the
    calls in progress, per-thread libraries ``own`` for this call."""

    __slots__ = ("_shared", "_own", "_saved")

    def __init__(self, shared: list, own: list) -> None:
        self._shared, self._own = shared, own

    def __enter__(self) -> None:
        self._saved = []
        entered = []  # the shared libraries counted so far: left again if a later step fails
        try:
            with _lock:
                for lc in self._shared:
                    held = _held.get(lc.filepath)
                    if held is None:
                        n = lc.get_num_threads()
                        if n != 1:
                            _set(lc, 1)
                        _held[lc.filepath] = held = [0, lc, n]
                    held[0] += 1
                    entered.append(lc)
            for lc in self._own:
                n = lc.get_num_threads()
                self._saved.append((lc, n))
                lc.set_num_threads(1)
        except BaseException:
            self._leave(entered)
            raise

    def __exit__(self, *exc) -> None:
        self._leave(self._shared)

    def _leave(self, shared: list) -> None:
        """Restore the per-thread libraries' counts and leave the ``shared`` ones (each left
        even where a library's setter raises: a count left behind would hold one thread for
        good)."""
        try:
            for lc, n in reversed(self._saved):
                if n is not None:
                    lc.set_num_threads(n)
        finally:
            with _lock:
                restore = []
                for lc in shared:
                    held = _held[lc.filepath]
                    held[0] -= 1
                    if held[0] == 0:
                        del _held[lc.filepath]
                        if held[2] is not None and held[2] != 1:
                            restore.append(held)
                for _, lc, n in restore:
                    _set(lc, n)


def _set(lc, n: int) -> None:
    """Set process-wide library ``lc``'s thread count from whichever thread calls (under
    ``_lock``): threadpoolctl >= 3.6 lets one thread at a time set OpenBLAS's (its other
    threads' calls do nothing); its own setter, without that rule, where it has one."""
    getattr(lc, "_real_set_num_threads", lc.set_num_threads)(n)


def _after_fork_in_child() -> None:
    global _lock, LAZY
    _lock = threading.Lock()
    LAZY = threading.RLock()


if hasattr(os, "register_at_fork"):  # POSIX; the record of the limits is whole at the fork
    os.register_at_fork(
        before=lambda: _lock.acquire(),
        after_in_parent=lambda: _lock.release(),
        after_in_child=_after_fork_in_child,
    )
