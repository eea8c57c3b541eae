"""Review of session 91's bag writer (s91): the folders made for a bag have their names flushed
into their parents as soon as they are made, so that a second try, which finds them made, does
not leave them unflushed; relative, '..' and symlinked parents flush the real folders."""

import os

import numpy as np
import pytest

pytest.importorskip("rosbags")

import control  # noqa: E402
from control.robot import bags, read_recording, write_sensor_bag  # noqa: E402
from tests._fsync import record_folder_fsyncs  # noqa: E402

N = 40


def _write(path):
    t = 1.0 + np.arange(N) / 120.0
    accel = np.random.default_rng(0).normal(size=N)
    return write_sensor_bag(path, t, accel, t, 0.5 * (t - 1.0), np.full(N, 0.5), storage="mcap")


def test_a_second_try_after_a_write_that_failed_still_flushes_the_made_folder(
    tmp_path, monkeypatch
):
    # review s91: a first write that failed in its block left new/ made but its name in
    # tmp_path unflushed, and the second, finding new/ there, flushed only new/
    flushed = record_folder_fsyncs(monkeypatch, bags)
    target = tmp_path / "new" / "bag"
    with pytest.raises(RuntimeError, match="the recording failed"):
        with bags.open_bag_writer(target):
            raise RuntimeError("the recording failed")
    _write(target)
    assert os.stat(tmp_path).st_ino in flushed
    assert read_recording(target).imu.stamp_ns.size == N


def test_a_retry_after_an_io_error_flushing_a_made_folder_s_parent_flushes_it(
    tmp_path, monkeypatch
):
    # review s91: "check the disk and write it again" wrote the bag into the folder left
    # behind without flushing its name into tmp_path
    record_folder_fsyncs(monkeypatch, bags, fail_inode=os.stat(tmp_path).st_ino)
    target = tmp_path / "new" / "bag"
    with pytest.raises(control.ControlError, match="check the disk and write it again"):
        _write(target)
    assert os.listdir(tmp_path) == []  # nor the folder made for it
    monkeypatch.undo()
    flushed = record_folder_fsyncs(monkeypatch, bags)
    _write(target)
    assert os.stat(tmp_path).st_ino in flushed
    assert read_recording(target).imu.stamp_ns.size == N


def test_relative_dotdot_and_symlinked_parents_flush_the_real_folders(tmp_path, monkeypatch):
    (tmp_path / "real").mkdir()
    (tmp_path / "link").symlink_to("real")
    monkeypatch.chdir(tmp_path)
    flushed = record_folder_fsyncs(monkeypatch, bags)
    _write(os.path.join("a", "..", "b", "bag"))  # makes a/ and b/, both in tmp_path
    assert os.stat(tmp_path).st_ino in flushed and os.stat("b").st_ino in flushed
    flushed.clear()
    _write(os.path.join("link", "new", "bag"))  # new/ is made in real/
    assert {os.stat("real").st_ino, os.stat("real/new").st_ino} <= set(flushed)
    assert read_recording(tmp_path / "real" / "new" / "bag").imu.stamp_ns.size == N
