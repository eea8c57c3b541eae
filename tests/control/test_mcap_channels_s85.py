"""An MCAP file reads the same whichever way it was written: chunked with a summary (the fast
reader), without chunks (the mcap package) or without a summary (a recording cut short: the
stream reader). Each message decodes with its own channel's schema (several recorders, or a
schema registered again, on one topic); a schema without the definitions of its sub-messages
takes ROS 2's standard ones, and one that uses a type neither it nor ROS 2 defines is refused
naming the topic, the schema and the type (session 85)."""

import struct

import numpy as np
import pytest

pytest.importorskip("rosbags")
pytest.importorskip("mcap")

from rosbags.typesys import Stores, get_types_from_msg, get_typestore  # noqa: E402

from control.errors import BagError  # noqa: E402
from control.robot import messages as msgs  # noqa: E402
from control.robot import read_recording  # noqa: E402
from control.robot.bags import merge_in_time, sensor_messages  # noqa: E402
from control.robot.storage import MAGIC  # noqa: E402

N = 40
T = 2.0 + np.arange(N) / 120.0
ACCEL = np.random.default_rng(5).normal(0.0, 2.0, N)
SEP = "=" * 80 + "\n"
IMU, ODOM = "/imu/data", "/odometry/filtered"
FORMS = ["chunked", "unchunked", "unindexed"]
HEADER_ONLY = (  # an Imu under the standard name that holds a header only
    f"std_msgs/Header header\n{SEP}MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\n"
    f"string frame_id\n{SEP}MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n"
)


def _drive():
    return sensor_messages(T, ACCEL, T, T - 2.0, np.ones(N))


def _standard(msgtype: str) -> str:
    return msgs.typestore().generate_msgdef(msgtype, ros_version=2)[0]


def _bare(msgtype: str) -> str:
    """The standard definition without its sub-messages' ("MSG: ...") blocks."""
    return _standard(msgtype).partition(SEP)[0]


def _recoded(data: list[bytes], text: str, little_endian: bool = True) -> list[bytes]:
    """Standard Imu messages as the Imu ``text`` defines it (its fields taken from them)."""
    std = msgs.typestore()
    own = get_typestore(Stores.EMPTY)
    own.register(get_types_from_msg(text, msgs.IMU_TYPE))
    cls = own.types[msgs.IMU_TYPE]
    out = []
    for d in data:
        m = std.deserialize_cdr(d, msgs.IMU_TYPE)
        fields = {name: getattr(m, name) for name in cls.__dataclass_fields__}
        out.append(
            bytes(own.serialize_cdr(cls(**fields), msgs.IMU_TYPE, little_endian=little_endian))
        )
    return out


def _trimmed() -> tuple[str, list[bytes]]:
    """(definition, messages) of an Imu with a header and linear acceleration only."""
    text = (
        "std_msgs/Header header\ngeometry_msgs/Vector3 linear_acceleration\n"
        "float64[9] linear_acceleration_covariance\n"
        + SEP
        + _standard(msgs.IMU_TYPE).partition(SEP)[2]
    )
    return text, _recoded(_drive()[1], text)


def _big_endian(data: list[bytes]) -> list[bytes]:
    return _recoded(data, _standard(msgs.IMU_TYPE), little_endian=False)


def _pick(data: list[bytes], mask: np.ndarray) -> list[bytes]:
    return [d for d, keep in zip(data, mask, strict=True) if keep]


def _unindexed(data: bytes) -> bytes:
    """An MCAP file's bytes without its summary (as a recording cut short and repaired)."""
    pos = len(MAGIC)
    while True:
        op, length = struct.unpack_from("<BQ", data, pos)
        pos += 9 + length
        if op == 0x0F:  # DataEnd
            break
    return data[:pos] + struct.pack("<BQQQI", 0x02, 20, 0, 0, 0) + MAGIC


def _mcap(path, form: str, imu_parts, extra=()):
    """An MCAP file (``form``: one of `FORMS`) of the drive's odometry and the IMU messages
    ``imu_parts`` (a channel each: (schema text or bytes, message indices, their data));
    ``extra``: (topic, type, encoding, schema
    text) of channels without messages."""
    from mcap.writer import Writer

    t_imu, _, t_odom, odom = _drive()
    with open(path, "wb") as f:
        w = Writer(f, use_chunking=form != "unchunked")
        w.start(profile="ros2", library="test")
        streams = []
        for text, idx, data in imu_parts:
            raw = text if isinstance(text, bytes) else text.encode()
            schema = w.register_schema(msgs.IMU_TYPE, "ros2msg", raw)
            streams.append((w.register_channel(IMU, "cdr", schema), t_imu[idx], data))
        schema = w.register_schema(
            msgs.ODOMETRY_TYPE, "ros2msg", _standard(msgs.ODOMETRY_TYPE).encode()
        )
        streams.append((w.register_channel(ODOM, "cdr", schema), t_odom, odom))
        for topic, msgtype, encoding, text in extra:
            schema = w.register_schema(msgtype, "ros2msg", text.encode())
            w.register_channel(topic, encoding, schema)
        for channel, stamp, data in merge_in_time(streams):
            w.add_message(channel, log_time=stamp, data=data, publish_time=stamp)
        w.finish()
    if form == "unindexed":
        path.write_bytes(_unindexed(path.read_bytes()))
    return path


def _assert_drive(rec):
    t_imu, _, t_odom, _ = _drive()
    assert np.array_equal(rec.imu.stamp_ns, t_imu)
    assert np.array_equal(rec.imu.accel[:, 2], ACCEL)
    assert not rec.imu.accel[:, :2].any()
    assert np.array_equal(rec.odometry.stamp_ns, t_odom)
    assert np.array_equal(rec.odometry.position[:, 0], T - 2.0)
    assert rec.topics == {IMU: msgs.IMU_TYPE, ODOM: msgs.ODOMETRY_TYPE}


@pytest.mark.parametrize("form", FORMS)
@pytest.mark.parametrize("split", ["halves", "interleaved"])
@pytest.mark.parametrize("standard_first", [True, False])
def test_each_channel_of_a_topic_decodes_with_its_own_schema(tmp_path, form, split, standard_first):
    # two recorders on /imu/data, one with the standard Imu, one with its own (trimmed) Imu:
    # every path decoded all the topic's messages with one schema (the last met) and called
    # the file damaged ("message 0 ... does not deserialise (SerdeError: CDR message size
    # mismatch ...)")
    _, imu, _, _ = _drive()
    text, trimmed = _trimmed()
    mine = np.arange(N) < N // 2 if split == "halves" else np.arange(N) % 2 == 0
    std = (_standard(msgs.IMU_TYPE), np.flatnonzero(mine), _pick(imu, mine))
    own = (text, np.flatnonzero(~mine), _pick(trimmed, ~mine))
    parts = [std, own] if standard_first else [own, std]
    _assert_drive(read_recording(_mcap(tmp_path / "two.mcap", form, parts)))


def test_a_file_reads_the_same_whichever_way_it_was_written(tmp_path):
    # standard messages, big-endian ones (the generic decoder), two schemas on one topic
    _, imu, _, _ = _drive()
    text, trimmed = _trimmed()
    half = np.arange(N) < N // 2
    files = {
        "standard": [(_standard(msgs.IMU_TYPE), np.arange(N), imu)],
        "big_endian": [(_standard(msgs.IMU_TYPE), np.arange(N), _big_endian(imu))],
        "two_schemas": [
            (text, np.flatnonzero(half), _pick(trimmed, half)),
            (_standard(msgs.IMU_TYPE), np.flatnonzero(~half), _big_endian(imu)[N // 2 :]),
        ],
    }
    for name, parts in files.items():
        recs = [read_recording(_mcap(tmp_path / f"{name}_{f}.mcap", f, parts)) for f in FORMS]
        for rec in recs:
            _assert_drive(rec)
        for rec in recs[1:]:
            assert rec.topics == recs[0].topics
            for got, want in ((rec.imu, recs[0].imu), (rec.odometry, recs[0].odometry)):
                for field in ("log_ns", "stamp_ns"):
                    assert np.array_equal(getattr(got, field), getattr(want, field))
            assert np.array_equal(rec.odometry.velocity, recs[0].odometry.velocity)


@pytest.mark.parametrize("form", FORMS)
def test_a_schema_without_its_sub_messages_takes_the_standard_ones(tmp_path, form):
    # sensor_msgs/msg/Imu given without its "MSG: std_msgs/Header" etc. blocks: the generic
    # decoder (big-endian data) failed with "does not deserialise (KeyError:
    # 'std_msgs/msg/Header')"
    _, imu, _, _ = _drive()
    parts = [(_bare(msgs.IMU_TYPE), np.arange(N), _big_endian(imu))]
    _assert_drive(read_recording(_mcap(tmp_path / "bare.mcap", form, parts)))


@pytest.mark.parametrize("form", FORMS)
def test_a_sub_message_neither_defined_nor_standard_is_named(tmp_path, form):
    _, imu, _, _ = _drive()
    text = _bare(msgs.IMU_TYPE) + "my_msgs/Extra[] extra\n"
    path = _mcap(tmp_path / "extra.mcap", form, [(text, np.arange(N), _big_endian(imu))])
    with pytest.raises(BagError) as info:
        read_recording(path)
    message = str(info.value)
    for part in ("'sensor_msgs/msg/Imu' (ros2msg)", "topic '/imu/data'", "'my_msgs/msg/Extra'"):
        assert part in message
    assert "KeyError" not in message


@pytest.mark.parametrize("form", FORMS)
def test_a_schema_without_the_fields_read_is_named(tmp_path, form):
    # an Imu defined with a header only: AttributeError escaped read_recording
    _, imu, _, _ = _drive()
    path = _mcap(
        tmp_path / "header.mcap", form, [(HEADER_ONLY, np.arange(N), _recoded(imu, HEADER_ONLY))]
    )
    why = r"message 0 of the topic '/imu/data' in .* lacks the fields the replay reads \(header"
    with pytest.raises(BagError, match=why):
        read_recording(path)


@pytest.mark.parametrize("form", FORMS)
@pytest.mark.parametrize(
    "extra, why",
    [
        ((IMU, msgs.ODOMETRY_TYPE, "cdr"), "holds several message types"),
        ((IMU, msgs.IMU_TYPE, "json"), "is encoded as 'json'"),
    ],
)
def test_a_topics_other_channels_count_on_every_path(tmp_path, form, extra, why):
    # a channel of another type or encoding on the IMU topic, without messages: the fast
    # reader refused the file, the others read it (or named another type, the last met)
    _, imu, _, _ = _drive()
    text = _standard(extra[1])
    path = _mcap(tmp_path / "x.mcap", form, [(_standard(msgs.IMU_TYPE), np.arange(N), imu)],
                 [(*extra, text)])  # fmt: skip
    with pytest.raises(BagError, match=why):
        read_recording(path)


@pytest.mark.parametrize("form", FORMS)
def test_a_schema_that_is_not_text_is_named_alike_on_every_path(tmp_path, form):
    # (the fast reader said so; the others "does not parse (UnicodeDecodeError ...)")
    _, imu, _, _ = _drive()
    text = b"\xff" + _standard(msgs.IMU_TYPE).encode()[1:]
    path = _mcap(tmp_path / "bad.mcap", form, [(text, np.arange(N), imu)])
    with pytest.raises(BagError, match=r"is damaged: the schema of '/imu/data' is not UTF-8"):
        read_recording(path)


def test_a_topic_of_several_channels_takes_the_fast_reader(tmp_path, monkeypatch):
    # its statistics count messages a channel, the fast reader found them a topic: they never
    # matched, and every such file went the slow way (the mcap package)
    from control.robot import bags

    _, imu, _, _ = _drive()
    half = np.arange(N) < N // 2
    parts = [(_standard(msgs.IMU_TYPE), np.flatnonzero(m), _pick(imu, m)) for m in (half, ~half)]
    path = _mcap(tmp_path / "two.mcap", "chunked", parts)

    def slow(*args):
        raise AssertionError("read by the mcap package")

    monkeypatch.setattr(bags, "_read_mcap", slow)
    _assert_drive(read_recording(path))
