"""A campaign killed outright takes its pool's workers with it, and the cache folder's write
check neither collides with another process's nor leaves a file behind."""

import os
import signal
import subprocess
import sys
import textwrap

import pytest

import vehicle
from tests._processes import assert_workers_end
from vehicle import campaign


@pytest.mark.skipif(sys.platform != "linux", reason="/proc")
def test_a_killed_campaign_takes_its_pool_workers_with_it(tmp_path):
    """A campaign killed by SIGTERM or SIGKILL left its workers idle for ever (seen: 6 minutes
    and counting), each a copy of its memory."""
    script = textwrap.dedent(
        """
        import multiprocessing, os, signal
        import numpy as np
        import vehicle
        from vehicle import campaign

        real = campaign._completed

        def first_then_killed(futures, pool=None):
            for fut in real(futures, pool):  # a run has finished: the workers are up
                print(*[p.pid for p in multiprocessing.active_children()], flush=True)
                os.kill(os.getpid(), signal.SIGKILL)
                yield fut

        campaign._completed = first_then_killed
        design = np.array([[0.7, 250.0], [1.6, 550.0], [1.1, 400.0]])
        vehicle.run_campaign(design, road_length_m=6.0, window=300, lead_in_m=0.5,
                             progress=False, seed=1)
        """
    )
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    proc = subprocess.Popen(
        [sys.executable, "-c", script], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
        env=env, text=True,
    )  # fmt: skip
    workers = [int(pid) for pid in proc.stdout.readline().split()]
    proc.stdout.close()
    assert proc.wait() == -signal.SIGKILL and workers
    assert_workers_end(workers)


def test_the_cache_folder_check_takes_no_name_another_process_may_hold(tmp_path, monkeypatch):
    """The write check wrote and removed ``.write-test-<pid>``: a campaign on another machine
    sharing the folder with the same process id (containers: often) removed it first, or had
    left one (interrupted) that this user cannot write, and the folder was refused ("cannot be
    used as a folder")."""
    (tmp_path / f".write-test-{os.getpid()}").mkdir()  # another's, not writable here
    assert campaign._cache_folder(tmp_path) == tmp_path
    assert os.listdir(tmp_path) == [f".write-test-{os.getpid()}"]  # nothing added


def test_the_cache_folder_check_still_refuses_a_folder_it_cannot_write(tmp_path, monkeypatch):
    def denied(*args, **kwargs):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(campaign.tempfile, "TemporaryFile", denied)
    with pytest.raises(vehicle.VehicleError, match="cannot be used as a folder: .*Permission"):
        campaign._cache_folder(tmp_path)
