"""An interrupt that reaches the campaign's process alone (a notebook's interrupt button, `kill
-INT`: a terminal's Ctrl-C signals the workers too) ended the campaign only once every running
simulation had finished: with 1,700 m runs at 0.5 m/s, 24 s after the signal. The running runs
are now cut off and the workers ended (0.6 s); a run cut off leaves no cache entry.

The test installs Python's SIGINT handler for its run: a process started with SIGINT ignored
(a background job of a non-interactive shell, `cmd &`: how session 90's and 93's failing
fresh-clone runs were started) keeps it ignored, and `_thread.interrupt_main` then does
nothing, so the interrupt never came."""

import _thread
import multiprocessing
import os
import signal
import threading
import time

import numpy as np
import pytest

import vehicle
from vehicle import campaign

RUN_S = 20.0
"""How long a stand-in run simulates, s: one that was waited out writes its marker file. Long,
so that no run finishes before the interrupt on a loaded machine (the runs are cut off: the
test takes well under a second)."""


def slow_run(spec, cache_dir=None):
    """A stand-in for `campaign.run_one` (forked workers inherit it): marks its start, sleeps,
    then marks its end."""
    folder = os.environ["CAMPAIGN_INTERRUPT_TEST_DIR"]
    with open(f"{folder}/started-{spec.seed}", "w"):
        pass
    time.sleep(RUN_S)
    with open(f"{folder}/finished-{spec.seed}", "w"):
        pass
    raise AssertionError("a run the interrupt should have cut off has finished")


def interrupt_once_started(folder, done, sent):
    """Interrupt the main thread (as SIGINT to this process would) once a run has started;
    ``sent`` gets the time of the interrupt (``time.monotonic``)."""
    while not any(p.name.startswith("started-") for p in folder.iterdir()):
        if done.wait(0.02):
            return
    sent.append(time.monotonic())
    _thread.interrupt_main()


@pytest.mark.skipif(
    multiprocessing.get_start_method() != "fork", reason="the stand-in reaches forked workers"
)
def test_an_interrupt_cuts_off_the_running_runs_instead_of_waiting_for_them(tmp_path, monkeypatch):
    monkeypatch.setenv("CAMPAIGN_INTERRUPT_TEST_DIR", str(tmp_path))  # (workers inherit it)
    monkeypatch.setattr(campaign, "run_one", slow_run)
    done, sent = threading.Event(), []
    handler = signal.signal(signal.SIGINT, signal.default_int_handler)
    watcher = threading.Thread(target=interrupt_once_started, args=(tmp_path, done, sent))
    watcher.start()
    start = time.monotonic()
    try:
        with pytest.raises(KeyboardInterrupt):
            try:
                vehicle.run_campaign(
                    np.array([[0.7, 250.0], [1.6, 550.0]]), road_length_m=6.0, window=300,
                    lead_in_m=0.5, progress=False, seed=1,
                )  # fmt: skip
            except Exception as exc:  # (says when the interrupt went, should it be lost again)
                when = (
                    f"interrupt_main called {sent[0] - start:.3f} s after the campaign started"
                    if sent
                    else "interrupt_main not called (no run seen started)"
                )
                ended = f"the campaign ended {time.monotonic() - start:.3f} s after its start"
                raise AssertionError(f"{exc!r}: {when}; {ended}") from exc
    finally:
        done.set()
        watcher.join()
        signal.signal(signal.SIGINT, handler)
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith("started-")]
    assert not [p for p in multiprocessing.active_children() if p.is_alive()]  # none simulates
    assert not [p.name for p in tmp_path.iterdir() if p.name.startswith("finished-")]
