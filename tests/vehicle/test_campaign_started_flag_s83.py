"""run_campaign's own pool under spawn or forkserver tells a worker that ended while starting
from one that ended in a run, and its workers end with a campaign killed and left unreaped
(session 83 review).

Before: a worker that got past the main script and then ended with exit code 1 in a run (a
library's ``exit(1)``) was named "a campaign worker process ended while starting ... call
run_campaign inside an ``if __name__ == "__main__":`` block" (under fork: the
BrokenProcessPool); and a forkserver's worker whose campaign was killed but not yet reaped by
its parent (a zombie) kept running: ``os.kill(pid, 0)`` finds a zombie.
(The watchers' tests: tests/test_pool_watchers_s83.py.)"""

import os
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool

import numpy as np
import pytest

import vehicle
from tests._processes import ForkNamedSpawn
from vehicle import campaign

pytestmark = pytest.mark.skipif(not hasattr(os, "fork"), reason="the stand-in pool forks")


def _ends_in_the_run(spec, cache):
    os._exit(1)  # a started worker that ends in its run


def test_a_started_worker_that_ends_in_a_run_is_not_named_a_start_failure(monkeypatch):
    context = ForkNamedSpawn()

    def pool(max_workers, initializer, initargs):
        return ProcessPoolExecutor(max_workers, mp_context=context, initializer=initializer,
                                   initargs=initargs)  # fmt: skip

    monkeypatch.setattr(campaign.multiprocessing, "get_context", lambda: context)
    monkeypatch.setattr(campaign, "ProcessPoolExecutor", pool)
    monkeypatch.setattr(campaign, "run_one", _ends_in_the_run)
    with pytest.raises(BrokenProcessPool):
        vehicle.run_campaign(np.array([[0.5, 200.0]]), road_length_m=4.0, window=100,
                             progress=False)  # fmt: skip
