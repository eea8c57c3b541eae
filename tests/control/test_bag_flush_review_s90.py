"""Review of s90 (control): a bag whose parent folder cannot be flushed to disk after its move
(an I/O error) is not kept, so that the caller's cleanup and a second try hold: before, the
bag stayed at ``path`` with the error, ``terrain-replay``'s cleanup (which removes only what
it knows it wrote) left it and the ``--out`` folder it made, and the second try the message
advised was refused ("exists already")."""

import errno
import os
import sys

import pytest

pytest.importorskip("rosbags")
pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="no fsync of a folder there")

from control.errors import ControlError  # noqa: E402
from control.robot import bags, cli  # noqa: E402


def _fail_fsync_of(monkeypatch, folder):
    """``os.fsync`` raises EIO for ``folder``'s descriptor (once it exists), syncs others."""
    real = os.fsync

    def fsync(fd):
        if os.path.exists(folder) and os.fstat(fd).st_ino == os.stat(folder).st_ino:
            raise OSError(errno.EIO, os.strerror(errno.EIO))
        real(fd)

    monkeypatch.setattr(os, "fsync", fsync)


def test_a_bag_whose_parent_cannot_be_flushed_is_not_kept_and_a_retry_writes_it(
    tmp_path, monkeypatch
):
    target = tmp_path / "bag"
    _fail_fsync_of(monkeypatch, tmp_path)
    with pytest.raises(ControlError) as info:
        with bags.open_bag_writer(target):
            pass
    assert str(info.value) == (
        f"{target}: cannot write (its folder {tmp_path} could not be flushed to disk after the "
        f"move: {os.strerror(errno.EIO)}; the bag was not kept: check the disk and write it "
        "again)"
    )
    assert isinstance(info.value.__cause__, OSError)
    assert os.listdir(tmp_path) == []  # neither the bag nor the hidden folder
    monkeypatch.undo()
    with bags.open_bag_writer(target):
        pass
    assert (target / "metadata.yaml").is_file()


class _Result:
    """A ReplayResult's writers: a CSV and a real (empty) bag."""

    def to_csv(self, path):
        path.write_text("csv\n")

    def write_bag(self, path):
        with bags.open_bag_writer(path):
            pass


def test_replay_out_left_empty_when_the_bag_cannot_be_flushed(tmp_path, monkeypatch):
    out = tmp_path / "out"
    _fail_fsync_of(monkeypatch, out)
    with pytest.raises(ControlError, match="the bag was not kept"):
        cli._write(out, _Result(), {})
    assert os.listdir(tmp_path) == []  # its outputs and the folder it made removed
