"""Review of the session-75 path audit: replay_bag's csv and out_bag (and an emulator path next
to them) that the OS cannot look up are ControlErrors naming the argument before the replay,
and its recording is named ``bag`` (a raw UnicodeEncodeError, or a name too long found only
when the bag was written after the replay, or "path=" before)."""

import pytest

from control.errors import BagError, ControlError
from control.robot import replay_bag

LONG = "z" * 300  # above the 255 bytes a file name may have on common file systems


@pytest.fixture
def bag(tmp_path):
    path = tmp_path / "rec.mcap"
    path.write_bytes(b"not read: every check here comes first")
    return path


@pytest.mark.parametrize(
    ("name", "leaf", "match"),
    [
        ("csv", "a\ud800.csv", r"csv=.*holds '\\ud800'"),
        ("out_bag", "a\ud800", r"out_bag=.*holds '\\ud800'"),
        ("out_bag", LONG, "out_bag=.*cannot look it up"),  # before: found after the replay
    ],
    ids=["csv-surrogate", "out_bag-surrogate", "out_bag-too-long"],
)
def test_replay_outputs_the_os_cannot_look_up_are_named_up_front(bag, tmp_path, name, leaf, match):
    with pytest.raises(ControlError, match=match):
        replay_bag(bag, "A", **{name: tmp_path / leaf})


def test_an_emulator_path_the_os_cannot_encode_beside_a_csv_is_named(bag, tmp_path):
    with pytest.raises(ControlError, match=r"emulator=.*holds '\\ud800'"):
        replay_bag(bag, str(tmp_path / "e\ud800.gpmsa"), csv=tmp_path / "out.csv")


def test_the_recording_is_named_bag(tmp_path):
    with pytest.raises(BagError, match=r"^bag=.*holds '\\ud800'"):
        replay_bag(tmp_path / "r\ud800.mcap", "A")


def test_an_emulator_path_under_home_is_expanded(tmp_path, monkeypatch):
    """load_emulator read "~/e.gpmsa" literally (no such file) where the bag and CSV paths
    expand the home folder."""
    import shutil

    from control.robot.replay import load_emulator
    from control.shipped import shipped_emulator_path

    monkeypatch.setenv("HOME", str(tmp_path))
    shutil.copyfile(shipped_emulator_path("A"), tmp_path / "e.gpmsa")
    assert load_emulator("~/e.gpmsa").q == 1
