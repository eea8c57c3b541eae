"""Parallel chains where a user runs them: in a daemonic worker (a multiprocessing.Pool's, a dask
worker's), which may not start processes, and on a dask Client whose workers cannot import the
chains' module (dask waits forever for such a task)."""

import asyncio
import multiprocessing
import sys
import warnings
from concurrent.futures import Executor, ThreadPoolExecutor

import numpy as np
import pytest

import gpmsa
from gpmsa import backends
from gpmsa.mcmc import parallel

SHORT = {"n_iter": 40, "tune_rounds": 2, "tune_levels": 5}


@pytest.fixture(scope="module")
def problem():
    from _backend_cases import multi_data

    return gpmsa.prepare(multi_data()[0]).problem


# --- a daemonic worker runs the chains itself -----------------------------------------------------
def _sample_here(problem, n_jobs):
    """In the pool's worker: the draws, or the error's type and message."""
    try:
        chains = backends.get("numpy").sample(problem, n_chains=2, seed=5, n_jobs=n_jobs, **SHORT)
    except Exception as exc:
        return type(exc).__name__, str(exc)
    return chains.draws


@pytest.mark.skipif(sys.platform != "linux", reason="a fork pool starts fast on Linux only")
@pytest.mark.skipif(parallel.available_cpus() < 2, reason="needs two CPUs")
def test_a_daemonic_worker_runs_its_chains_itself_or_says_why_not(problem):
    serial = backends.get("numpy").sample(problem, n_chains=2, seed=5, n_jobs=1, **SHORT)
    with multiprocessing.get_context("fork").Pool(1) as pool:  # daemonic workers
        every_cpu = pool.apply(_sample_here, (problem, None))
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            two = pool.apply(_sample_here, (problem, 2))
    # before: a pool refused by multiprocessing, a RuntimeWarning, a retry, then ChainError
    # "chain 0 of 2 failed after 2 attempts: AssertionError: daemonic processes are not
    # allowed to have children", for the default n_jobs too
    assert isinstance(every_cpu, dict), every_cpu
    for name, val in serial.draws.items():
        np.testing.assert_array_equal(every_cpu[name], val, err_msg=name)
    assert two[0] == "GPMSAError" and "daemonic worker" in two[1] and "n_jobs=1" in two[1]
    assert not caught


# --- a dask Client whose workers lack the package -------------------------------------------------
class _FakeClient:
    """A dask Client's face (``get_executor``, ``status``, ``scheduler_info``, ``sync``, ``run``)
    of one worker that fails to import."""

    status = "running"

    def __init__(self, error: BaseException | None):
        self.error, self.ran = error, []

    def scheduler_info(self, n_workers=5):
        return {"workers": {"tcp://worker:1": {}}}

    def sync(self, fn, *args):
        return asyncio.run(fn(*args))

    async def run(self, fn, *args, workers, on_error, asynchronous):
        self.ran.append(args)
        return {w: self.error if self.error is not None else fn(*args) for w in workers}

    def get_executor(self) -> Executor:
        return ThreadPoolExecutor(1)


def _double(x, progress=False, desc=""):
    return 2 * x


def test_a_dask_client_whose_workers_cannot_import_the_chains_is_refused():
    missing = ModuleNotFoundError("No module named 'gpmsa'")
    client = _FakeClient(missing)
    with pytest.raises(
        gpmsa.GPMSAError,
        match=r"workers cannot import .*test_chain_walk_s75 "
        r"\(ModuleNotFoundError: No module named 'gpmsa', on tcp://worker:1\); install gpmsa",
    ):
        parallel.run_chains(_double, [{"x": 1}, {"x": 2}], executor=client)
    assert client.ran == [(_double.__module__,)]  # checked before any task was submitted
    fine = _FakeClient(None)  # workers that import it: the chains run
    assert parallel.run_chains(_double, [{"x": 1}, {"x": 2}], executor=fine) == [2, 4]
    assert fine.ran == [(_double.__module__,)]


def _hide_gpmsa():
    for name in [k for k in sys.modules if k == "gpmsa" or k.startswith("gpmsa.")]:
        del sys.modules[name]
    sys.modules["gpmsa"] = None  # `import gpmsa` now raises ModuleNotFoundError


@pytest.mark.slow
def test_a_real_dask_cluster_without_gpmsa_is_refused_not_waited_on(problem):
    distributed = pytest.importorskip("distributed")
    with (
        distributed.LocalCluster(
            n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        client.run(_hide_gpmsa)
        for given in (client, client.get_executor()):  # before: waited forever on either
            with pytest.raises(gpmsa.GPMSAError, match="workers cannot import gpmsa.mcmc"):
                backends.get("numpy").sample(problem, n_chains=2, seed=5, executor=given, **SHORT)
