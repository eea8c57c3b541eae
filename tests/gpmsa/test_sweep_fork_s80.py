"""A forked process sweeps a folder of stale temporaries at its own first save there.

`gpmsa.io.atomic` lists a folder for the temporaries of saves killed outright once a process
(`_sweep_once`). A child forked after its parent's sweep (a worker of a fork pool) inherited the
parent's record of swept folders, so it never swept: a temporary left by a worker killed since
stayed until a process started afresh saved there, where the docs say "a later process's first
save into that folder" removes it.
"""

import os
import subprocess
import sys

import pytest

from gpmsa.io import atomic


def _dead_pid() -> int:
    """The id of a process that ran and ended (and was waited for)."""
    proc = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)  # fmt: skip
    return int(proc.stdout)


def _save(path) -> None:
    with atomic.atomic_write(path, text=True) as fh:
        fh.write("whole")


@pytest.mark.skipif(not hasattr(os, "fork"), reason="no fork")
def test_a_forked_child_sweeps_at_its_first_save(tmp_path):
    _save(tmp_path / "a.txt")  # this process's sweep of tmp_path
    stale = f".b.txt.{_dead_pid()}@{atomic._host_id()}.0123456789ab.part"  # killed since
    (tmp_path / stale).write_bytes(b"half a file")
    pid = os.fork()
    if pid == 0:  # the child: save, and leave without running pytest's clean-up
        code = 1
        try:
            _save(tmp_path / "c.txt")
            code = 0
        finally:
            os._exit(code)
    _, status = os.waitpid(pid, 0)
    assert os.waitstatus_to_exitcode(status) == 0
    assert sorted(os.listdir(tmp_path)) == ["a.txt", "c.txt"]  # before: the stale one stayed
    _save(tmp_path / "d.txt")  # this process: swept once already, no second listing
    assert (tmp_path / "d.txt").read_text() == "whole"
