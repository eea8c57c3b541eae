"""Chain runs that stop early leave nothing running, a closed dask Client is refused (not a
hang), short chains are never judged converged, and ``sample`` refuses bad run arguments."""

import faulthandler
import multiprocessing
import os
import re
import signal
import threading
import time
from contextlib import nullcontext

import numpy as np
import pytest

import gpmsa
from gpmsa import backends
from gpmsa.mcmc import diagnostics, parallel


@pytest.fixture(scope="module")
def problem():
    from _backend_cases import multi_data

    return gpmsa.prepare(multi_data()[0]).problem


# --- a run that stops early ends its workers ------------------------------------------------------
def _first_fails(x, error, progress=False, desc=""):
    if x == 0:
        time.sleep(0.3)  # the other chain is running by now
        raise error
    time.sleep(30.0)  # a long chain nobody will read
    return x


def _sleeps(x, progress=False, desc=""):
    time.sleep(30.0)
    return x


def _workers_left(before: set, wait_s: float = 5.0) -> list:
    deadline = time.monotonic() + wait_s
    while True:
        left = [p for p in multiprocessing.active_children() if p.pid not in before]
        if not left or time.monotonic() > deadline:
            return left
        time.sleep(0.1)


@pytest.mark.skipif(parallel.available_cpus() < 2, reason="needs two CPUs for a pool")
@pytest.mark.parametrize(
    ("error", "match"),
    [
        (gpmsa.GPMSAError("bad input 42"), "chain 0 of 2 failed: GPMSAError: bad input 42"),
        (ValueError("broke 42"), "chain 0 of 2 failed after 2 attempts: ValueError: broke 42"),
    ],
)
def test_a_failed_chain_ends_the_workers_still_running(error, match):
    before = {p.pid for p in multiprocessing.active_children()}
    tasks = [{"x": i, "error": error} for i in range(2)]
    start = time.monotonic()
    retried = not isinstance(error, gpmsa.GPMSAError)  # not an input error: run once more
    with pytest.warns(RuntimeWarning, match="running it again") if retried else nullcontext():
        with pytest.raises(gpmsa.ChainError, match=match):
            parallel.run_chains(_first_fails, tasks, n_jobs=2)
    assert time.monotonic() - start < 10.0  # the error comes without waiting for chain 1
    assert _workers_left(before) == []


@pytest.mark.skipif(parallel.available_cpus() < 2, reason="needs two CPUs for a pool")
@pytest.mark.parametrize("taken_by", ["the process", "another thread"])
def test_an_interrupted_run_stops_at_once_and_ends_its_workers(taken_by):
    # Ctrl-C is a SIGINT to the process, which the kernel may hand to any of its threads; one
    # that another thread takes must stop the run as well (it waited for the chains' 30 s). Python
    # turns SIGINT into KeyboardInterrupt unless the process started with it ignored, as a
    # background job of a shell without job control does (`pytest &`): the test sets it.
    sent_after = []  # seconds from the start to the interrupt, once sent
    main_pid = os.getpid()

    def interrupt() -> None:
        sent_after.append(time.monotonic() - start)
        if taken_by == "the process":
            os.kill(main_pid, signal.SIGINT)
        else:  # the timer's own thread takes it
            signal.pthread_kill(threading.get_ident(), signal.SIGINT)

    before = {p.pid for p in multiprocessing.active_children()}
    handler = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(1.0, interrupt)
    faulthandler.dump_traceback_later(8.0)  # a run that goes on: every thread's stack to stderr
    start = time.monotonic()
    timer.start()
    interrupted = False
    try:
        parallel.run_chains(_sleeps, [{"x": i} for i in range(2)], n_jobs=2)
    except KeyboardInterrupt:
        interrupted = True
    finally:
        timer.cancel()
        faulthandler.cancel_dump_traceback_later()
        took = time.monotonic() - start
        sent = f"sent after {sent_after[0]:.2f} s" if sent_after else "never sent"
        lost = "" if interrupted else _second_interrupt()
        signal.signal(signal.SIGINT, handler)
    assert interrupted, (
        f"the run ended after {took:.1f} s without a KeyboardInterrupt ({sent}); a second one, "
        f"sent to the main thread then, {lost}"
    )
    assert took < 10.0, f"the interrupt ({sent}) stopped the run after {took:.1f} s"
    assert _workers_left(before) == []


def _second_interrupt() -> str:
    """What a SIGINT sent to the main thread (this one) does now: whether Python still turns it
    into a KeyboardInterrupt (the diagnosis of a lost one)."""
    try:
        signal.pthread_kill(threading.get_ident(), signal.SIGINT)
        time.sleep(0.5)
    except KeyboardInterrupt:
        return "raised one"
    return f"raised none either (Python's handler: {signal.getsignal(signal.SIGINT)!r})"


# --- a closed dask Client -------------------------------------------------------------------------
def _double(x, progress=False, desc=""):
    return 2 * x


def test_a_closed_dask_client_is_refused_without_a_hang():
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(
        n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None
    )
    client = distributed.Client(cluster)
    tasks = [{"x": i} for i in range(3)]
    assert parallel.run_chains(_double, tasks, executor=client) == [0, 2, 4]
    executor = client.get_executor()
    client.close()
    cluster.close()
    # dask takes a task resubmitted to a closed Client and never runs it: a daemon thread
    # bounds the wait
    for given, match in ((client, "the dask Client is closed"),
                         (executor, "refused chain 0 of 3: ClosedClientError")):  # fmt: skip
        got = []

        def run(given=given, got=got):
            try:
                parallel.run_chains(_double, tasks, executor=given)
            except Exception as exc:
                got.append(exc)

        thread = threading.Thread(target=run, daemon=True)
        thread.start()
        thread.join(60)
        assert not thread.is_alive(), f"run_chains hung on a closed Client ({match})"
        assert isinstance(got[0], gpmsa.GPMSAError) and re.search(match, str(got[0]))


# --- the convergence verdict ----------------------------------------------------------------------
def _verdict(x: np.ndarray) -> dict:
    summary = diagnostics.summarize({"a": x[:, :, None]})
    return diagnostics.convergence(summary, {"a": (1,)}, x.shape[0], x.shape[1])


def test_chains_stuck_apart_are_flagged_however_short():
    rng = np.random.default_rng(0)
    for n_draws in (5, 7, 8, 20):  # ArviZ's bulk ESS of these is above 100
        stuck = np.repeat(rng.normal(size=(64, 1)), n_draws, axis=1)
        stuck += 1e-3 * rng.normal(size=stuck.shape)
        record = _verdict(stuck)
        assert not record["converged"], n_draws
        why = record["flagged"]["a[0]"]
        assert why.startswith("R-hat") or why == f"too few draws to judge ({n_draws} a chain)"
    same = np.repeat(rng.normal(size=(1, 2000)), 4, axis=0)  # identical chains: R-hat 1
    record = _verdict(same)
    assert record["converged"] and abs(record["rhat"]["a"][0] - 1.0) < 0.01


# --- sample's run arguments -----------------------------------------------------------------------
SHORT = {"n_iter": 20, "tune_rounds": 2, "tune_levels": 5, "n_jobs": 1}


@pytest.mark.parametrize(
    ("bad", "match"),
    [
        ({"tune": "no"}, "tune must be True or False, got 'no'"),
        ({"progress": "no"}, "progress must be True or False, got 'no'"),
        ({"n_chains": True}, "n_chains must be an integer >= 1, got True"),
        ({"n_iter": True}, "n_iter must be an integer >= 1, got True"),
    ],
)
def test_sample_refuses_a_flag_or_count_of_another_type(problem, capsys, bad, match):
    with pytest.raises(gpmsa.GPMSAError, match=match):
        backends.get("numpy").sample(problem, **{**SHORT, **bad})
    assert capsys.readouterr().err == ""  # progress="no" drew no bar


def test_sample_refuses_draws_beyond_the_memory_limit(problem, monkeypatch):
    monkeypatch.setattr(gpmsa.limits, "MAX_MEMORY_BYTES", 100_000)
    with pytest.raises(gpmsa.ResourceLimitError, match=r"sample\(n_iter=1000, n_chains=2\)"):
        backends.get("numpy").sample(problem, n_chains=2, tune=False, **{**SHORT, "n_iter": 1000})
