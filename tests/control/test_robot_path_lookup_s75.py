"""Robot file paths the OS cannot look up (a name too long for the file system, a NUL byte, a
character its encoding cannot write) are ControlError / BagError naming the argument, not a bare
OSError or ValueError from Python 3.11's Path.exists."""

import numpy as np
import pytest

from control.errors import BagError, ControlError
from control.robot.replay import check_csv_target, load_emulator
from control.robot.storage import check_mcap_target

LONG = "y" * 300  # above the 255 bytes a file name may have on common file systems


def test_reading_a_recording_with_a_name_too_long_is_a_bag_error(tmp_path):
    pytest.importorskip("rosbags")
    from control.robot import read_recording

    with pytest.raises(BagError, match="path=.*cannot look it up"):
        read_recording(tmp_path / LONG)


def test_an_emulator_path_too_long_is_a_control_error_naming_the_argument(tmp_path):
    with pytest.raises(ControlError, match="emulator=.*cannot look it up"):
        load_emulator(tmp_path / LONG)


@pytest.mark.parametrize("check", [check_csv_target, check_mcap_target])
def test_output_paths_too_long_are_control_errors_naming_the_argument(tmp_path, check):
    with pytest.raises(ControlError, match="csv=.*cannot look it up"):
        check(tmp_path / LONG, "csv")


@pytest.mark.parametrize("name", ["a\0b", "\ud800"])
def test_a_bag_written_to_an_unusable_path_is_a_control_error(tmp_path, name):
    pytest.importorskip("rosbags")
    from control.robot import write_sensor_bag

    t = np.arange(4) * 0.01
    with pytest.raises(ControlError, match="path="):
        write_sensor_bag(tmp_path / name, t, t, t, t, np.ones(4))
