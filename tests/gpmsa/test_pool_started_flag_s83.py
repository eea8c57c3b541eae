"""gpmsa's own pool under spawn or forkserver tells a worker that ended while starting from one
that ended in a chain, and its workers end with an owner killed and left unreaped (session 83
review).

Before: a worker that got past the main script and then ended with exit code 1 in a chain (a
library's ``exit(1)``, as OpenBLAS's on too many threads) was named "a worker process ended
while starting ... call gpmsa inside an ``if __name__ == "__main__":`` block" and not retried
(under fork the same death is retried); and a forkserver's worker whose owner was killed but
not yet reaped by its parent (a zombie) kept running: ``os.kill(pid, 0)`` finds a zombie.
(The watchers' tests: tests/test_pool_watchers_s83.py.)"""

import os

import pytest

from gpmsa.mcmc import parallel
from tests._processes import ForkNamedSpawn

pytestmark = pytest.mark.skipif(not hasattr(os, "fork"), reason="the stand-in pool forks")


def _ends_once(x, marker, progress=False, desc=""):
    if x == 1 and not os.path.exists(marker):
        open(marker, "w").close()
        os._exit(1)  # a started worker that ends in the chain
    return x


def test_a_started_worker_that_ends_in_a_chain_is_retried(monkeypatch, tmp_path):
    monkeypatch.setattr(parallel, "_WorkerContext", ForkNamedSpawn)
    marker = str(tmp_path / "ended")
    tasks = [{"x": i, "marker": marker} for i in range(2)]
    with pytest.warns(parallel.ChainRetryWarning, match="BrokenProcessPool"):
        assert parallel.run_chains(_ends_once, tasks, n_jobs=2) == [0, 1]
