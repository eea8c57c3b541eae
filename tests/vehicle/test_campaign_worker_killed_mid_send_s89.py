"""A campaign worker killed while it sends its run's result (the OOM killer, a `kill -9`), with no
interrupt or error to stop the pool, left the pool's manager thread reading the rest of that
message for ever, and the campaign waiting for ever on a run that would never finish. The wait
now sees a worker of its own pool ended while the pool is not marked broken, and raises (the
pool is then stopped: no process and no thread left)."""

import multiprocessing
import sys
import threading
from concurrent.futures import BrokenExecutor, ProcessPoolExecutor

import pytest
from _processes import half_result_then_die

from vehicle import campaign


@pytest.mark.skipif(sys.platform != "linux", reason="a forked worker")
def test_the_wait_gives_up_on_a_worker_killed_mid_send(monkeypatch):
    monkeypatch.setattr(campaign, "_STUCK_S", 0.5)
    pool = ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("fork"))
    manager = None
    rescue = threading.Timer(60.0, lambda: pool._result_queue._writer.close())  # no hang
    rescue.start()
    try:
        futures = {pool.submit(half_result_then_die): 0}
        manager = pool._executor_manager_thread
        with pytest.raises(BrokenExecutor, match="ended while it sent"):
            for _ in campaign._completed(futures, pool):
                pass
    finally:
        rescue.cancel()
        campaign._stop(pool)
    assert not manager.is_alive()
    assert not multiprocessing.active_children()


@pytest.mark.skipif(
    multiprocessing.get_start_method() != "fork", reason="the stand-in reaches forked workers"
)
def test_a_campaign_whose_worker_is_killed_mid_send_raises_instead_of_waiting(monkeypatch):
    import numpy as np

    import vehicle

    monkeypatch.setattr(campaign, "_STUCK_S", 0.5)
    monkeypatch.setattr(campaign, "run_one", half_result_then_die)
    with pytest.raises(BrokenExecutor, match="ended while it sent"):
        vehicle.run_campaign(
            np.array([[0.7, 250.0], [1.6, 550.0]]), road_length_m=6.0, window=300,
            lead_in_m=0.5, progress=False, seed=1,
        )  # fmt: skip
    assert not multiprocessing.active_children()
    assert not [t for t in threading.enumerate() if "Executor" in type(t).__name__]
