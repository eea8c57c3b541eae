"""The check of a dask Client's workers before parallel chains (gpmsa.mcmc.parallel): a worker of
another gpmsa version is refused, naming it and both versions; a ``get_executor(workers=...)``
has only the workers its tasks may run on checked; a hung worker is named after
``WORKER_CHECK_S`` instead of blocking the check for ever. In-process clusters (threads, ~1 s)
with the worker's answer stubbed; real worker processes in the slow test."""

import asyncio
import os
import signal
import sys
import time

import pytest

import gpmsa
from gpmsa import backends
from gpmsa.mcmc import parallel
from tests._extras import DISTRIBUTED


def _double(x, progress=False, desc=""):
    return 2 * x


def _worker(client, name) -> str:
    return next(a for a, i in client.scheduler_info(n_workers=-1)["workers"].items()
                if i["name"] == name)  # fmt: skip


def _older_on_1(module, dask_worker):
    """Worker 1 runs gpmsa 0.0.9, worker 0 this process's gpmsa."""
    return None, "0.0.9" if dask_worker.name == 1 else gpmsa.__version__


def _dev_on_1(module, dask_worker):
    return None, gpmsa.__version__ + ".dev1" if dask_worker.name == 1 else gpmsa.__version__


def _missing_on_1(module, dask_worker):
    why = "ModuleNotFoundError: No module named 'gpmsa'" if dask_worker.name == 1 else None
    return why, gpmsa.__version__


async def _hung_on_1(module, dask_worker):
    if dask_worker.name == 1:  # holds its answer, as a stopped worker does
        await asyncio.sleep(30)
    return None, gpmsa.__version__


def test_a_worker_of_another_gpmsa_version_is_refused_naming_it_and_both_versions(
    dask_client, monkeypatch
):
    one, zero = _worker(dask_client, 1), _worker(dask_client, 0)
    # the real answer: this process's version, the module imported; the chains run
    assert parallel._worker_report(__name__) == (None, gpmsa.__version__)
    assert parallel.run_chains(_double, [{"x": 1}, {"x": 2}], executor=dask_client) == [2, 4]
    monkeypatch.setattr(parallel, "_worker_report", _older_on_1, raising=False)
    for given in (dask_client, dask_client.get_executor()):
        # before: accepted (the version was not asked), chains run on another gpmsa's code
        with pytest.raises(gpmsa.GPMSAError, match="another gpmsa version") as err:
            parallel.run_chains(_double, [{"x": 1}, {"x": 2}], executor=given)
        assert f"this process's {gpmsa.__version__} (gpmsa 0.0.9 on {one})" in str(err.value)
        assert zero not in str(err.value) and f"install gpmsa {gpmsa.__version__}" in str(err.value)
    monkeypatch.setattr(parallel, "_worker_report", _dev_on_1)  # a development suffix too
    with pytest.raises(gpmsa.GPMSAError, match=rf"gpmsa {gpmsa.__version__}\.dev1 on {one}"):
        parallel.as_executor(dask_client, _double)
    # the workers that may run the tasks: the other one alone is fine
    executor = dask_client.get_executor(workers=[zero])
    assert parallel.run_chains(_double, [{"x": 1}, {"x": 2}], executor=executor) == [2, 4]


def test_only_the_workers_a_restricted_executor_may_use_are_checked(dask_client, monkeypatch):
    one, zero = _worker(dask_client, 1), _worker(dask_client, 0)
    monkeypatch.setattr(parallel, "_worker_report", _missing_on_1, raising=False)
    with pytest.raises(gpmsa.GPMSAError, match=f"cannot import .*'gpmsa', on {one}"):
        parallel.as_executor(dask_client, _double)
    # by address, by name: only worker 0 may run them (before: refused for worker 1)
    for workers in ([zero], zero, [0]):
        executor = dask_client.get_executor(workers=workers)
        assert parallel.run_chains(_double, [{"x": 3}], executor=executor) == [6]
    for kwargs in ({"workers": [one]}, {"workers": [zero], "allow_other_workers": True}):
        with pytest.raises(gpmsa.GPMSAError, match=f"cannot import .*on {one}"):
            parallel.as_executor(dask_client.get_executor(**kwargs), _double)


@DISTRIBUTED  # dask's own reading of an address
def test_the_workers_a_task_may_run_on_are_read_as_dask_reads_them():
    infos = {
        "tcp://10.0.0.1:1": {"name": "a", "host": "10.0.0.1", "resources": {"GPU": 1}},
        "tcp://10.0.0.1:2": {"name": 7, "host": "10.0.0.1"},
        "tcp://10.0.0.2:1": {"name": "c", "host": "10.0.0.2", "resources": {"GPU": 2}},
    }
    workers = parallel._task_workers
    assert workers(infos, {}) == list(infos)
    assert workers(infos, {"workers": ["a", 7]}) == ["tcp://10.0.0.1:1", "tcp://10.0.0.1:2"]
    assert workers(infos, {"workers": "10.0.0.2:1"}) == ["tcp://10.0.0.2:1"]  # scheme added
    assert workers(infos, {"workers": [("10.0.0.1", 2)]}) == ["tcp://10.0.0.1:2"]
    assert workers(infos, {"workers": ["10.0.0.1"]}) == ["tcp://10.0.0.1:1", "tcp://10.0.0.1:2"]
    assert workers(infos, {"resources": {"GPU": 2}}) == ["tcp://10.0.0.2:1"]
    assert workers(infos, {"workers": ["a", "c"], "resources": {"GPU": 1}}) == [
        "tcp://10.0.0.1:1",
        "tcp://10.0.0.2:1",
    ]
    assert workers(infos, {"workers": ["a"], "allow_other_workers": True}) == list(infos)
    assert workers(infos, {"workers": ["nobody"]}) == []  # dask waits for such a worker


def test_a_hung_worker_is_named_after_the_timeout_not_waited_on(dask_client, monkeypatch):
    one, zero = _worker(dask_client, 1), _worker(dask_client, 0)
    monkeypatch.setattr(parallel, "_worker_report", _hung_on_1, raising=False)
    monkeypatch.setattr(parallel, "WORKER_CHECK_S", 0.3, raising=False)
    t = time.perf_counter()
    with pytest.raises(gpmsa.GPMSAError, match="did not answer within 0.3 s") as err:
        parallel.run_chains(_double, [{"x": 1}], executor=dask_client)
    assert 0.3 <= time.perf_counter() - t < 1.5  # before: blocked until the worker answered
    assert one in str(err.value) and zero not in str(err.value)
    executor = dask_client.get_executor(workers=[zero])  # the tasks kept off it: they run
    assert parallel.run_chains(_double, [{"x": 1}], executor=executor) == [2]
    assert parallel.WORKER_CHECK_S == 0.3
    monkeypatch.undo()
    assert parallel.WORKER_CHECK_S == 60.0  # the documented default


def _other_version():
    import gpmsa._version

    gpmsa._version.__version__ = "0.0.9"


def _hide_gpmsa():
    for name in [k for k in sys.modules if k == "gpmsa" or k.startswith("gpmsa.")]:
        del sys.modules[name]
    sys.modules["gpmsa"] = None


@pytest.mark.slow
def test_a_real_cluster_of_other_versions_missing_and_stopped_workers(monkeypatch):
    distributed = pytest.importorskip("distributed")
    sys.path.insert(0, os.path.dirname(__file__))
    from _backend_cases import multi_data

    problem = gpmsa.prepare(multi_data()[0]).problem
    short = {"n_iter": 40, "tune_rounds": 2, "tune_levels": 5}
    serial = backends.get("numpy").sample(problem, n_chains=2, seed=5, n_jobs=1, **short)
    with (
        distributed.LocalCluster(
            n_workers=3, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        a, b, c = sorted(client.scheduler_info(n_workers=-1)["workers"])
        client.run(_other_version, workers=[a])
        client.run(_hide_gpmsa, workers=[b])
        with pytest.raises(gpmsa.GPMSAError, match=f"cannot import .*on {b}"):
            parallel.as_executor(client, _double)
        with pytest.raises(gpmsa.GPMSAError, match=f"another gpmsa .*gpmsa 0.0.9 on {a}\\)"):
            parallel.as_executor(client.get_executor(workers=[a, c]), _double)
        chains = backends.get("numpy").sample(  # before: refused for b, which it never uses
            problem, n_chains=2, seed=5, executor=client.get_executor(workers=[c]), **short
        )
        for name, val in serial.draws.items():
            assert (chains.draws[name] == val).all(), name
        pid = client.run(os.getpid, workers=[c])[c]
        monkeypatch.setattr(parallel, "WORKER_CHECK_S", 2.0)
        os.kill(pid, signal.SIGSTOP)
        try:
            t = time.perf_counter()
            with pytest.raises(gpmsa.GPMSAError, match=f"workers {c} did not answer within 2 s"):
                parallel.as_executor(client.get_executor(workers=[c]), _double)
            assert time.perf_counter() - t < 5  # before: blocked while it was stopped
        finally:
            os.kill(pid, signal.SIGCONT)
