"""run_closed_loop and the replay make no tqdm bar without ``progress`` (gpmsa's NoBar): tqdm's
first bar, a disabled one too, starts its monitor thread and keeps it, and a later fork in the
process (gpmsa.fit's chains, run_campaign's pool) ran beside it."""

import numpy as np
import pytest
import tqdm.std

import control
import roadgen


def _refuse(cls, *args, **kwargs):
    raise AssertionError("a tqdm bar was made without progress")


def test_the_closed_loop_makes_no_tqdm_bar_without_progress(monkeypatch, emulator_b, likelihood_b):
    track = roadgen.track([(3.0, 300.0)], seed=1)
    monkeypatch.setattr(tqdm.std.tqdm, "__new__", _refuse)
    run = control.run_closed_loop(track, emulator_b, noise_std=1.0, seed=1, likelihood=likelihood_b)
    assert run.time.size > 0


def test_the_closed_loop_bar_shows_with_progress(capsys, emulator_b, likelihood_b):
    track = roadgen.track([(3.0, 300.0)], seed=1)
    control.run_closed_loop(
        track, emulator_b, noise_std=1.0, seed=1, likelihood=likelihood_b, progress=True
    )
    assert "0/3 [" in capsys.readouterr().err


def test_the_replay_makes_no_tqdm_bar_without_progress(tmp_path, monkeypatch, capsys, likelihood_a):
    pytest.importorskip("rosbags")
    pytest.importorskip("mcap")
    from control.robot import write_sensor_bag

    t = 1.0 + np.arange(400) / 120.0
    accel = np.random.default_rng(1).normal(size=t.size)
    bag = write_sensor_bag(tmp_path / "drive", t, accel, t, t - 1.0, np.ones(t.size))
    shown = control.replay_bag(bag, "A", likelihood=likelihood_a, progress=True)
    assert "update" in capsys.readouterr().err
    monkeypatch.setattr(tqdm.std.tqdm, "__new__", _refuse)
    quiet = control.replay_bag(bag, "A", likelihood=likelihood_a)
    assert np.array_equal(quiet.command, shown.command) and quiet.status.size > 0
