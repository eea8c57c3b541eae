"""``terrain-replay --release-m``: the Simplex's release dwell, as ``examples/closed_loop.py
--release-m`` takes it (default ``control.Simplex.release_m``; a bad value is a usage error
naming the option), given to the replay's Simplex.

Before: the command had no such option (``unrecognized arguments: --release-m``), so a replay
could not show the commands of a Simplex with the dwell that the closed loop runs."""

import dataclasses
import json

import numpy as np
import pytest

import control
from control.robot import cli


def test_release_m_is_an_option_with_the_simplex_default():
    args = cli.parser().parse_args(["bag", "--emulator", "B"])
    assert args.release_m == control.Simplex.release_m
    assert cli.parser().parse_args(["bag", "--emulator", "B", "--release-m", "5"]).release_m == 5
    assert "--release-m" in cli.parser().format_help()


@pytest.mark.parametrize("value", ["-1", "nan", "inf"])
def test_a_bad_release_m_is_a_usage_error_naming_the_option(value, tmp_path, capsys):
    with pytest.raises(SystemExit) as done:
        cli.main(["bag", "--emulator", "B", "--out", str(tmp_path / "o"), "--release-m", value])
    assert done.value.code == 2
    err = capsys.readouterr().err
    assert "terrain-replay: error: --release-m: release_m must be a finite distance >= 0" in err
    assert not (tmp_path / "o").exists()


def test_the_replay_runs_the_simplex_with_the_release_dwell(tmp_path, monkeypatch):
    pytest.importorskip("rosbags")
    pytest.importorskip("mcap")
    from control.robot import write_sensor_bag

    t = 1.0 + np.arange(400) / 120.0
    accel = np.random.default_rng(1).normal(size=t.size)
    bag = write_sensor_bag(tmp_path / "drive", t, accel, t, t - 1.0, np.ones(t.size))
    ran = []
    replay = cli.replay_bag

    def spy(*args, **kwargs):
        result = replay(*args, **kwargs)
        ran.append(result.simplex)
        return result

    monkeypatch.setattr(cli, "replay_bag", spy)
    argv = [str(bag), "--emulator", "A", "--out", str(tmp_path / "o"), "--release-m", "7.5"]
    assert cli.main(argv) == 0
    assert ran == [control.Simplex(release_m=7.5)]
    # replay.json says which Simplex made the commands (before: no Simplex setting at all)
    report = json.loads((tmp_path / "o" / "replay.json").read_text())
    assert report["simplex"] == dataclasses.asdict(control.Simplex(release_m=7.5))
