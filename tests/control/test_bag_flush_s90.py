"""A bag this package writes (s90) is flushed to disk before its move into place, and its
folder after: a power cut after `write_sensor_bag` returns keeps the whole bag (rosbags' writer
flushes nothing itself)."""

import errno
import os
import stat

import numpy as np
import pytest

pytest.importorskip("rosbags")

import control  # noqa: E402
from control.robot import bags, read_recording, write_sensor_bag  # noqa: E402
from gpmsa.io import atomic  # noqa: E402
from tests._fsync import fail_fsync, record_folder_fsyncs  # noqa: E402

N = 40


def _write(path, storage):
    t = 1.0 + np.arange(N) / 120.0
    accel = np.random.default_rng(0).normal(size=N)
    return write_sensor_bag(path, t, accel, t, 0.5 * (t - 1.0), np.full(N, 0.5),
                            storage=storage)  # fmt: skip


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_every_file_then_the_bag_then_its_parent_are_flushed(tmp_path, monkeypatch, storage):
    events, real_fsync = [], os.fsync
    target = tmp_path / "bag"

    def fsync(fd):
        st = os.fstat(fd)
        kind = "folder" if stat.S_ISDIR(st.st_mode) else "file"
        events.append((kind, st.st_ino, target.exists()))
        real_fsync(fd)

    monkeypatch.setattr(bags.os, "fsync", fsync)
    monkeypatch.setattr(atomic.os, "fsync", fsync)
    _write(target, storage)
    inodes = {os.stat(p).st_ino: p.name for p in target.iterdir()}
    files = [e for e in events if e[0] == "file"]
    assert sorted(inodes[e[1]] for e in files) == sorted(inodes.values())  # each file once
    assert all(not moved for _, _, moved in files)  # before the move
    assert events[len(files)] == ("folder", os.stat(target).st_ino, False)  # the bag, before
    assert events[len(files) + 1 :] == [("folder", os.stat(tmp_path).st_ino, True)]  # parent
    assert read_recording(target).imu.stamp_ns.size == N


def test_an_io_error_flushing_a_file_leaves_no_bag_and_names_it(tmp_path, monkeypatch):
    fail_fsync(monkeypatch, bags, of="file")
    target = tmp_path / "bag"
    with pytest.raises(control.ControlError) as info:
        _write(target, "mcap")
    assert str(info.value) == f"{target}: cannot write ({os.strerror(errno.EIO)})"
    assert os.listdir(tmp_path) == []  # nor the hidden folder


def test_an_io_error_flushing_the_parent_names_it_with_the_bag_in_place(tmp_path, monkeypatch):
    """Where the bag cannot be moved back out of the way either (review s90: otherwise it is
    not kept, tests/control/test_review_s90.py), flush_folder's error says it is in place."""
    real_fsync, real_rename = os.fsync, os.rename
    target = tmp_path / "bag"

    def fsync(fd):
        if os.fstat(fd).st_ino == os.stat(tmp_path).st_ino:
            raise OSError(errno.EIO, os.strerror(errno.EIO))
        real_fsync(fd)

    def rename(src, dst):
        if os.fspath(src) == os.fspath(target):
            raise OSError(errno.EIO, os.strerror(errno.EIO))
        real_rename(src, dst)

    monkeypatch.setattr(atomic.os, "fsync", fsync)
    monkeypatch.setattr(bags.os, "rename", rename)
    with pytest.raises(control.ControlError, match=f"^{tmp_path}: the files were moved into"):
        _write(target, "mcap")
    assert os.listdir(tmp_path) == ["bag"]
    assert read_recording(target).imu.stamp_ns.size == N


def test_folders_made_for_the_bag_are_flushed_into_their_parents(tmp_path, monkeypatch):
    # session 91: a bag written to new/deeper/bag made new/ and new/deeper/, but their names in
    # tmp_path and new/ were never flushed: a power cut could lose the whole bag
    events = record_folder_fsyncs(monkeypatch, bags)
    target = tmp_path / "new" / "deeper" / "bag"
    _write(target, "mcap")
    inode = {p: os.stat(p).st_ino for p in (target, target.parent, target.parent.parent)}
    assert events == [inode[target.parent.parent], os.stat(tmp_path).st_ino,  # as made
                      inode[target], inode[target.parent]]  # fmt: skip
    assert bags._missing_folders(target) == []  # (written)
    assert bags._missing_folders(tmp_path / "a" / "b") == [tmp_path / "a" / "b", tmp_path / "a"]


def test_an_io_error_flushing_a_made_folder_s_parent_keeps_no_bag(tmp_path, monkeypatch):
    record_folder_fsyncs(monkeypatch, atomic, fail_inode=os.stat(tmp_path).st_ino)
    target = tmp_path / "new" / "bag"
    with pytest.raises(control.ControlError) as info:
        _write(target, "mcap")
    assert str(info.value) == (
        f"{target}: cannot write (the folder {tmp_path} could not be flushed to disk after 'new' "
        f"was made in it: {os.strerror(errno.EIO)}; nothing was kept: check the disk and write it "
        "again)"
    )
    assert os.listdir(tmp_path) == []  # (review s91: nor the folder made for it)
