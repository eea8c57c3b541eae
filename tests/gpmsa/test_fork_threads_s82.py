"""gpmsa forks its chains' workers with no thread of its own running: tqdm starts a monitor
thread ("tqdm_monitor") with its first bar, a disabled one too, and keeps it; a pool forked
beside it gives Python >= 3.12's DeprecationWarning ("This process is multi-threaded, use of
fork() may lead to deadlocks in the child") and a rare real deadlock. Without ``progress`` no
tqdm object is made; with it, the bar is a tqdm subclass without the monitor; tqdm's own class
is left as it was.

Before (session 82): ``gpmsa.fit(..., n_chains=2, n_jobs=2)`` forked each worker beside
tqdm_monitor, progress on or off (2 DeprecationWarnings a fit on Python 3.13)."""

import os
import warnings

import numpy as np
import pytest
import tqdm.auto
import tqdm.std

import gpmsa
from gpmsa._progress import NoBar, progress_bar


def _data():
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(10, 1)), rng.uniform(size=(10, 1))
    return gpmsa.SimData(x=x, t=t, y=np.sin(3 * x) + t)


@pytest.mark.skipif(not hasattr(os, "fork"), reason="no fork on this platform")
@pytest.mark.parametrize("progress", [False, True])
def test_the_chains_workers_fork_with_no_other_thread(forks, progress, capsys):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        gpmsa.fit(_data(), n_iter=20, seed=1, progress=progress)  # one chain here: its bar
        gpmsa.fit(_data(), n_iter=20, n_chains=2, n_jobs=2, seed=1, progress=progress)
    assert forks == [[], []]  # two workers, forked beside no thread started here
    assert ("chain: 100%" in capsys.readouterr().err) is progress
    assert tqdm.auto.tqdm.monitor_interval == tqdm.std.tqdm.monitor_interval == 10


def test_no_progress_makes_no_tqdm_bar():
    bar = progress_bar(False, 5, "fit")
    assert isinstance(bar, NoBar)
    with bar:
        bar.set_description("fit: tuning")
        bar.update()
        bar.update(3)
    assert (bar.n, bar.total) == (4, 5)
    shown = progress_bar(True, 2, "fit", "it")
    shown.close()
    assert isinstance(shown, tqdm.auto.tqdm) and type(shown).monitor_interval == 0
