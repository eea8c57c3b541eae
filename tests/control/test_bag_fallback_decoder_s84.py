"""The generic decoder behind the fast one: messages whose layout the fast CDR decoder refuses
(big-endian data, a type the file defines otherwise) are decoded with the definitions the file
carries, as rosbags reads a bag, whichever path (an indexed MCAP file, an unindexed one, a
sqlite3 bag) reads them."""

import numpy as np
import pytest

pytest.importorskip("rosbags")
pytest.importorskip("mcap")

from rosbags.typesys import Stores, get_types_from_msg, get_typestore  # noqa: E402

from control.errors import BagError  # noqa: E402
from control.robot import messages as msgs  # noqa: E402
from control.robot import read_recording  # noqa: E402
from control.robot.bags import merge_in_time, open_bag_writer, sensor_messages  # noqa: E402

N = 40
T = 2.0 + np.arange(N) / 120.0
ACCEL = np.random.default_rng(3).normal(0.0, 2.0, N)
SEP = "=" * 80 + "\n"
# a trimmed Imu under the standard name: header and linear acceleration only
TRIMMED_IMU = (
    "std_msgs/Header header\ngeometry_msgs/Vector3 linear_acceleration\n"
    "float64[9] linear_acceleration_covariance\n"
)
IDL = {  # the standard Imu in ROS 2 IDL, one block a type
    "sensor_msgs/msg/Imu": "module sensor_msgs { module msg { struct Imu { "
    "std_msgs::msg::Header header; geometry_msgs::msg::Quaternion orientation; "
    "double orientation_covariance[9]; geometry_msgs::msg::Vector3 angular_velocity; "
    "double angular_velocity_covariance[9]; geometry_msgs::msg::Vector3 linear_acceleration; "
    "double linear_acceleration_covariance[9]; }; }; };\n",
    "std_msgs/msg/Header": "module std_msgs { module msg { struct Header { "
    "builtin_interfaces::msg::Time stamp; string frame_id; }; }; };\n",
    "builtin_interfaces/msg/Time": "module builtin_interfaces { module msg { struct Time { "
    "int32 sec; uint32 nanosec; }; }; };\n",
    "geometry_msgs/msg/Vector3": "module geometry_msgs { module msg { struct Quaternion { "
    "double x; double y; double z; double w; }; struct Vector3 { double x; double y; "
    "double z; }; }; };\n",
}
IDL_BLOCKS = "".join(f"{SEP}IDL: {name}\n{text}" for name, text in IDL.items())


def _drive():
    return sensor_messages(T, ACCEL, T, T - 2.0, np.ones(N))


def _big_endian(data: list[bytes], msgtype: str) -> list[bytes]:
    store = msgs.typestore()
    return [
        bytes(store.serialize_cdr(store.deserialize_cdr(d, msgtype), msgtype, little_endian=False))
        for d in data
    ]


def _standard(msgtype: str) -> tuple[str, str]:
    return "ros2msg", msgs.typestore().generate_msgdef(msgtype, ros_version=2)[0]


def _trimmed(imu: list[bytes]) -> tuple[tuple[str, str], list[bytes]]:
    """(definition, messages) of the trimmed Imu, holding the standard messages' fields."""
    std = msgs.typestore()
    deps = _standard(msgs.IMU_TYPE)[1].partition(SEP)[2]
    text = TRIMMED_IMU + SEP + deps
    own = get_typestore(Stores.EMPTY)
    own.register(get_types_from_msg(text, msgs.IMU_TYPE))
    out = []
    for d in imu:
        m = std.deserialize_cdr(d, msgs.IMU_TYPE)
        trimmed = own.types[msgs.IMU_TYPE](
            m.header, m.linear_acceleration, m.linear_acceleration_covariance
        )
        out.append(bytes(own.serialize_cdr(trimmed, msgs.IMU_TYPE)))
    return ("ros2msg", text), out


def _mcap(path, imu_schema, imu, odom_schema=None, odom=None, chunked=True):
    """An MCAP file (chunked: indexed, read fast; else read by the mcap package) of the drive's
    IMU and odometry messages under these schemas ((encoding, text))."""
    from mcap.writer import Writer

    t_imu, imu0, t_odom, odom0 = _drive()
    odom_schema = odom_schema or _standard(msgs.ODOMETRY_TYPE)
    with open(path, "wb") as f:
        w = Writer(f, use_chunking=chunked)
        w.start(profile="ros2", library="test")
        channels = []
        for topic, msgtype, (encoding, text) in (
            ("/imu/data", msgs.IMU_TYPE, imu_schema),
            ("/odometry/filtered", msgs.ODOMETRY_TYPE, odom_schema),
        ):
            schema = w.register_schema(msgtype, encoding, text.encode())
            channels.append(w.register_channel(topic, "cdr", schema))
        streams = [(channels[0], t_imu, imu or imu0), (channels[1], t_odom, odom or odom0)]
        for channel, stamp, data in merge_in_time(streams):
            w.add_message(channel, log_time=stamp, data=data, publish_time=stamp)
        w.finish()
    return path


def _assert_drive(rec):
    t_imu, _, t_odom, _ = _drive()
    assert np.array_equal(rec.imu.stamp_ns, t_imu)
    assert np.array_equal(rec.imu.accel[:, 2], ACCEL)
    assert not rec.imu.accel[:, :2].any()
    assert np.array_equal(rec.odometry.stamp_ns, t_odom)
    assert np.array_equal(rec.odometry.position[:, 0], T - 2.0)
    assert np.array_equal(rec.odometry.velocity[:, 0], np.ones(N))


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_big_endian_messages_in_a_bag_decode_to_their_values(tmp_path, storage):
    # the fast decoder reads little-endian CDR only; big-endian goes the generic way
    t_imu, imu, t_odom, odom = _drive()
    store = msgs.typestore()
    with open_bag_writer(tmp_path / "bag", storage=storage) as w:
        for topic, msgtype, stamps, data in (
            ("/imu/data", msgs.IMU_TYPE, t_imu, imu),
            ("/odometry/filtered", msgs.ODOMETRY_TYPE, t_odom, odom),
        ):
            conn = w.add_connection(topic, msgtype, typestore=store)
            for stamp, d in zip(stamps.tolist(), _big_endian(data, msgtype), strict=True):
                w.write(conn, stamp, d)
    rec = read_recording(tmp_path / "bag")
    assert rec.storage == storage
    _assert_drive(rec)


@pytest.mark.parametrize("chunked", [True, False])
def test_a_files_own_definition_of_imu_decodes_its_messages_on_either_path(tmp_path, chunked):
    # an indexed MCAP file decoded such messages with ROS 2's standard Imu (the file's own,
    # "clashing", definition was passed over) and called the file damaged ("message 0 ... does
    # not deserialise"), where the same messages unindexed (and rosbags) read right
    _, imu, _, _ = _drive()
    schema, trimmed = _trimmed(imu)
    rec = read_recording(_mcap(tmp_path / "own.mcap", schema, trimmed, chunked=chunked))
    _assert_drive(rec)


@pytest.mark.parametrize("chunked", [True, False])
def test_an_idl_schema_in_mcaps_block_form_decodes(tmp_path, chunked):
    # MCAP's ros2idl schema: one "IDL: <type>" block a type, each after a line of 80 '='
    # (the form rosbag2 writes); the unindexed path called such a file damaged ("does not
    # parse"); big-endian data, so the definition is used
    _, imu, _, odom = _drive()
    be_imu = _big_endian(imu, msgs.IMU_TYPE)
    be_odom = _big_endian(odom, msgs.ODOMETRY_TYPE)
    path = _mcap(tmp_path / "idl.mcap", ("ros2idl", IDL_BLOCKS), be_imu, None, be_odom, chunked)
    _assert_drive(read_recording(path))
    # one IDL text without blocks reads too
    text = "".join(IDL.values())
    _assert_drive(read_recording(_mcap(tmp_path / "one.mcap", ("ros2idl", text), be_imu)))


@pytest.mark.parametrize("chunked", [True, False])
def test_an_empty_schema_leaves_the_standard_definition_to_serve(tmp_path, chunked):
    # a recorder that does not know a type's definition writes an empty schema
    _, imu, _, _ = _drive()
    path = _mcap(
        tmp_path / "empty.mcap", ("", ""), _big_endian(imu, msgs.IMU_TYPE), None, None, chunked
    )
    _assert_drive(read_recording(path))


@pytest.mark.parametrize("chunked", [True, False])
def test_a_schema_that_does_not_parse_is_named(tmp_path, chunked):
    _, imu, _, _ = _drive()
    path = _mcap(
        tmp_path / "bad.mcap", ("ros2msg", "float64[ x"),
        _big_endian(imu, msgs.IMU_TYPE), None, None, chunked,
    )  # fmt: skip
    with pytest.raises(BagError, match=r"damaged: the schema of the topic '/imu/data' does "
                                       r"not parse \(TypesysError"):  # fmt: skip
        read_recording(path)
