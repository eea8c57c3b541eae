"""A chain's worker killed while it sends its draws (the OOM killer, a `kill -9`), with no
interrupt or error to stop the pool, left the pool's manager thread reading the rest of that
message for ever, and `run_chains` waiting for ever. The wait now sees a worker of its own pool
ended while the pool is not marked broken, and takes the pool as broken: the chains run again
(same seeds, same draws), as after any worker's death."""

import multiprocessing
import os
import sys

import pytest
from _processes import half_result_then_die

from gpmsa.mcmc import parallel


def half_send_once(x, marker, progress=False, desc=""):
    """Chain 1's first attempt writes the header of a 1 MiB result and 10 of its bytes to the
    pool's result pipe, as a worker killed mid-send leaves it, and dies as the OOM killer ends
    a process; every other run returns 2 x."""
    if x == 1 and not os.path.exists(marker):
        open(marker, "w").close()
        half_result_then_die()
    return 2 * x


@pytest.mark.skipif(sys.platform != "linux", reason="forked workers (Linux)")
@pytest.mark.skipif(parallel.available_cpus() < 2, reason="needs two CPUs for a pool")
def test_a_worker_killed_mid_send_breaks_the_pool_and_the_chains_run_again(tmp_path, monkeypatch):
    monkeypatch.setattr(parallel, "_STUCK_S", 0.5)
    marker = str(tmp_path / "died")
    tasks = [{"x": i, "marker": marker} for i in range(3)]
    with pytest.warns(RuntimeWarning, match="ended while it sent"):
        got = parallel.run_chains(half_send_once, tasks, n_jobs=2)
    assert got == [0, 2, 4] and os.path.exists(marker)
    assert not multiprocessing.active_children()
