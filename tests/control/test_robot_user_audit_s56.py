"""A robot user's workflows from docs/robot.md and docs/closed-loop.md (session 56 audit)."""

import numpy as np
import pytest

pytest.importorskip("rosbags")
pytest.importorskip("mcap")

import control  # noqa: E402
from control.errors import ControlError, EmulatorMismatchError  # noqa: E402
from control.robot import replay, write_sensor_bag  # noqa: E402


@pytest.fixture
def small_bag(tmp_path):
    t = np.arange(240) / 120.0
    accel = np.random.default_rng(0).normal(size=t.size)
    return write_sensor_bag(tmp_path / "bag", t, accel, t, 1.5 * t, np.full(t.size, 1.5))


@pytest.fixture
def unread(monkeypatch):
    """Fail the test if the recording is read: the settings are to be refused before."""

    def read(*args, **kwargs):
        raise AssertionError("the recording was read before the settings were checked")

    monkeypatch.setattr(replay, "read_recording", read)


def test_replay_bag_refuses_bcr_settings_that_are_not_bcr_settings(small_bag, unread):
    with pytest.raises(ControlError, match=r"bcr must be a control\.BCRSettings, got 'x'"):
        control.replay_bag(small_bag, "A", bcr="x")


def test_replay_bag_refuses_a_bcr_feature_unlike_the_emulators_before_reading(small_bag, unread):
    window = control.BCRSettings(method="window", feature=control.PAPER_WINDOW)
    with pytest.raises(EmulatorMismatchError, match="the BCR's feature differs"):
        control.replay_bag(small_bag, "A", bcr=window)
