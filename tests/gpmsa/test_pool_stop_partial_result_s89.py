"""A worker ended while it sends its result (a chain's draws, megabytes: Ctrl-C or an error
elsewhere reaches `_stop` mid-send) left the pool's manager thread reading the rest of the message
for ever: `_stop` waited 5 s for it, and the interpreter, which joins that thread at exit, never
ended. `_stop` now closes the pool's own end of the result pipe once the workers are gone, so the
manager thread reads an end of file and winds down."""

import multiprocessing
import os
import struct
import sys
import time

import pytest

from gpmsa.mcmc import parallel

_writer_fd: list[int] = []
"""The result pipe's write end, inherited by the forked worker."""


def send_half_a_result(marker: str) -> None:
    """Write the header of a 1 MiB message and 10 of its bytes to the result pipe, as a worker
    cut off mid-send leaves it, then wait to be ended."""
    os.write(_writer_fd[0], struct.pack("!i", 1 << 20) + b"x" * 10)
    with open(marker, "w"):
        pass
    time.sleep(60.0)


def wait_for(path: str, seconds: float = 60.0) -> None:
    deadline = time.monotonic() + seconds
    while not os.path.exists(path):
        assert time.monotonic() < deadline, "the worker never wrote its part of a result"
        time.sleep(0.01)


@pytest.mark.skipif(sys.platform != "linux", reason="the stand-in reaches forked workers (Linux)")
def test_a_worker_ended_mid_send_leaves_no_manager_thread(tmp_path):
    pool = parallel._own_pool(1)
    _writer_fd[:] = [pool._result_queue._writer.fileno()]
    marker = str(tmp_path / "sent")
    future = pool.submit(send_half_a_result, marker)
    wait_for(marker)
    manager = pool._executor_manager_thread
    parallel._stop(pool)
    assert not manager.is_alive()  # alive, reading for ever, before
    assert future.done()
    assert not multiprocessing.active_children()
