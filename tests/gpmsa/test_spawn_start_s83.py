"""gpmsa's own chain pool where its workers start by spawn or forkserver (macOS's default, or
multiprocessing.set_start_method's choice): each worker runs the main script again.

Before (session 83): a script that called gpmsa outside an ``if __name__ == "__main__":`` block,
or one read from standard input, broke every pool: a ChainRetryWarning, a fresh pool that broke
the same way, then "ChainError: chain 1 of 2 failed after 2 attempts: BrokenProcessPool: A process
in the process pool was terminated abruptly" (650 lines of the workers' tracebacks). A worker
that a forkserver started watched its parent, the forkserver, which outlives a killed owner while
any worker holds its pipe: the workers outlived it.
(The watchers' tests: tests/test_pool_watchers_s83.py.)"""

import multiprocessing.context
import os
import sys
import types
import warnings
from concurrent.futures import ProcessPoolExecutor

import pytest

from gpmsa.errors import ChainError
from gpmsa.mcmc import parallel
from tests._processes import ForkNamedSpawn, ends_while_starting

pytestmark = pytest.mark.skipif(not hasattr(os, "fork"), reason="the stand-in pool forks")


def _task(x, progress=False, desc=""):
    return x


@pytest.fixture
def failing_spawn_pool(monkeypatch):
    def pool(workers):
        return ProcessPoolExecutor(workers, mp_context=ForkNamedSpawn(),
                                   initializer=ends_while_starting)  # fmt: skip

    monkeypatch.setattr(parallel, "_own_pool", pool)


def test_a_worker_that_ends_while_starting_names_the_main_guard(failing_spawn_pool, monkeypatch):
    script = types.ModuleType("__main__")
    script.__file__, script.__spec__ = __file__, None
    monkeypatch.setitem(sys.modules, "__main__", script)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no retry: a fresh pool would end the same way
        with pytest.raises(ChainError, match="ended while starting") as info:
            parallel.run_chains(_task, [{"x": 0}, {"x": 1}], n_jobs=2)
    message = str(info.value)
    assert "'spawn'" in message and 'if __name__ == "__main__":' in message
    assert __file__ in message and "n_jobs=1" in message


def test_a_script_read_from_stdin_is_named(failing_spawn_pool, monkeypatch):
    script = types.ModuleType("__main__")
    script.__file__, script.__spec__ = "<stdin>", None
    monkeypatch.setitem(sys.modules, "__main__", script)
    with pytest.raises(ChainError, match="read from <stdin> cannot be read again"):
        parallel.run_chains(_task, [{"x": 0}, {"x": 1}], n_jobs=2)


def test_a_forked_worker_that_dies_is_still_retried(monkeypatch):
    def pool(workers):  # a fork pool: the start-up diagnosis does not apply
        return ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("fork"),
                                   initializer=ends_while_starting)  # fmt: skip

    monkeypatch.setattr(parallel, "_own_pool", pool)
    with pytest.warns(parallel.ChainRetryWarning), pytest.raises(ChainError, match="attempts"):
        parallel.run_chains(_task, [{"x": 0}, {"x": 1}], n_jobs=2)
