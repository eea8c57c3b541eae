"""run_campaign's own pool, broken by a worker that ended while starting before every run was
submitted: the next ``submit`` refuses (BrokenProcessPool) and the campaign says why, as it does
where the break shows in a run's result.

Before (session 84): the submit loop lay outside the start-failure handler, so a campaign of many
runs whose spawn or forkserver workers failed to start (a script without the main guard) could
still end in a bare "BrokenProcessPool: A child process terminated abruptly" from inside
concurrent.futures (a race with the pool's manager thread; made certain here)."""

import os
import sys
import time
import types
from concurrent.futures import ProcessPoolExecutor

import numpy as np
import pytest

import vehicle
from tests._processes import ForkNamedSpawn, ends_while_starting
from vehicle import campaign

pytestmark = pytest.mark.skipif(not hasattr(os, "fork"), reason="the stand-in pool forks")


class _BreaksBeforeTheSecondSubmit(ProcessPoolExecutor):
    """Waits, before every submit after the first, until the pool knows it is broken."""

    def submit(self, fn, /, *args, **kwargs):
        if getattr(self, "_submitted", False):
            deadline = time.monotonic() + 20.0
            while not self._broken and time.monotonic() < deadline:
                time.sleep(0.01)
        self._submitted = True
        return super().submit(fn, *args, **kwargs)


def test_a_pool_broken_while_runs_are_submitted_names_the_main_guard(monkeypatch):
    def pool(max_workers, initializer, initargs):
        return _BreaksBeforeTheSecondSubmit(max_workers, mp_context=ForkNamedSpawn(),
                                            initializer=ends_while_starting,
                                            initargs=initargs)  # fmt: skip

    script = types.ModuleType("__main__")
    script.__file__, script.__spec__ = __file__, None
    monkeypatch.setitem(sys.modules, "__main__", script)
    monkeypatch.setattr(campaign, "ProcessPoolExecutor", pool)
    design = np.array([[0.5, 200.0], [0.6, 300.0], [0.7, 400.0]])
    with pytest.raises(vehicle.VehicleError, match="ended while starting") as info:
        vehicle.run_campaign(design, road_length_m=4.0, window=100, progress=False)
    assert "'spawn'" in str(info.value) and 'if __name__ == "__main__":' in str(info.value)
