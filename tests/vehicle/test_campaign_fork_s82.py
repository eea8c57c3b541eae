"""run_campaign forks its pool's workers with no thread of its own running: tqdm starts a
monitor thread with its first bar, a disabled one too, and keeps it; a pool forked beside it
gives Python >= 3.12's DeprecationWarning ("This process is multi-threaded, use of fork() may
lead to deadlocks in the child") and a rare real deadlock. Without ``progress`` no tqdm object is
made; with it (the default), the bar is a tqdm subclass without the monitor.

Before (session 82): each worker forked beside tqdm_monitor, progress on or off (2
DeprecationWarnings a two-run campaign on Python 3.13)."""

import multiprocessing
import os

import numpy as np
import pytest
import tqdm.auto
import tqdm.std

import vehicle

DESIGN = np.array([[0.5, 200.0], [0.8, 400.0]])


@pytest.mark.skipif(not hasattr(os, "fork"), reason="no fork on this platform")
@pytest.mark.parametrize("progress", [False, True])
def test_the_campaign_workers_fork_with_no_other_thread(forks, progress, capsys):
    c = vehicle.run_campaign(DESIGN, road_length_m=4.0, window=100, progress=progress)
    assert c.f_full.shape == (2,) and np.isfinite(c.f_full).all()
    if multiprocessing.get_start_method() == "fork":  # Linux before Python 3.14
        assert forks and len(forks) <= 2  # a worker per run, at most the CPUs
    assert all(names == [] for names in forks)  # forked beside no thread started here
    assert ("campaign jackal: 100%" in capsys.readouterr().err.lower()) is progress
    assert tqdm.auto.tqdm.monitor_interval == 10
