"""GD's unit where the replay and the closed-loop example print GD: in brackets, as ``gpmsa
info`` and ``gpmsa calibrate`` print it ("1e-6 m^3", the shipped emulators', reads as a
number), the numbers as before."""

from types import SimpleNamespace

import numpy as np
import pytest

from control.robot.replay import ReplayResult


def _describe(**unit) -> str:
    """`ReplayResult.describe` over stand-ins of its parts: 3 ok estimates, GD 301.4 to 512.6."""
    topic = SimpleNamespace(describe=lambda: "a topic")
    fake = SimpleNamespace(
        imu=topic, odometry=topic, resampling=SimpleNamespace(filter="none"), notes=(),
        status=np.array(["ok"] * 3), gd_mean=np.array([301.4, 400.0, 512.6]),
        mode=np.array(["normal", "safety", "normal"]), domain_edge=np.array([""] * 3),
        real_time_factor=50.0, read_s=0.1, condition_s=0.1, bcr_s=0.1,
        _count_line=lambda: "3 estimates", **unit,
    )  # fmt: skip
    return ReplayResult.describe(fake)


def test_the_replay_names_the_gd_unit_in_brackets_after_the_same_numbers():
    lines = _describe(gd_unit="1e-6 m^3").splitlines()
    assert "GD posterior mean 301 to 513 [1e-6 m^3]; safety mode 33% of the time" in lines


def test_without_a_unit_the_line_is_as_before():
    for unit in ({}, {"gd_unit": ""}):  # a result pickled before it had one; none recorded
        assert "GD posterior mean 301 to 513; safety mode 33% of the time" in _describe(**unit)


def test_an_odd_unit_stays_on_its_line():
    text = _describe(gd_unit="m^3\n" + "x" * 100)
    assert "GD posterior mean 301 to 513 [m^3\\nxxx" in text and "...]; safety" in text


def test_a_replay_records_the_emulators_unit(emulator_a, likelihood_a, tmp_path):
    pytest.importorskip("rosbags")
    pytest.importorskip("mcap")
    import control
    import roadgen
    from control.robot import replay_bag

    path = tmp_path / "run.mcap"
    control.run_closed_loop(roadgen.track([(6, 300)], seed=3), emulator_a, seed=3,
                            likelihood=likelihood_a, record=path)  # fmt: skip
    replayed = replay_bag(path, emulator_a, likelihood=likelihood_a)
    assert replayed.gd_unit == emulator_a.t_units[0] == "1e-6 m^3"
    assert "[1e-6 m^3]; safety mode" in replayed.describe()
