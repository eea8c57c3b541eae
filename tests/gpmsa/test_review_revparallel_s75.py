"""Review of the session-75 parallel-chain walkthrough (gpmsa.mcmc.parallel): a dask worker lost
during the import check is not an import failure, an asynchronous Client in its own event loop
is refused (it hung), a ProcessPoolExecutor in a daemonic worker is refused without a retry,
and a ValueError without errno is described."""

import asyncio
import multiprocessing
import sys
import time
import warnings
from concurrent.futures import Executor, ProcessPoolExecutor, ThreadPoolExecutor
from pathlib import Path

import pytest

import gpmsa
from gpmsa.io.atomic import _cannot_write
from gpmsa.mcmc import parallel


def _double(x, progress=False, desc=""):
    return 2 * x


class CommClosedError(OSError):
    """dask's own (distributed.comm.core.CommClosedError is an OSError too)."""


class _Client:
    """A dask Client's face of one worker: ``run`` answers as ``answer`` says, ``get_executor``
    runs tasks."""

    status = "running"

    def __init__(self, answer):
        self.answer = answer

    def scheduler_info(self, n_workers=5):
        return {"workers": {"tcp://w:1": {}}}

    def sync(self, fn, *args):
        return asyncio.run(fn(*args))

    async def run(self, fn, *args, workers, on_error, asynchronous):
        return self.answer(fn, args)

    def get_executor(self) -> Executor:
        return ThreadPoolExecutor(1)


def _lost(fn, args):
    raise CommClosedError("in <TCP (closed) Scheduler Broadcast>: Connection reset by peer")


def test_a_worker_lost_during_the_import_check_does_not_refuse_the_chains():
    # before: GPMSAError "workers cannot import ... (CommClosedError ...); install gpmsa",
    # although dask reschedules a lost worker's tasks (a real cluster: the chains then ran)
    assert parallel.run_chains(_double, [{"x": 1}, {"x": 2}], executor=_Client(_lost)) == [2, 4]


def test_an_import_that_fails_with_an_os_error_on_a_worker_is_still_refused(monkeypatch):
    def no_library(module):
        raise OSError("libtorch_cpu.so: cannot open shared object file")

    def run_here(fn, args):
        return {"tcp://w:1": fn(*args)}

    monkeypatch.setattr(parallel.importlib, "import_module", no_library)
    with pytest.raises(gpmsa.GPMSAError, match=r"cannot import .*libtorch_cpu.so.*on tcp://w:1"):
        parallel.run_chains(_double, [{"x": 1}], executor=_Client(run_here))


def test_an_asynchronous_client_in_its_own_event_loop_is_refused_not_hung():
    distributed = pytest.importorskip("distributed")

    async def main():
        async with (
            distributed.LocalCluster(
                n_workers=1, processes=False, asynchronous=True, dashboard_address=None
            ) as cluster,
            distributed.Client(cluster, asynchronous=True) as client,
        ):
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                for given in (client, client.get_executor()):
                    # before: accepted (client.run gave a coroutine, never awaited: a
                    # RuntimeWarning), then run_chains blocked the loop for ever
                    with pytest.raises(gpmsa.GPMSAError, match="asynchronous.*another thread"):
                        parallel.as_executor(given, _double)
            assert not [w for w in caught if "never awaited" in str(w.message)]
            # from another thread the same Client runs the chains
            tasks = [{"x": 1}, {"x": 2}]
            assert await asyncio.to_thread(parallel.run_chains, _double, tasks,
                                           executor=client) == [2, 4]  # fmt: skip

    asyncio.run(main())


def _with_a_process_pool():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            parallel.run_chains(_double, [{"x": 1}, {"x": 2}], executor=ProcessPoolExecutor(2))
        except Exception as exc:
            return type(exc).__name__, str(exc), [str(w.message) for w in caught]
    return None


@pytest.mark.skipif(sys.platform != "linux", reason="a fork pool starts fast on Linux only")
def test_a_process_pool_executor_in_a_daemonic_worker_is_refused_without_a_retry():
    with multiprocessing.get_context("fork").Pool(1) as pool:
        t = time.perf_counter()
        got = pool.apply(_with_a_process_pool)
        assert time.perf_counter() - t < 5
    # before: ChainError "chain 0 of 2 failed after 2 attempts: AssertionError: daemonic
    # processes are not allowed to have children", after a RuntimeWarning and a retry
    assert got is not None and got[0] == "GPMSAError", got
    assert "daemonic worker" in got[1] and "executor=None" in got[1]
    assert got[2] == []


def test_a_value_error_without_errno_is_described_not_an_attribute_error():
    # Windows: os.stat raises ValueError("stat: path too long for Windows") for > 32767 chars
    why = _cannot_write(Path("x"), ValueError("stat: path too long for Windows"))
    assert why == "x: cannot write (stat: path too long for Windows)"


@pytest.mark.slow
def test_a_real_cluster_with_a_killed_worker_runs_the_chains():
    import os
    import signal

    distributed = pytest.importorskip("distributed")
    from gpmsa import backends

    sys.path.insert(0, str(Path(__file__).parent))
    from _backend_cases import multi_data

    problem = gpmsa.prepare(multi_data()[0]).problem
    short = {"n_iter": 40, "tune_rounds": 2, "tune_levels": 5}
    serial = backends.get("numpy").sample(problem, n_chains=2, seed=5, n_jobs=1, **short)
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        pid = sorted(client.run(os.getpid).items())[0][1]
        os.kill(pid, signal.SIGKILL)  # the scheduler still lists it: the check reaches a corpse
        chains = backends.get("numpy").sample(problem, n_chains=2, seed=5, executor=client,
                                              **short)  # fmt: skip
    for name, val in serial.draws.items():
        assert (chains.draws[name] == val).all(), name
