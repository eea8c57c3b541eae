"""A sqlite3 bag's messages that the fast decoder does not fit are decoded with the definition
the bag carries (rosbag2's message_definitions table, which rosbags' writer fills), as an MCAP
file's are (session 84 review). Before: the sqlite3 path ignored that table and decoded with ROS
2's standard definition, calling a bag of a trimmed Imu damaged ("message 0 ... does not
deserialise: buffer is smaller than requested size") that rosbags and the same bag as MCAP
read right."""

import sqlite3
import sys
from pathlib import Path

import pytest

pytest.importorskip("rosbags")
pytest.importorskip("mcap")

from rosbags.typesys import Stores, get_types_from_msg, get_typestore  # noqa: E402

from control.errors import BagError  # noqa: E402
from control.robot import messages as msgs  # noqa: E402
from control.robot import read_recording  # noqa: E402
from control.robot.bags import open_bag_writer  # noqa: E402

sys.path.insert(0, str(Path(__file__).parent))
from test_bag_fallback_decoder_s84 import _assert_drive, _drive, _trimmed  # noqa: E402


def _bag(path: Path, storage: str) -> Path:
    """A bag of the drive whose Imu is the trimmed one, its definition recorded by rosbags."""
    t_imu, imu, t_odom, odom = _drive()
    (_, text), trimmed = _trimmed(imu)
    own = get_typestore(Stores.EMPTY)
    own.register(get_types_from_msg(text, msgs.IMU_TYPE))
    with open_bag_writer(path, storage=storage) as w:
        conn = w.add_connection("/imu/data", msgs.IMU_TYPE, typestore=own)
        for stamp, data in zip(t_imu.tolist(), trimmed, strict=True):
            w.write(conn, stamp, data)
        std = msgs.typestore()
        conn = w.add_connection("/odometry/filtered", msgs.ODOMETRY_TYPE, typestore=std)
        for stamp, data in zip(t_odom.tolist(), odom, strict=True):
            w.write(conn, stamp, data)
    return path


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_a_bags_own_definition_of_imu_decodes_its_messages_in_either_storage(tmp_path, storage):
    rec = read_recording(_bag(tmp_path / "bag", storage))
    assert rec.storage == storage
    _assert_drive(rec)


def test_a_sqlite3_definition_that_does_not_parse_is_named(tmp_path):
    path = _bag(tmp_path / "bag", "sqlite3")
    (db,) = path.glob("*.db3")
    with sqlite3.connect(db) as con:
        con.execute(
            "UPDATE message_definitions SET encoded_message_definition = 'float64[ x' "
            "WHERE topic_type = ?",
            (msgs.IMU_TYPE,),
        )
    con.close()
    with pytest.raises(BagError, match=r"damaged: the schema of the topic '/imu/data' does "
                                       r"not parse \(TypesysError"):  # fmt: skip
        read_recording(path)
