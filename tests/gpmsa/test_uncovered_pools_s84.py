"""Chain-pool paths the whole suite never ran in its own process (session 84's coverage sweep,
third part; the daemonic-worker cases also run in real Pool workers in test_chain_walk_s75.py
and test_review_revparallel_s75.py, which coverage does not follow): a platform without CPU
affinity, a daemonic process, a bad ``retries``, and the parent watch's fallbacks."""

import os
from concurrent.futures import ProcessPoolExecutor
from types import SimpleNamespace

import pytest

from gpmsa.errors import GPMSAError
from gpmsa.mcmc import parallel


def _task(value, progress=False, desc=""):
    return value


def test_cpus_without_an_affinity_mask_are_the_cpu_count(monkeypatch):
    monkeypatch.delattr(os, "sched_getaffinity", raising=False)
    monkeypatch.setattr(os, "cpu_count", lambda: 3)
    assert parallel.available_cpus() == 3
    monkeypatch.setattr(os, "cpu_count", lambda: None)  # undeterminable: one
    assert parallel.available_cpus() == 1


def test_a_daemonic_process_runs_its_chains_itself(monkeypatch):
    monkeypatch.setattr(parallel.multiprocessing, "current_process",
                        lambda: SimpleNamespace(daemon=True))  # fmt: skip
    monkeypatch.setattr(parallel, "available_cpus", lambda: 4)
    assert parallel.n_workers(None, 4) == 1 and parallel.n_workers(-1, 4) == 1
    assert parallel.n_workers(3, 1) == 1  # one chain: no worker to start
    with pytest.raises(GPMSAError, match="n_jobs=2: this process is a daemonic worker .*n_jobs=1"):
        parallel.n_workers(2, 2)
    pool = ProcessPoolExecutor(1)  # starts no process before a submit
    try:
        with pytest.raises(GPMSAError, match="cannot start its processes in this daemonic"):
            parallel.as_executor(pool)
    finally:
        pool.shutdown()
    assert parallel.run_chains(_task, [{"value": 1}, {"value": 2}]) == [1, 2]  # here, in turn


@pytest.mark.parametrize("retries", [-1, 1.0, None])
def test_retries_must_be_a_count(retries):
    with pytest.raises(GPMSAError, match=f"retries must be an integer >= 0, got {retries!r}"):
        parallel.run_chains(_task, [{"value": 1}], n_jobs=1, retries=retries)


def test_the_parent_watch_falls_back_to_a_signal_probe(monkeypatch):
    """Without pidfd_open (not Linux, a kernel before 5.3) a process's end is probed with
    signal 0: ended where it is gone, alive where it belongs to another user."""

    def refuse(pid):
        raise OSError("ENOSYS")

    monkeypatch.setattr(os, "pidfd_open", refuse, raising=False)
    ended = parallel._ended(os.getpid())
    assert ended() is False

    def kill(pid, sig, error):
        raise error

    for error, alive in ((ProcessLookupError(), False), (PermissionError(), True)):
        monkeypatch.setattr(os, "kill", lambda pid, sig, e=error: kill(pid, sig, e))
        assert parallel._alive(12345) is alive
        assert ended() is (not alive)
