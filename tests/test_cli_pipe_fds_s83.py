"""The console commands, called in-process (``gpmsa.cli.main.main``, ``control.robot.cli.main``),
close what they open when their reader has gone: each call whose stdout raised BrokenPipeError
left one descriptor of /dev/null open (a notebook or a test calling them leaked one a call)."""

import os
import sys

import numpy as np
import pytest

pytestmark = pytest.mark.skipif(not os.path.isdir("/proc/self/fd"), reason="counts /proc fds")


class _GoneReader:
    """A stdout whose reader has gone (every write raises BrokenPipeError) on a real file."""

    def __init__(self, fh) -> None:
        self._fh = fh

    def write(self, text: str) -> int:
        raise BrokenPipeError(32, "Broken pipe")

    def flush(self) -> None:
        raise BrokenPipeError(32, "Broken pipe")

    def fileno(self) -> int:
        return self._fh.fileno()


def _open_fds() -> int:
    return len(os.listdir("/proc/self/fd"))


def test_gpmsa_info_to_a_gone_reader_leaves_no_descriptor_open(tmp_path, monkeypatch):
    import gpmsa
    from gpmsa.cli.main import main

    x, t = np.random.default_rng(0).uniform(size=(2, 8, 1))
    sim = gpmsa.SimData(x=x, t=t, y=x * (1 + t), x_names=["x"], t_names=["t"])
    params = {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [1e3], "lamWOs": [1e3]}
    path = str(gpmsa.Emulator.from_params(sim, params).save(tmp_path / "e.gpmsa"))
    with open(tmp_path / "out", "w") as fh:
        monkeypatch.setattr(sys, "stdout", _GoneReader(fh))
        before = _open_fds()
        assert main(["info", path]) == 0
        assert _open_fds() == before


def test_terrain_replay_to_a_gone_reader_leaves_no_descriptor_open(tmp_path, monkeypatch):
    pytest.importorskip("rosbags", reason="the robot extra")
    from control.robot import write_sensor_bag
    from control.robot.cli import main

    t = np.arange(1, 601) / 120.0
    speed = np.minimum(20.0 * t, 1.0)
    accel = np.random.default_rng(0).normal(0.0, 4.0, t.size)
    bag = write_sensor_bag(tmp_path / "bag", t, accel, t, np.cumsum(speed) / 120.0, speed)
    with open(tmp_path / "out", "w") as fh:
        monkeypatch.setattr(sys, "stdout", _GoneReader(fh))
        before = _open_fds()
        assert main([str(bag), "--emulator", "A", "--out", str(tmp_path / "b")]) == 0
        assert _open_fds() == before
