"""Processes in tests: whether one runs, and that workers end once their parent was killed."""

from __future__ import annotations

import multiprocessing.context
import os
import signal
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
