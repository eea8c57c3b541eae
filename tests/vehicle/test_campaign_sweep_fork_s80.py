"""A campaign worker forked after its parent's sweep sweeps the cache folder at its own first
save (vehicle's copy of gpmsa's once-a-folder-and-process sweep of stale temporaries): it
inherited the parent's record of swept folders, so a temporary left by a worker killed since
stayed until a process started afresh saved there."""

import os
import subprocess
import sys

import numpy as np
import pytest

from vehicle import campaign


def _dead_pid() -> int:
    """The id of a process that ran and ended (and was waited for)."""
    proc = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)  # fmt: skip
    return int(proc.stdout)


@pytest.mark.skipif(not hasattr(os, "fork"), reason="no fork")
def test_a_forked_worker_sweeps_the_cache_at_its_first_save(tmp_path):
    campaign._save_npz(tmp_path / "run-a.npz", {"f": np.zeros(2)})  # the parent's sweep
    stale = f".run-b.npz.{_dead_pid()}@{campaign._host_id()}.0123456789ab.part"
    (tmp_path / stale).write_bytes(b"half a file")  # a worker killed since
    pid = os.fork()
    if pid == 0:  # the next worker: save, and leave without running pytest's clean-up
        code = 1
        try:
            campaign._save_npz(tmp_path / "run-c.npz", {"f": np.ones(2)})
            code = 0
        finally:
            os._exit(code)
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0
    assert sorted(os.listdir(tmp_path)) == ["run-a.npz", "run-c.npz"]  # before: stale stayed
    np.testing.assert_array_equal(np.load(tmp_path / "run-c.npz")["f"], np.ones(2))
