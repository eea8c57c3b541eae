"""gpmsa's own pool workers never collect the garbage they inherit from the parent: a forked
worker that collected another pool's executor would run its weakref callback, which takes a lock
one of the parent's threads may have held at the fork, and wait forever (seen once in CI)."""

import gc
import threading
import time
import weakref

import pytest

from gpmsa.mcmc import parallel

_fired: list[int] = []
_refs: list = []
_held = threading.Lock()


class _Garbage:
    pass


def _plant_cyclic_garbage(callback) -> None:
    item = _Garbage()
    item.itself = item  # a cycle: only the garbage collector frees it
    _refs.append(weakref.ref(item, callback))


def _collections_in_worker(x, progress=False, desc=""):
    """Collect in the worker: (inherited garbage freed, garbage made here freed)."""
    before = len(_fired)
    gc.collect()
    inherited = len(_fired) - before
    _plant_cyclic_garbage(lambda _: _fired.append(2))
    before = len(_fired)
    gc.collect()
    return inherited, len(_fired) - before


@pytest.mark.skipif(parallel.available_cpus() < 2, reason="needs two CPUs for a pool")
def test_a_worker_leaves_inherited_garbage_alone_and_collects_its_own():
    enabled = gc.isenabled()
    gc.disable()  # keep the planted garbage uncollected in the parent until the fork
    try:
        _plant_cyclic_garbage(lambda _: _fired.append(1))
        results = parallel.run_chains(_collections_in_worker, [{"x": 0}, {"x": 1}], n_jobs=2)
    finally:
        if enabled:
            gc.enable()
    assert results == [(0, 1), (0, 1)]  # before: (1, 1), the inherited callback ran
    before = len(_fired)
    gc.collect()
    assert len(_fired) == before + 1  # the parent still frees it, its callback runs here


def _takes_the_held_lock(x, progress=False, desc=""):
    gc.collect()  # a collected trap would block on _held, taken by the parent at the fork
    return x


@pytest.mark.skipif(parallel.available_cpus() < 2, reason="needs two CPUs for a pool")
def test_a_lock_held_at_the_fork_does_not_hang_a_worker():
    def blocks(_):
        with _held:
            pass

    enabled = gc.isenabled()
    gc.disable()
    _held.acquire()
    try:
        _plant_cyclic_garbage(blocks)
        done = []
        runner = threading.Thread(
            target=lambda: done.append(
                parallel.run_chains(_takes_the_held_lock, [{"x": 0}, {"x": 1}], n_jobs=2)
            ),
            daemon=True,
        )
        runner.start()
        runner.join(timeout=20.0)
        hung = runner.is_alive()
    finally:
        _held.release()
        if enabled:
            gc.enable()
    gc.collect()
    assert not hung, "a worker waited for a lock it inherited held"
    assert done == [[0, 1]]


def _naps(seconds: float) -> float:
    time.sleep(seconds)
    return seconds


@pytest.mark.skipif(parallel.available_cpus() < 2, reason="needs two CPUs for a pool")
def test_a_stopped_pool_has_no_manager_thread_left():
    # the pool's manager thread takes its locks while it winds down: a fork in the meantime (the
    # next pool's workers) inherits them held. Stopped mid-chain, it was alive 13 times in 20.
    left = 0
    for _ in range(5):
        pool = parallel._own_pool(2)
        for _ in range(2):
            pool.submit(_naps, 0.3)
        time.sleep(0.05)
        manager = pool._executor_manager_thread
        parallel._stop(pool)
        left += manager.is_alive()
    assert left == 0
