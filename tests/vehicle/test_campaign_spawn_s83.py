"""run_campaign's own pool where its workers start by spawn or forkserver (Python 3.14's default
on Linux, macOS's, or multiprocessing.set_start_method's choice): each worker runs the main
script again.

Before (session 83): a script that ran the campaign outside an ``if __name__ == "__main__":``
block, or read from standard input, gave a bare "BrokenProcessPool: A process in the process pool
was terminated abruptly" from inside concurrent.futures; and a forkserver's workers watched the
forkserver, which outlives a killed campaign while any worker holds its pipe: they outlived it.
(The watchers' tests: tests/test_pool_watchers_s83.py.)"""

import os
import sys
import types
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pytest

import vehicle
from tests._processes import ForkNamedForkserver, ends_while_starting
from vehicle import campaign

pytestmark = pytest.mark.skipif(not hasattr(os, "fork"), reason="the stand-in pool forks")


def test_a_worker_that_ends_while_starting_names_the_main_guard(monkeypatch):
    def pool(max_workers, initializer, initargs):
        return ProcessPoolExecutor(max_workers, mp_context=ForkNamedForkserver(),
                                   initializer=ends_while_starting, initargs=initargs)  # fmt: skip

    script = types.ModuleType("__main__")
    script.__file__, script.__spec__ = __file__, None
    monkeypatch.setitem(sys.modules, "__main__", script)
    monkeypatch.setattr(campaign, "ProcessPoolExecutor", pool)
    with pytest.raises(vehicle.VehicleError, match="ended while starting") as info:
        vehicle.run_campaign(np.array([[0.5, 200.0]]), road_length_m=4.0, window=100,
                             progress=False)  # fmt: skip
    message = str(info.value)
    assert "'forkserver'" in message and 'if __name__ == "__main__":' in message
    assert __file__ in message
