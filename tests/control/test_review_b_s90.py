"""Review of session 90's sqlite3 text decoding (`control.robot.storage`): a TEXT value that
is not UTF-8 is named by the table it is in, not always as a topic's name or type."""

import sqlite3

import pytest

from control.errors import BagError
from control.robot import storage as st


def _db(path, *changes: str):
    """A bag file of one topic '/a' (id 1), one message and one definition, then ``changes``
    (SQL statements) applied."""
    con = sqlite3.connect(path)
    con.execute("CREATE TABLE topics (id INTEGER PRIMARY KEY, name, type, serialization_format)")
    con.execute("CREATE TABLE messages (id INTEGER PRIMARY KEY, topic_id, timestamp, data)")
    con.execute(
        "CREATE TABLE message_definitions (id INTEGER PRIMARY KEY, topic_type, encoding, "
        "encoded_message_definition)"
    )
    con.execute("INSERT INTO topics VALUES (1, '/a', 'pkg/msg/A', 'cdr')")
    con.execute("INSERT INTO messages VALUES (1, 1, 5, X'0102')")
    con.execute("INSERT INTO message_definitions VALUES (1, 'pkg/msg/A', 'ros2msg', 'int32 a')")
    for sql in changes:
        con.execute(sql)
    con.commit()
    con.close()
    return path


NOT_UTF8 = "CAST(X'2FFFFE' AS TEXT)"  # '/' then two bytes UTF-8 never holds


def _refusal(path) -> str:
    with pytest.raises(BagError) as info:
        st.sqlite_messages([path], ["/a"])
    return str(info.value)


def test_the_file_reads_before_any_change(tmp_path):
    out = st.sqlite_messages([_db(tmp_path / "x.db3")], ["/a"])
    assert (out.log_ns, out.data) == ({"/a": [5]}, {"/a": [b"\x01\x02"]})
    assert out.definitions == {"/a": [("ros2msg", "int32 a")]}


@pytest.mark.parametrize("column", ["timestamp", "data"])
def test_a_message_value_that_is_non_utf8_text_is_the_messages_fault(tmp_path, column):
    path = _db(tmp_path / "x.db3", f"UPDATE messages SET {column} = {NOT_UTF8}")
    assert _refusal(path) == (
        f"{path} is damaged: a message of the topic '/a' lacks an integer time stamp or its data"
    )


@pytest.mark.parametrize("column", ["topic_type", "encoding"])
def test_a_definitions_type_or_encoding_not_utf8_is_the_definitions_fault(tmp_path, column):
    path = _db(tmp_path / "x.db3", f"UPDATE message_definitions SET {column} = {NOT_UTF8}")
    assert _refusal(path) == (
        f"{path} is damaged: a message definition's type or encoding is not UTF-8 text"
    )


@pytest.mark.parametrize("column", ["name", "type", "serialization_format"])
def test_a_topic_field_not_utf8_is_named_with_the_serialisation_format(tmp_path, column):
    path = _db(tmp_path / "x.db3", f"UPDATE topics SET {column} = {NOT_UTF8}")
    assert _refusal(path) == (
        f"{path} is damaged: a topic's name, type or serialisation format is not UTF-8 text"
    )


def test_non_utf8_text_in_columns_not_read_is_not_decoded(tmp_path):
    """offered_qos_profiles and the metadata table (rosbag2 schema 3 on) are never selected."""
    path = _db(
        tmp_path / "x.db3",
        "ALTER TABLE topics ADD COLUMN offered_qos_profiles",
        f"UPDATE topics SET offered_qos_profiles = {NOT_UTF8}",
        "CREATE TABLE metadata (id INTEGER PRIMARY KEY, metadata_version, metadata)",
        f"INSERT INTO metadata VALUES (1, 9, {NOT_UTF8})",
    )
    assert st.sqlite_messages([path], ["/a"]).log_ns == {"/a": [5]}


def test_a_sqlite3_bag_written_by_rosbags_reads_with_utf8_topic_names(tmp_path):
    pytest.importorskip("rosbags.rosbag2")
    import numpy as np

    from control.robot.bags import read_recording, write_sensor_bag

    t = np.arange(20) * 0.01
    imu, odom = "/\u00edmu/donn\u00e9es", "/\u043e\u0434\u043e\u043c"
    bag = write_sensor_bag(tmp_path / "bag", t, np.sin(t), t[::4], t[::4], np.ones(5),
                           storage="sqlite3", imu_topic=imu, odom_topic=odom)  # fmt: skip
    got = read_recording(bag, imu, odom)
    assert got.storage == "sqlite3"
    assert got.imu.stamp_ns.tolist() == [round(v * 1e9) for v in t]
    assert got.odometry.stamp_ns.tolist() == [round(v * 1e9) for v in t[::4]]
