"""A worker ended while it sends its result (a chain's draws, megabytes: Ctrl-C or an error
elsewhere reaches `_stop` mid-send) left the pool's manager thread reading the rest of the message
for ever: `_stop` waited 5 s for it, and the interpreter, which joins that thread at exit, never
ended. `_stop` now closes the pool's own end of the result pipe once the workers are gone, so the
manager thread reads an end of file and winds down."""

import multiprocessing
import sys

import pytest
from _processes import half_result_then_wait, wait_for

from gpmsa.mcmc import parallel


@pytest.mark.skipif(sys.platform != "linux", reason="the stand-in reaches forked workers (Linux)")
def test_a_worker_ended_mid_send_leaves_no_manager_thread(tmp_path):
    pool = parallel._own_pool(1)
    marker = str(tmp_path / "sent")
    future = pool.submit(half_result_then_wait, marker)
    wait_for(marker)
    manager = pool._executor_manager_thread
    parallel._stop(pool)
    assert not manager.is_alive()  # alive, reading for ever, before
    assert future.done()
    assert not multiprocessing.active_children()
