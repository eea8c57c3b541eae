"""Findings of the s64 fuzz of robot recordings (/tmp/fuzz): a damaged or hostile recording
raises `BagError` naming the file and the damage, never an exception of the libraries that
read it."""

import numpy as np
import pytest

pytest.importorskip("rosbags")
pytest.importorskip("mcap")

from control.errors import BagError  # noqa: E402
from control.robot import cli, read_recording, write_sensor_bag  # noqa: E402


def _signals(n: int = 60):
    t = 1.0 + np.arange(n) / 120.0
    return t, np.random.default_rng(0).normal(size=n), t, 0.5 * (t - 1.0), np.full(n, 0.5)


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
@pytest.mark.parametrize(
    "text", ["[" * 5000 + "]" * 5000, "a: " + "{b: " * 3000 + "1" + "}" * 3000], ids=["list", "map"]
)
def test_a_bag_metadata_nested_too_deep_is_a_bag_error(tmp_path, storage, text):
    """A metadata.yaml nested thousands deep: this package's reading of it gives up, and
    rosbags' parser, which then reads it, raised RecursionError out of ``read_recording`` (and
    the command printed a traceback)."""
    bag = write_sensor_bag(tmp_path / "drive", *_signals(), storage=storage)
    (bag / "metadata.yaml").write_text(text)
    with pytest.raises(BagError, match=f"cannot open {bag} as a ROS bag: its metadata.yaml is "
                                       "nested too deep to parse"):  # fmt: skip
        read_recording(bag)


def test_the_command_reports_a_bag_metadata_nested_too_deep_in_one_line(tmp_path, capsys):
    bag = write_sensor_bag(tmp_path / "drive", *_signals())
    (bag / "metadata.yaml").write_text("[" * 5000 + "]" * 5000)
    code = cli.main([str(bag), "--emulator", "A", "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1
    assert err.startswith("terrain-replay: error: ") and "nested too deep" in err
