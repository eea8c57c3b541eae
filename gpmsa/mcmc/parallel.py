"""Run independent chains in parallel: own worker processes, or any ``concurrent.futures.Executor``.

Each chain is one task: a module-level function called with plain, picklable data (the Problem,
settings and the chain's own ``numpy.random.SeedSequence``), so its draws depend on the chain's
index and the seed only, never on the number of workers or on where it ran. With one worker and
no executor the chains run one after another in this process (no pool), as they do in a daemonic
process (a ``multiprocessing.Pool``'s or a dask worker's), which may not start one. A dask
Client's workers that may run the tasks are first asked to import the task's module and to say
their gpmsa version, which must be this process's: dask would wait forever for a task they cannot
unpickle, and another version runs other code on other data. A worker that does not answer
within ``WORKER_CHECK_S`` is named in a GPMSAError.

Failures: a task that raises ``GPMSAError`` (bad input, the same on any machine) stops the run with
``ChainError`` naming the chain. Any other failure (a worker that died, also one killed while it
sent its draws, which the pool itself would wait on for ever: `_ended_mid_send`; a lost connection,
an executor whose ``submit`` raises) is retried ``retries`` times, with a ``RuntimeWarning``, in a
fresh pool when the pool was ours; then ``ChainError`` names the chain and the cause (at once where
a worker of ours that spawn or forkserver started ended while starting: a script without an ``if
__name__ == "__main__":`` block, or read from standard input). A chain is never dropped silently.
When a run stops early (a chain failed, or KeyboardInterrupt), the chains not yet finished are
cancelled: gpmsa's own worker processes are ended, an executor's futures cancelled. Ctrl-C stops a
parallel run within a quarter of a second, whichever of the process's threads the kernel hands the
signal to. A process killed outright (SIGTERM, SIGKILL), whose cleanup never runs, takes its own
workers with it (`end_with_parent`)."""

from __future__ import annotations

import asyncio
import gc
import importlib
import multiprocessing
import multiprocessing.connection
import multiprocessing.context
import os
import select
import signal
import sys
import threading
import time
import warnings
from collections.abc import Callable, Sequence
from concurrent.futures import (
    FIRST_COMPLETED,
    BrokenExecutor,
    Executor,
    Future,
    ProcessPoolExecutor,
    wait,
)
from concurrent.futures.process import BrokenProcessPool
from numbers import Number

import numpy as np

from gpmsa import _version
from gpmsa._progress import progress_bar
from gpmsa.errors import ChainError, ChainRetryWarning, GPMSAError, user_stacklevel

RETRIES = 1
"""Default number of times a chain whose task failed for a reason other than its input is rerun."""

WORKER_CHECK_S = 60.0
"""Seconds a dask Client's workers have to answer the check before the chains (import the task's
module, say their gpmsa version; 2-5 ms on two local worker processes): one that has not answered
by then (hung, e.g. stopped) is named in a GPMSAError, where dask would give it tasks that never
end. Read at each check: set ``gpmsa.mcmc.parallel.WORKER_CHECK_S`` for workers that import
slowly."""


def available_cpus() -> int:
    """CPUs this process may run on (its affinity mask where the platform has one)."""
    if hasattr(os, "sched_getaffinity"):
        return max(1, len(os.sched_getaffinity(0)))
    return max(1, os.cpu_count() or 1)


def n_workers(n_jobs: int | None, n_chains: int) -> int:
    """Worker processes for ``n_chains`` chains: ``n_jobs`` (None or -1, joblib's spelling: every
    CPU), never more than the chains; in a daemonic process (a ``multiprocessing.Pool``'s or a
    dask worker's), which may not start any, None or -1 gives 1 (the chains run in it).
    GPMSAError for ``n_jobs`` 0 or below -1, not an integer, (counting only the workers that
    would run, min(n_jobs, n_chains)) above the CPUs available, or above 1 in a daemonic
    process."""
    cpus = available_cpus()
    integer = not isinstance(n_jobs, bool) and isinstance(n_jobs, int | np.integer)
    daemon = multiprocessing.current_process().daemon
    if n_jobs is None or (integer and n_jobs == -1):
        return 1 if daemon else max(1, min(cpus, n_chains))
    if not integer or n_jobs < 1:
        raise GPMSAError(
            f"n_jobs must be None or -1 (every CPU) or an integer >= 1, got {n_jobs!r}"
        )
    n_jobs = int(n_jobs)
    if daemon and min(n_jobs, n_chains) > 1:
        raise GPMSAError(
            f"n_jobs={n_jobs}: this process is a daemonic worker (a multiprocessing.Pool's or a "
            "dask worker's), which may not start worker processes; give n_jobs=1 or None (the "
            "chains run here, one after another, with the same draws)"
        )
    if min(n_jobs, n_chains) > cpus:  # only the workers that would run count
        raise GPMSAError(
            f"n_jobs={n_jobs} is more than the {cpus} CPUs this process may use; give "
            f"n_jobs <= {cpus}, or an executor= (e.g. a dask Client's) to run elsewhere"
        )
    return min(n_jobs, n_chains)


def in_this_process(callables: list[str], n_jobs, executor, n_chains: int):
    """(n_jobs, executor) for chains that hold ``callables`` of this process (names of a
    constraint, a log prior, a mean basis: a lambda cannot be pickled), run here one after
    another: (1, None); GPMSAError for an executor=, and still for a bad n_jobs. Unchanged
    where there are none."""
    if not callables:
        return n_jobs, executor
    if executor is not None:
        which = (
            f"{callables[0]} is a callable of this process: it"
            if len(callables) == 1
            else f"{' and '.join(callables)} are callables of this process: they"
        )
        raise GPMSAError(
            f"{which} cannot go to executor=; leave executor= out: the chains then run here, "
            "one after another, with the draws the executor would give"
        )
    n_workers(n_jobs, n_chains)
    return 1, None


def as_executor(executor, fn: Callable | None = None) -> Executor | None:
    """``executor`` as a ``concurrent.futures.Executor`` (a dask ``Client`` gives its own). With
    ``fn`` (a task function) and a dask ``Client`` (or its ``get_executor()``), first checks the
    workers that may run the tasks (`_check_workers`): dask waits forever for a task its workers
    cannot unpickle (gpmsa, or torch for the torch backend, not installed there)."""
    if executor is None:
        return executor
    if isinstance(executor, ProcessPoolExecutor) and multiprocessing.current_process().daemon:
        raise GPMSAError(  # its submit fails, a retry too: "daemonic processes are not allowed..."
            "executor: a ProcessPoolExecutor cannot start its processes in this daemonic worker "
            "(a multiprocessing.Pool's or a dask worker's); leave executor=None and n_jobs=None "
            "(the chains run here, one after another, with the same draws)"
        )
    client = _dask_client(executor)
    closed = getattr(client, "status", None) in ("closing", "closed")
    if closed and client is executor:  # (its executor's submit refuses the task: run_chains)
        raise GPMSAError(  # its executor would hang: a task resubmitted there never ends
            f"executor: the dask Client is {client.status}; pass a running Client"
        )
    if client is not None and not closed and getattr(client, "asynchronous", False):
        raise GPMSAError(  # its run() gives a coroutine here; waiting for the chains, a hang
            "executor: the dask Client is asynchronous and this thread runs its event loop, "
            "which waiting for the chains here would block for ever; call gpmsa from another "
            "thread (e.g. await asyncio.to_thread(...)) or pass a synchronous Client"
        )
    if client is not None and not closed and fn is not None:
        restrictions = {} if client is executor else getattr(executor, "_kwargs", {})
        _check_workers(client, fn.__module__, restrictions, WORKER_CHECK_S)
    if isinstance(executor, Executor):
        return executor
    if client is not None:
        return executor.get_executor()
    raise GPMSAError(
        f"executor must be a concurrent.futures.Executor or a dask Client, got {executor!r}"
    )


def _dask_client(executor):
    """The dask ``Client`` behind ``executor`` (a Client, or its ``get_executor()``), else None."""
    if callable(getattr(executor, "get_executor", None)):
        return executor
    client = getattr(executor, "_client", None)  # distributed's ClientExecutor
    return client if callable(getattr(client, "get_executor", None)) else None


def _all_workers(client) -> dict:
    """The scheduler's record of every worker of the dask ``client``: distributed 2025.4 and
    later list 5 unless asked ``n_workers=-1``; earlier releases take no such argument and list
    all."""
    try:
        return client.scheduler_info(n_workers=-1)["workers"]
    except TypeError as error:
        if "n_workers" not in str(error):
            raise
        return client.scheduler_info()["workers"]


def _check_workers(client, module: str, restrictions: dict, timeout_s: float) -> None:
    """GPMSAError unless every worker of the dask ``client`` that may run a task submitted with
    ``restrictions`` (a ``get_executor(...)``'s: `_task_workers`) imports ``module`` and runs
    this process's gpmsa version, all answering within ``timeout_s`` seconds. The versions must
    be equal, a development suffix included: the tasks' pickled functions and data, and the
    draws they return, may differ between any two versions. A worker that cannot be reached
    (lost meanwhile: an OSError such as dask's CommClosedError) is not refused: dask runs its
    tasks elsewhere, as it would without the check."""
    infos = _all_workers(client)
    workers = _task_workers(infos, restrictions)
    if not workers:  # none yet (dask waits for them, e.g. an adaptive cluster's)
        return
    answers = client.sync(_ask_workers, client, workers, module, timeout_s)
    failed, versions = [], {}
    for who, answer in answers.items():
        if isinstance(answer, OSError):
            continue
        if isinstance(answer, BaseException):  # e.g. gpmsa missing: `_worker_report` unpickled
            failed.append(f"{_describe(answer)}, on {who}")
        elif answer[0] is not None:
            failed.append(f"{answer[0]}, on {who}")
        elif answer[1] != _version.__version__:
            versions.setdefault(answer[1], []).append(who)
    ours = _version.__version__
    if failed:
        raise GPMSAError(
            f"executor: the dask Client's workers cannot import {module} ({'; '.join(failed)}); "
            f"install gpmsa {ours} (and, for the torch backend, torch) where they run, or pass "
            "n_jobs= to run the chains on this machine"
        )
    if versions:
        theirs = "; ".join(f"gpmsa {v} on {', '.join(sorted(w))}" for v, w in versions.items())
        raise GPMSAError(
            f"executor: the dask Client's workers run another gpmsa version than this process's "
            f"{ours} ({theirs}): the chains would run other code on other data; install gpmsa "
            f"{ours} where they run, or pass n_jobs= to run the chains on this machine"
        )
    silent = sorted(set(workers) - set(answers))
    if silent:
        raise GPMSAError(
            f"executor: the dask Client's workers {', '.join(silent)} did not answer within "
            f"{timeout_s:g} s (gpmsa.mcmc.parallel.WORKER_CHECK_S) whether they import {module}: "
            "hung (stopped, or busy in a call that holds its event loop) or slow to import; dask "
            "would give them chains that never end. Restart or retire them, raise WORKER_CHECK_S, "
            "or restrict the tasks to other workers (Client.get_executor(workers=[...]))"
        )


def _task_workers(infos: dict[str, dict], restrictions: dict) -> list[str]:
    """The addresses of the workers (``infos``: the scheduler's, by address) that may run a task
    submitted with ``restrictions`` (``workers``, ``resources``, ``allow_other_workers``, as
    ``Client.submit`` takes them), read as dask's scheduler reads them: ``workers`` one name,
    address or host (a string or a number), or a list, set or tuple of them, each a worker's
    name or address (a (host, port) tuple too), else a host; a worker has each resource asked,
    as much."""
    if restrictions.get("allow_other_workers"):  # any worker, where none of those fits
        return list(infos)
    out = list(infos)
    named = restrictions.get("workers")
    if named is not None:
        from distributed.comm.addressing import resolve_address, unparse_host_port

        names = {info.get("name"): addr for addr, info in infos.items()}
        addresses, hosts = set(), set()
        for entry in [named] if isinstance(named, str | Number) else named:  # Client.submit's
            if isinstance(entry, tuple):
                entry = unparse_host_port(*entry)
            if entry in names:
                addresses.add(names[entry])
                continue
            try:
                addresses.add(resolve_address(entry))
            except (ValueError, TypeError):  # no port: a host (a number: no worker)
                hosts.add(entry)
        out = [a for a in out if a in addresses or infos[a].get("host") in hosts]
    needs = restrictions.get("resources") or {}
    has = {a: infos[a].get("resources") or {} for a in out}
    return [a for a in out if all(has[a].get(r, 0) >= amount for r, amount in needs.items())]


async def _ask_workers(client, workers: list[str], module: str, timeout_s: float) -> dict:
    """Each of ``workers``' `_worker_report` on ``module`` (or the exception that came instead),
    by address, for those that answered within ``timeout_s`` seconds; run in the Client's
    event loop (``Client.sync``), one call a worker so that a hung one delays no other."""

    async def ask(who: str):
        got = await client.run(
            _worker_report, module, workers=[who], on_error="return", asynchronous=True
        )
        return got[who]

    asked = {asyncio.ensure_future(ask(who)): who for who in workers}
    done, late = await asyncio.wait(asked, timeout=timeout_s)
    for fut in late:
        fut.cancel()
    return {asked[fut]: fut.exception() or fut.result() for fut in done}


def _worker_report(module: str) -> tuple[str | None, str]:
    """(None where ``module`` imports here, else why not; this process's gpmsa version): what
    each dask worker answers `_check_workers`."""
    return _importable(module), _version.__version__


def _importable(module: str) -> str | None:
    """None where ``module`` imports here, else why not (an import may fail with any error, an
    OSError for a missing shared library too)."""
    try:
        importlib.import_module(module)
    except Exception as exc:
        return _describe(exc)
    return None


_forking_thread: int | None = None
"""The thread of this process that forks one of gpmsa's own pool workers, while it does (read in
the child, whose one thread is the one that forked: another thread's fork meanwhile is not
ours)."""


def _freeze_inherited() -> None:
    """In a forked worker, put every object inherited from the parent beyond the garbage
    collector's reach (`gc.freeze`). The parent's uncollected garbage may hold another pool's
    executor whose weakref callback takes a lock that one of the parent's threads held at the
    fork (CPython's ``concurrent.futures.process``): collected in the child, it would wait for
    that lock forever. Runs before any Python code of the child; what the chain creates is
    collected as usual. Any child forgets the flag: its own forks are not gpmsa's workers."""
    global _forking_thread
    if _forking_thread is not None and _forking_thread == threading.get_ident():
        gc.freeze()
    _forking_thread = None


if sys.platform == "linux":  # where `_own_pool` forks (Windows has no ForkProcess)
    os.register_at_fork(after_in_child=_freeze_inherited)

    class _WorkerProcess(multiprocessing.context.ForkProcess):
        """A fork-started pool worker whose child freezes what it inherits
        (`_freeze_inherited`)."""

        @staticmethod
        def _Popen(process_obj):
            global _forking_thread
            _forking_thread = threading.get_ident()
            try:
                return multiprocessing.context.ForkProcess._Popen(process_obj)
            finally:
                _forking_thread = None

    class _WorkerContext(multiprocessing.context.ForkContext):
        Process = _WorkerProcess


def _own_pool(workers: int) -> ProcessPoolExecutor:
    # fork where it exists (Linux): a worker starts in ~0.05 s against ~2 s for forkserver or
    # spawn, which re-import numpy and scipy. The workers run numpy only, one BLAS thread.
    ctx = _WorkerContext() if sys.platform == "linux" else multiprocessing.get_context()
    started = None if ctx.get_start_method() == "fork" else ctx.Value("b", 0, lock=False)
    pool = ProcessPoolExecutor(max_workers=workers, mp_context=ctx, initializer=end_with_parent,
                               initargs=(os.getpid(), started))  # fmt: skip
    pool.gpmsa_started = started  # read by `_start_failure`
    return pool


_PR_SET_PDEATHSIG = 1
"""Linux's prctl option: the signal a process gets when its parent ends."""


def end_with_parent(owner: int | None = None, started=None) -> None:
    """A pool worker's initializer: set the shared flag ``started`` (a ``Value``; None: none) to
    1, and end this worker when ``owner`` (the process whose pool it serves; None: its parent)
    ends. (Spawn and forkserver run the main script before the initializer: a worker that set
    the flag got past it.) A parent killed (SIGTERM, SIGKILL, the OOM killer: its cleanup
    never runs) would leave its pool's workers waiting for tasks for ever, each holding a copy of
    its memory. On Linux, where the owner started the worker itself, the kernel kills the worker
    then (prctl PR_SET_PDEATHSIG); elsewhere on POSIX, and where a forkserver started it (its
    parent, which outlives the owner while any worker holds its pipe), a thread checks the
    parent and the owner each second (on Windows none: a process's parent id there is not
    updated when the parent ends). The kernel's signal follows the thread that started the
    worker: the one that calls and waits for the pool, which outlives it."""
    if started is not None:
        started.value = 1
    parent = os.getppid()
    owner = parent if owner is None else owner
    if sys.platform == "linux" and owner == parent:
        try:
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            if libc.prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) == 0:
                if os.getppid() != parent:  # it ended before the call
                    os._exit(1)
                return
        except (OSError, AttributeError):  # no libc.prctl: watch as elsewhere
            pass
    if sys.platform == "win32":  # os.getppid() keeps the ended parent's id: nothing to watch
        return
    threading.Thread(target=_watch_parent, args=(parent, owner), name="gpmsa-end-with-parent",
                     daemon=True).start()  # fmt: skip


def _watch_parent(parent: int, owner: int) -> None:
    ended = _ended(owner)
    while os.getppid() == parent and not ended():
        time.sleep(1.0)
    os._exit(1)


def _ended(pid: int) -> Callable[[], bool]:
    """A test whether process ``pid`` has ended: on Linux by a pidfd, readable once it ended,
    before its parent reaps it (a killed owner whose parent does not wait for it stays a
    zombie), and never by another process that reuses the id; elsewhere by `_alive`."""
    try:
        fd = os.pidfd_open(pid)
    except ProcessLookupError:
        return lambda: True
    except (AttributeError, OSError):  # not Linux, or a kernel before 5.3
        return lambda: not _alive(pid)
    poller = select.poll()
    poller.register(fd, select.POLLIN)
    return lambda: bool(poller.poll(0))


def _alive(pid: int) -> bool:
    """Whether process ``pid`` exists."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's
        pass
    return True


_JOIN_S = 5.0
"""Seconds to wait for a terminated worker process to exit."""

_POLL_S = 0.25
"""Seconds between the main thread's checks for an interrupt while chains run. The kernel may
hand a process's SIGINT (Ctrl-C) to any of its threads, BLAS's or the pool's; Python acts on it
in the main thread only, and a wait without a timeout would hold it until a chain ends."""


_STUCK_S = 2.0
"""Seconds a worker of our own pool may have ended while the pool is not marked broken before
the wait takes the pool as broken (`_ended_mid_send`); the pool marks itself broken within
milliseconds of a worker's end unless its manager thread is reading a result that worker was
sending."""


def _ended_mid_send(pool: ProcessPoolExecutor, first_seen: list[float]) -> bool:
    """Whether a worker of our own ``pool`` has been seen ended for `_STUCK_S` while the pool is
    not marked broken (``first_seen``: [] or [when it was first seen, ``time.monotonic``],
    updated). A worker killed while it sent a chain's draws (the OOM killer, ``kill -9``) leaves
    the pool's manager thread reading the rest of that message for ever: it never marks the pool
    broken, and the chain's future never finishes (`_stop`, called then, ends the manager)."""
    sentinels = [p.sentinel for p in (getattr(pool, "_processes", None) or {}).values()]
    if getattr(pool, "_broken", False) or not sentinels:
        first_seen.clear()
        return False
    if not multiprocessing.connection.wait(sentinels, timeout=0):
        first_seen.clear()
        return False
    if not first_seen:
        first_seen.append(time.monotonic())
    return time.monotonic() - first_seen[0] >= _STUCK_S


def _stop(pool: ProcessPoolExecutor) -> None:
    """Shut our pool down at once: cancel the chains not started and end the workers still
    running one (``terminate_workers`` of Python 3.14), so that a failed or interrupted run
    leaves no process computing chains nobody will read."""
    processes = list((getattr(pool, "_processes", None) or {}).values())
    manager = getattr(pool, "_executor_manager_thread", None)  # shutdown forgets it
    results = getattr(pool, "_result_queue", None)  # this too
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in processes:
        if proc.is_alive():
            proc.terminate()
    for proc in processes:
        proc.join(timeout=_JOIN_S)
    if all(not proc.is_alive() for proc in processes):
        _close_writer(results)
    if manager is not None:  # it takes the pool's locks: a fork while it runs inherits them
        manager.join(timeout=_JOIN_S)


def _close_writer(results: object) -> None:
    """Close this process's end of a pool's result pipe (its workers all ended): a worker ended
    while it sent a result leaves the rest of that message unwritten, and the pool's manager
    thread would wait for it for ever (the interpreter joins that thread at exit: it would never
    end); with no writer left it reads an end of file, and winds down as after any broken
    worker. Nothing in this process writes there."""
    writer = getattr(results, "_writer", None)
    if writer is not None:
        writer.close()


def _start_failure(pool: ProcessPoolExecutor) -> str | None:
    """Why our ``pool`` broke, where a worker started by spawn or forkserver (not fork) ended with
    an error (exit code > 0) while it started: it runs the main script again (as
    ``"__mp_main__"``), which fails where the script calls gpmsa outside an
    ``if __name__ == "__main__":`` block or was read from standard input; else None (also where
    a worker got past the main script, its flag ``pool.gpmsa_started`` set: one that ended in a
    chain, by ``exit(1)`` in a library, is retried)."""
    context = getattr(pool, "_mp_context", None)
    method = context.get_start_method() if context is not None else "fork"
    started = getattr(pool, "gpmsa_started", None)
    if method == "fork" or (started is not None and started.value):
        return None
    manager = getattr(pool, "_executor_manager_thread", None)
    if manager is not None:  # it joins the workers: a worker may not have ended quite yet
        manager.join(timeout=_JOIN_S)
    codes = [p.exitcode for p in (getattr(pool, "_processes", None) or {}).values()]
    code = next((c for c in codes if c is not None and c > 0), None)
    if code is None:
        return None
    main = sys.modules.get("__main__")
    path = getattr(main, "__file__", None)
    if getattr(main, "__spec__", None) is None and path is not None and not os.path.isfile(path):
        fix = f"a script read from {path} cannot be read again: save it as a file and run that"
    else:
        where = f" of {path}" if path is not None else ""
        fix = f'call gpmsa inside an `if __name__ == "__main__":` block{where}'
    return (
        f"a worker process ended while starting (exit code {code}; its error is above, on "
        f"stderr). The workers start by {method!r} (this platform's default, or "
        f"multiprocessing.set_start_method's choice), which runs the main script again in each: "
        f"{fix}; or give n_jobs=1 (the chains then run here, with the same draws)"
    )


def _closed(exc: BaseException) -> bool:
    """Whether ``exc``, raised by an executor's ``submit``, says the executor is shut down or
    its dask Client closed (no retry can help; dask would even accept the next task, never to
    run it)."""
    return "shutdown" in str(exc) or type(exc).__name__ == "ClosedClientError"


def _describe(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__


def run_chains(
    fn: Callable,
    tasks: Sequence[dict],
    *,
    n_jobs: int | None = None,
    executor=None,
    progress: bool = False,
    desc: str = "chains",
    retries: int = RETRIES,
    what: str = "chain",
    check: Callable[[int, object], str | None] | None = None,
) -> list:
    """``[fn(**task, progress=..., desc=...) for task in tasks]``, the tasks run in parallel.

    ``fn`` must be a module-level function (it is pickled by reference) taking ``progress`` and
    ``desc`` keywords; ``tasks`` one dict of picklable keyword arguments per chain. ``n_jobs``:
    worker processes (None: every CPU; never more than the chains); ``executor``: any
    ``concurrent.futures.Executor`` or a dask ``Client`` instead (``n_jobs`` must then be None).
    ``progress``: in this process, each chain's own bar; in parallel, one bar over the chains.
    Returns the results in chain order. Raises ChainError naming the failed chain (see the
    module docstring for retries); ``what`` is what a task is called there ("chain").
    ``check(i, result)``: None when task i's result is its own, else the draws it should hold
    (e.g. "60 sweeps"): an executor returned something else; ChainError names the first such
    chain.
    """
    n = len(tasks)
    if executor is not None and n_jobs is not None:
        raise GPMSAError("give n_jobs or executor, not both (n_jobs sizes gpmsa's own pool)")
    executor = as_executor(executor, fn)
    if not isinstance(retries, int) or retries < 0:
        raise GPMSAError(f"retries must be an integer >= 0, got {retries!r}")
    workers = 1 if executor is not None else n_workers(n_jobs, n)
    if executor is None and workers == 1:
        results = [_in_process(fn, task, i, n, progress, desc, what)
                   for i, task in enumerate(tasks)]  # fmt: skip
    else:
        results = _parallel(fn, tasks, executor, workers, progress, desc, retries, what)
    for i, result in enumerate(results if check is not None else ()):
        expected = check(i, result)
        if expected is not None:
            raise ChainError(
                f"{what} {i} of {n} returned a {type(result).__name__} that is not its draws "
                f"({expected}); an executor must return each task's own result",
                (i,),
            )
    return results


def _in_process(fn, task, i, n, progress, desc, what):
    try:
        return fn(**task, progress=progress, desc=f"{desc} {i + 1}/{n}")
    except Exception as exc:
        raise ChainError(f"{what} {i} of {n} failed: {_describe(exc)}", (i,)) from exc


def _parallel(fn, tasks, executor, workers, progress, desc, retries, what):
    n = len(tasks)
    own = executor is None
    pool = _own_pool(workers) if own else executor
    results: list = [None] * n
    attempts = [0] * n
    running: dict[Future, int] = {}
    bar = progress_bar(progress, n, desc, what, mininterval=0.1)  # no thread beside the forks

    def submit(i: int) -> None:
        attempts[i] += 1
        running[pool.submit(fn, **tasks[i], progress=False, desc=f"{desc} {i + 1}/{n}")] = i

    def retry_or_raise(i: int, exc: BaseException) -> None:
        nonlocal pool
        broken = own and isinstance(exc, BrokenExecutor)  # a dead worker breaks the whole pool
        why = _start_failure(pool) if broken else None
        if why is not None:  # a fresh pool's workers would end the same way
            raise ChainError(f"{what} {i} of {n} failed: {why}", (i,)) from exc
        if isinstance(exc, GPMSAError) or attempts[i] > retries:
            tries = f" after {attempts[i]} attempts" if attempts[i] > 1 else ""
            raise ChainError(f"{what} {i} of {n} failed{tries}: {_describe(exc)}", (i,)) from exc
        warnings.warn(
            f"{what} {i} of {n} failed ({_describe(exc)}); running it again (same seed, same "
            f"draws)", ChainRetryWarning, stacklevel=user_stacklevel(),
        )  # fmt: skip
        if broken:
            _stop(pool)
            pool = _own_pool(workers)
            others = list(running.items())
            running.clear()
            for fut, j in others:
                if fut.done() and not fut.cancelled() and fut.exception() is None:
                    results[j] = fut.result()  # finished before the pool broke
                    bar.update()
                else:  # died with the pool: run again, not counted as an attempt of its own
                    attempts[j] -= 1
                    _submit_checked(j)
        _submit_checked(i)

    def _submit_checked(i: int) -> None:
        try:
            submit(i)
        except Exception as exc:  # the executor refused the task
            if not own and _closed(exc):  # a transient refusal is retried
                raise GPMSAError(
                    f"the executor refused {what} {i} of {n}: {_describe(exc)}; pass an "
                    "executor that is running"
                ) from exc
            retry_or_raise(i, exc)

    try:
        for i in range(n):
            _submit_checked(i)
        first_seen: list[float] = []
        while running:
            done, _ = wait(list(running), timeout=_POLL_S, return_when=FIRST_COMPLETED)
            if not done and own and _ended_mid_send(pool, first_seen):
                first_seen.clear()
                fut, i = next(iter(running.items()))  # the pool is broken: as after any death
                del running[fut]
                retry_or_raise(i, BrokenProcessPool(
                    "a worker process ended while it sent a result (killed: out of memory?)"
                ))  # fmt: skip
                continue
            for fut in done:
                i = running.pop(fut, None)
                if i is None:  # resubmitted after its pool broke
                    continue
                try:
                    results[i] = fut.result()
                except Exception as exc:
                    retry_or_raise(i, exc)
                    continue
                bar.update()
    except BaseException:
        for fut in running:
            fut.cancel()
        if own:
            _stop(pool)
        raise
    finally:
        bar.close()
    if own:
        pool.shutdown()
    return results
