"""Campaign.save and the run cache (s90): after its move a save flushes the folder to disk, so
that a power cut just after it keeps the new file (as gpmsa.io.atomic's saves)."""

import errno
import os
import stat
import sys

import numpy as np
import pytest

import vehicle
from tests._fsync import fail_fsync
from vehicle import campaign

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="no fsync of a folder there")


def _campaign() -> vehicle.Campaign:
    fs = np.array([40.0, 80.0])
    return vehicle.Campaign(
        v=np.array([0.7, 1.6]), gd=np.array([250.0, 550.0]), seed=np.array([3, 4]),
        f_full=fs, f_window=fs, f_full_noisy=fs + 1, f_window_noisy=fs + 1,
        status=np.array(["ok", "ok"]), settings={"note": "hand-made"},
    )  # fmt: skip


def test_a_save_flushes_its_folder_after_the_move(tmp_path, monkeypatch):
    path = tmp_path / "c.npz"
    events, real_fsync = [], os.fsync

    def fsync(fd):
        st = os.fstat(fd)
        events.append(("folder", st.st_ino, path.exists()) if stat.S_ISDIR(st.st_mode) else "file")
        real_fsync(fd)

    monkeypatch.setattr(campaign.os, "fsync", fsync)
    _campaign().save(path)
    assert events == ["file", ("folder", os.stat(tmp_path).st_ino, True)]
    assert vehicle.load_campaign(path).f_full.tolist() == [40.0, 80.0]


def test_an_io_error_flushing_the_folder_is_named(tmp_path, monkeypatch):
    fail_fsync(monkeypatch, campaign)
    path = tmp_path / "c.npz"
    with pytest.raises(vehicle.CampaignFileError) as info:
        _campaign().save(path)
    assert str(info.value) == (
        f"cannot write campaign file {str(path)!r}: [Errno {errno.EIO}] {tmp_path}: the file "
        f"was moved into place, but the folder could not be flushed to disk "
        f"({os.strerror(errno.EIO)}): a power cut could still undo the save; check the disk and "
        "save again"
    )
    assert sorted(os.listdir(tmp_path)) == ["c.npz"]


def test_a_file_system_without_folder_fsync_saves_as_before(tmp_path, monkeypatch):
    fail_fsync(monkeypatch, campaign, code=errno.EINVAL)
    _campaign().save(tmp_path / "c.npz")
    assert vehicle.load_campaign(tmp_path / "c.npz").f_full.tolist() == [40.0, 80.0]
