"""The definition of our own message type written into every file carries its comments (the
units of GD, position, speed, the command), as ROS 2's rosbag2 and mcap writers store a .msg
definition (ros2msg: the type's text, then per dependency 80 '=' and ``MSG: <type>``); the
standard types' definitions are rosbags' own, as before (session 71)."""

import sqlite3

import pytest

pytest.importorskip("rosbags")
pytest.importorskip("mcap")

from _robot_cases import small_result  # noqa: E402
from mcap.reader import make_reader  # noqa: E402
from rosbags.highlevel import AnyReader  # noqa: E402
from rosbags.typesys import Stores, get_types_from_msg, get_typestore  # noqa: E402

from control.robot import messages as msgs  # noqa: E402
from control.robot import read_recording, record_run, replay_bag  # noqa: E402

UNITS = ("1e-6 m^3", "# m along the path", "# m/s, the Simplex's speed command")
SEP = "=" * 80 + "\nMSG: "


def _fields(text: str, name: str) -> dict:
    """{type: its fields} parsed from a ros2msg definition (comments dropped by the parser)."""
    return {k: v[1] for k, v in get_types_from_msg(text, name).items()}


def _check_estimate_definition(text: str) -> None:
    assert text.startswith(msgs.GD_ESTIMATE_MSG + SEP + "std_msgs/Header\n")
    assert all(unit in text for unit in UNITS)
    plain, _ = msgs.typestore().generate_msgdef(msgs.GD_ESTIMATE_TYPE, ros_version=2)
    assert _fields(text, msgs.GD_ESTIMATE_TYPE) == _fields(plain, msgs.GD_ESTIMATE_TYPE)
    assert text.split(SEP)[1:] == plain.split(SEP)[1:]  # the dependencies as rosbags writes them


def test_the_definition_function_keeps_comments_of_our_type_only():
    store = msgs.typestore()
    text, rihs01 = msgs.definition(store, msgs.GD_ESTIMATE_TYPE)
    _check_estimate_definition(text)
    assert rihs01 == store.hash_rihs01(msgs.GD_ESTIMATE_TYPE)  # comments do not enter the hash
    for msgtype in (msgs.IMU_TYPE, msgs.ODOMETRY_TYPE, msgs.FLOAT64_TYPE):
        want = store.generate_msgdef(msgtype, ros_version=2)[0], store.hash_rihs01(msgtype)
        assert msgs.definition(store, msgtype) == want


def test_a_recording_stores_the_commented_definition_and_reads_back(tmp_path):
    path = record_run(small_result(), tmp_path / "run.mcap")
    store = msgs.typestore()
    with path.open("rb") as f:
        reader = make_reader(f, validate_crcs=True)
        schemas = {s.name: s for s in reader.get_summary().schemas.values()}
        n = sum(1 for _ in reader.iter_messages(topics=["/bcr/estimate"]))
    _check_estimate_definition(schemas[msgs.GD_ESTIMATE_TYPE].data.decode())
    for msgtype in (msgs.IMU_TYPE, msgs.ODOMETRY_TYPE, msgs.FLOAT64_TYPE):
        plain = store.generate_msgdef(msgtype, ros_version=2)[0]
        assert schemas[msgtype].data.decode() == plain
    assert n == small_result().time.size
    assert read_recording(path).kind == "mcap"
    typestore = get_typestore(Stores.EMPTY)
    with AnyReader([path], default_typestore=typestore) as reader:  # the schema from the file
        conns = [c for c in reader.connections if c.topic == "/bcr/estimate"]
        got = [reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages(conns)]
    assert [m.gd_mean for m in got] == small_result().gd_mean.tolist()


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_the_replays_bag_stores_the_commented_definition(storage, emulator_a, tmp_path):
    run = record_run(small_result(600), tmp_path / "run.mcap")
    out = tmp_path / "estimates"
    result = replay_bag(run, emulator_a, out_bag=out, storage=storage, check_vehicle=False)
    if storage == "sqlite3":
        (db,) = out.glob("*.db3")
        with sqlite3.connect(db) as con:
            rows = dict(con.execute("SELECT topic_type, encoded_message_definition "
                                    "FROM message_definitions"))  # fmt: skip
        text = rows[msgs.GD_ESTIMATE_TYPE]
    else:
        (file,) = out.glob("*.mcap")
        with file.open("rb") as f:
            summary = make_reader(f, validate_crcs=True).get_summary()
        text = next(s.data.decode() for s in summary.schemas.values())
    _check_estimate_definition(text)
    with AnyReader([out], default_typestore=get_typestore(Stores.EMPTY)) as reader:
        got = [reader.deserialize(raw, c.msgtype) for c, _, raw in reader.messages()]
    assert [m.status for m in got] == result.status.tolist()
