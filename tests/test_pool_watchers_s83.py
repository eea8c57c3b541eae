"""The end-with-parent watchers of gpmsa's chain pool and of vehicle's campaign pool (written
twice: vehicle may not import gpmsa) end a worker with the process that owns its pool (session
83). Before: a forkserver's worker watched its parent, the forkserver, which outlives the owner
while any worker holds its pipe; and ``os.kill(pid, 0)`` took an owner killed but not yet reaped
(a zombie) for alive."""

import os
import signal
import subprocess
import sys

import pytest

from gpmsa.mcmc import parallel
from vehicle import campaign

# (module, its worker initializer)
WATCHERS = [(parallel, parallel.end_with_parent), (campaign, campaign._end_with_parent)]
IDS = ["gpmsa", "vehicle"]


@pytest.mark.parametrize(("module", "initializer"), WATCHERS, ids=IDS)
def test_a_worker_of_another_parent_watches_its_owner(module, initializer, monkeypatch):
    started = []

    class _Thread:
        def __init__(self, target, args, name, daemon):
            started.append((target, args))

        def start(self):
            pass

    monkeypatch.setattr(module.threading, "Thread", _Thread)
    owner = os.getppid() + 1  # a forkserver's worker: its parent is not the pool's owner
    initializer(owner)  # no prctl on this process: its parent is not the owner
    assert started == [(module._watch_parent, (os.getppid(), owner))]


@pytest.fixture
def ends(monkeypatch):
    """Patch a module's ``os._exit`` to raise SystemExit and its ``time.sleep`` to fail (a
    watcher that sleeps is still watching an owner that ended)."""

    def exits(code):
        raise SystemExit(code)

    def sleeps(seconds):
        raise AssertionError("still watching an owner that ended")

    def patch(module):
        monkeypatch.setattr(module.os, "_exit", exits)
        monkeypatch.setattr(module.time, "sleep", sleeps)

    return patch


@pytest.mark.parametrize(("module", "initializer"), WATCHERS, ids=IDS)
def test_the_watcher_ends_the_worker_once_the_owner_is_gone(module, initializer, ends):
    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    ends(module)
    with pytest.raises(SystemExit):
        module._watch_parent(os.getppid(), gone.pid)


@pytest.mark.skipif(not hasattr(os, "pidfd_open"), reason="a zombie reads as alive without pidfd")
@pytest.mark.parametrize(("module", "initializer"), WATCHERS, ids=IDS)
def test_the_watcher_ends_the_worker_of_an_owner_left_a_zombie(module, initializer, ends):
    owner = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        owner.send_signal(signal.SIGKILL)
        os.waitid(os.P_PID, owner.pid, os.WEXITED | os.WNOWAIT)  # ended, not reaped
        ends(module)
        with pytest.raises(SystemExit):
            module._watch_parent(os.getppid(), owner.pid)
    finally:
        owner.wait()
