"""The replay's outputs as a robotics engineer writes them (session 70).

Before: where writing into an existing ``--out`` folder failed on a read-only file system, the
clean-up that removes the outputs written so far unlinked each missing one, which such a file
system refuses too (EROFS, not ENOENT): its raw OSError ("[Errno 30] Read-only file system:
'.../estimates.csv'") replaced the write's own message naming the output. Now the clean-up
passes over what it cannot remove and the command reports the write's error."""

import errno
import pathlib

import pytest

from control.errors import ControlError
from control.robot import cli


class _Unwritable:
    """Stands for a ReplayResult whose CSV cannot be written (a read-only --out)."""

    def to_csv(self, path):
        raise ControlError(f"{path}: cannot write (Read-only file system)")


def test_a_failed_write_into_a_read_only_folder_reports_the_write(tmp_path, monkeypatch):
    out = tmp_path / "run1"
    out.mkdir()
    unlink = pathlib.Path.unlink

    def read_only(self, missing_ok=False):
        if self.parent == out:
            raise OSError(errno.EROFS, "Read-only file system", str(self))
        return unlink(self, missing_ok=missing_ok)

    monkeypatch.setattr(pathlib.Path, "unlink", read_only)
    with pytest.raises(ControlError, match=r"estimates.csv: cannot write \(Read-only file sys"):
        cli._write(out, _Unwritable(), {})
    assert out.is_dir()  # a folder that was there before is kept
