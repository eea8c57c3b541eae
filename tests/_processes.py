"""Processes in tests: whether one runs, and that workers end once their parent was killed."""

from __future__ import annotations

import multiprocessing.context
import os
import signal
import struct
import sys
import time


class ForkNamedSpawn(multiprocessing.context.ForkContext):
    """Forks (fast) but says 'spawn': the parent reads the start method from the context."""

    _name = "spawn"


class ForkNamedForkserver(multiprocessing.context.ForkContext):
    """Forks (fast) but says 'forkserver': the parent reads the start method from the context."""

    _name = "forkserver"


def ends_while_starting(*_initargs) -> None:
    """A worker initializer that ends as one whose import of the main script failed."""
    os._exit(1)


def alive(pid: int) -> bool:
    """Whether ``pid`` runs (not a zombie: reparented, init reaps it); Linux's /proc."""
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()[0] != "Z"
    except FileNotFoundError:
        return False


def assert_workers_end(workers: list[int], wait_s: float = 30.0) -> None:
    """Assert that every pid of ``workers`` ends within ``wait_s`` (the kernel signals them as
    their killed parent ends); those still running afterwards are killed."""
    try:
        deadline = time.monotonic() + wait_s
        while any(map(alive, workers)) and time.monotonic() < deadline:
            time.sleep(0.02)
        assert not [w for w in workers if alive(w)], f"workers {workers} outlived their parent"
    finally:
        for w in workers:
            if alive(w):
                os.kill(w, signal.SIGKILL)


def send_half_a_result() -> None:
    """In a worker of a ``concurrent.futures`` process pool: write the header of a 1 MiB result
    and 10 of its bytes to the pool's result pipe, as a worker cut off while it sends a result
    leaves it (the pool's manager thread then waits for the rest)."""
    frame = sys._getframe()
    while frame.f_code.co_name != "_process_worker":
        frame = frame.f_back
    writer = frame.f_locals["result_queue"]._writer
    os.write(writer.fileno(), struct.pack("!i", 1 << 20) + b"x" * 10)


def half_result_then_wait(marker: str) -> None:
    """`send_half_a_result`, create the file ``marker``, then wait to be ended (60 s)."""
    send_half_a_result()
    with open(marker, "w"):
        pass
    time.sleep(60.0)


def half_result_then_die(*_args, **_kwargs) -> None:
    """`send_half_a_result`, then die as the OOM killer ends a process (SIGKILL)."""
    send_half_a_result()
    os.kill(os.getpid(), signal.SIGKILL)


def wait_for(path: str, seconds: float = 60.0) -> None:
    """Wait until the file ``path`` exists (AssertionError after ``seconds``)."""
    deadline = time.monotonic() + seconds
    while not os.path.exists(path):
        assert time.monotonic() < deadline, f"{path} never appeared"
        time.sleep(0.01)
