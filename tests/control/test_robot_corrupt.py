"""Damaged recordings: a `BagError` naming the file, or the undamaged result, never a crash.

Small recordings are written with the project's writers (`write_sensor_bag`, the messages and
the MCAP layout of `record_run`, the ROS 1 writer of test_robot_replay.py), then truncated or
corrupted byte by byte.
"""

import shutil
from types import SimpleNamespace

import numpy as np
import pytest

pytest.importorskip("rosbags")
pytest.importorskip("mcap")

from test_robot_replay import _write_ros1_bag  # noqa: E402

from control.errors import BagError, ControlError  # noqa: E402
from control.robot import cli, read_recording, write_sensor_bag  # noqa: E402
from control.robot import messages as msgs  # noqa: E402
from control.robot.bags import merge_in_time, sensor_messages  # noqa: E402

N = 60  # messages per topic
TOPICS = ("/imu/data", "/odometry/filtered")


def _signals(n: int = N):
    """(IMU time s, accel, odometry time s, position, speed) of a short drive at 120 Hz."""
    t = 1.0 + np.arange(n) / 120.0
    accel = np.random.default_rng(0).normal(size=n)
    return t, accel, t, 0.5 * (t - 1.0), np.full(n, 0.5)


def _write_mcap(path, compression: str, chunk_size: int = 4096):
    """A bare MCAP file as `record_run` writes one (ROS 2 messages, ros2msg schemas, chunks
    with CRCs), chunks compressed with ``compression`` ("zstd", "lz4" or "none")."""
    from mcap.writer import CompressionType, Writer

    t_imu, imu, t_odom, odom = sensor_messages(*_signals())
    store = msgs.typestore()
    with open(path, "wb") as f:
        writer = Writer(f, chunk_size=chunk_size, compression=CompressionType[compression.upper()])
        writer.start(profile="ros2", library="terrain-gpmsa")
        channels = []
        for topic, msgtype in zip(TOPICS, (msgs.IMU_TYPE, msgs.ODOMETRY_TYPE), strict=True):
            definition, _ = store.generate_msgdef(msgtype, ros_version=2)
            schema = writer.register_schema(msgtype, "ros2msg", definition.encode())
            channels.append(writer.register_channel(topic, "cdr", schema))
        streams = [(channels[0], t_imu, imu), (channels[1], t_odom, odom)]
        for channel, stamp, data in merge_in_time(streams):
            writer.add_message(channel, log_time=stamp, data=data, publish_time=stamp)
        writer.finish()
    return path


@pytest.fixture(scope="module")
def recordings(tmp_path_factory):
    """kind -> (what to read, the file to damage inside it)."""
    root = tmp_path_factory.mktemp("recordings")
    out = {}
    for compression in ("none", "zstd", "lz4"):
        path = _write_mcap(root / f"{compression}.mcap", compression)
        out[f"mcap-{compression}"] = (path, path)
    for storage, suffix in (("mcap", ".mcap"), ("sqlite3", ".db3")):
        folder = write_sensor_bag(root / f"bag_{storage}", *_signals(), storage=storage)
        out[f"rosbag2-{storage}"] = (folder, next(folder.glob(f"*{suffix}")))
    t, accel, _, position, speed = _signals()
    run = SimpleNamespace(
        sample_time=t, sample_accel=accel, sample_position=position, sample_speed=speed
    )
    path = _write_ros1_bag(run, root / "run.bag")
    out["ros1"] = (path, path)
    return out


def _copy(recordings, kind: str, tmp_path):
    """A copy of a recording to damage: (what to read, the file inside it)."""
    target, file = recordings[kind]
    if target.is_dir():
        shutil.copytree(target, tmp_path / target.name)
        return tmp_path / target.name, tmp_path / target.name / file.name
    shutil.copy(target, tmp_path / target.name)
    return tmp_path / target.name, tmp_path / target.name


def _same(a, b) -> bool:
    return all(
        np.array_equal(getattr(x, k), getattr(y, k))
        for x, y in ((a.imu, b.imu), (a.odometry, b.odometry))
        for k in ("log_ns", "stamp_ns", *(("accel",) if x is a.imu else ("position", "velocity")))
    )


def _bag_error(target) -> BagError | None:
    """The BagError reading ``target`` raises, None where it reads; any other exception fails
    the test."""
    try:
        read_recording(target)
    except BagError as exc:
        assert str(target) in str(exc), str(exc)  # the message names the file
        return exc
    return None


def _write_flipped(file, data: bytes, at: int, mask: int) -> None:
    """Write ``data`` to ``file`` with the byte at ``at`` XORed with ``mask``."""
    file.write_bytes(data[:at] + bytes([data[at] ^ mask]) + data[at + 1 :])


def _chunks(path):
    """(start, length) of the chunks of an MCAP file, from its summary."""
    from mcap.reader import make_reader

    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
    return [(c.chunk_start_offset, c.chunk_length) for c in summary.chunk_indexes]


CHUNK_DATA = 9 + 8 + 8 + 8 + 4  # a Chunk record's opcode, length, times, size and CRC


def _records_at(data: bytes, start: int) -> tuple[int, int]:
    """(offset, length) of the (compressed) records of the chunk at ``start``."""
    pos = start + CHUNK_DATA
    n_comp = int.from_bytes(data[pos : pos + 4], "little")
    pos += 4 + n_comp
    return pos + 8, int.from_bytes(data[pos : pos + 8], "little")


@pytest.mark.parametrize("kind", ["mcap-none", "mcap-zstd", "mcap-lz4", "rosbag2-mcap",
                                  "rosbag2-sqlite3", "ros1"])  # fmt: skip
def test_a_truncated_recording_is_a_bag_error_naming_it(kind, recordings, tmp_path):
    target, file = _copy(recordings, kind, tmp_path)
    data = file.read_bytes()
    for cut in (0, 16, len(data) // 10, len(data) // 3, len(data) // 2, len(data) - 100,
                len(data) - 1):  # fmt: skip
        file.write_bytes(data[:cut])
        with pytest.raises(BagError) as info:
            read_recording(target)
        assert str(target) in str(info.value)


@pytest.mark.parametrize("compression", ["none", "zstd", "lz4"])
def test_a_flipped_byte_in_a_chunk_is_a_bag_error_naming_the_chunk(
    compression, recordings, tmp_path
):
    target, file = _copy(recordings, f"mcap-{compression}", tmp_path)
    data = file.read_bytes()
    for start, _ in _chunks(file)[:4]:
        at, length = _records_at(data, start)
        for k in (0, length // 2, length - 1):
            _write_flipped(file, data, at + k, 0x5A)
            with pytest.raises(BagError, match=f"{file} is damaged: the chunk at byte {start}"):
                read_recording(target)


def test_a_written_bags_chunks_carry_crcs_that_refuse_any_changed_byte(recordings, tmp_path):
    # rosbags' writer leaves each chunk's CRC 0 ("not computed"), and a flipped byte of a
    # message's orientation (unused) or receive time went unnoticed; `open_bag_writer` writes
    # the CRCs, which this package's reader, rosbags' and the mcap package's then check
    from mcap.reader import make_reader
    from mcap.stream_reader import CRCValidationError
    from rosbags.highlevel import AnyReader
    from rosbags.rosbag2 import ReaderError

    target, file = _copy(recordings, "rosbag2-mcap", tmp_path)
    data = file.read_bytes()
    starts = [start for start, _ in _chunks(file)]
    assert starts and all(int.from_bytes(data[s + 33 : s + 37], "little") for s in starts)
    t, accel, *_ = _signals()
    first = msgs.encode_imu(int(round(t[0] * 1e9)), [0.0, 0.0, accel[0]])
    at = data.find(first)
    assert at > 0 and data.find(first, at + 1) < 0
    orientation = at + len(first) - 8 * (4 + 9 + 3 + 9 + 3 + 9)
    log_time = at - 16  # the Message record's log time precedes its publish time and data
    for where in (orientation + 3, log_time):
        _write_flipped(file, data, where, 0x40)
        with pytest.raises(BagError, match=f"{file} is damaged: .* do not match their CRC"):
            read_recording(target)
        with open(file, "rb") as f, pytest.raises(CRCValidationError):
            list(make_reader(f, validate_crcs=True).iter_messages())
        with pytest.raises(ReaderError, match="checksum"), AnyReader([target]) as reader:
            list(reader.messages())


def test_a_chunk_whose_size_disagrees_with_its_zstd_frame_is_refused(recordings, tmp_path):
    target, file = _copy(recordings, "mcap-zstd", tmp_path)
    data = file.read_bytes()
    start, _ = _chunks(file)[0]
    size_at = start + 9 + 16
    size = int.from_bytes(data[size_at : size_at + 8], "little")
    file.write_bytes(data[:size_at] + (size + 1).to_bytes(8, "little") + data[size_at + 8 :])
    with pytest.raises(BagError, match=f"zstd frame declares {size} bytes, its header {size + 1}"):
        read_recording(target)


def test_a_zstd_frame_that_inflates_past_its_chunk_is_stopped_there(recordings, tmp_path):
    # a frame that does not declare its size (1 MiB of zeros in 47 bytes) in place of the
    # chunk's, the rest padded with a skippable frame: decompression stops at the header's size
    import zstandard

    target, file = _copy(recordings, "mcap-zstd", tmp_path)
    data = file.read_bytes()
    start, _ = _chunks(file)[0]
    at, length = _records_at(data, start)
    bomb = zstandard.ZstdCompressor(write_content_size=False).compress(bytes(1 << 20))
    assert zstandard.frame_content_size(bomb) == -1
    pad = length - len(bomb) - 8
    skippable = (0x184D2A50).to_bytes(4, "little") + pad.to_bytes(4, "little") + bytes(pad)
    file.write_bytes(data[:at] + bomb + skippable + data[at + length :])
    with pytest.raises(BagError, match="its records hold more than the .* bytes its header"):
        read_recording(target)


def test_a_corrupted_sqlite3_bag_is_a_bag_error(recordings, tmp_path):
    target, file = _copy(recordings, "rosbag2-sqlite3", tmp_path)
    data = file.read_bytes()
    file.write_bytes(b"not a database!\x00" + data[16:])
    with pytest.raises(BagError, match=f"{file} is not a readable rosbag2 sqlite3 file"):
        read_recording(target)
    # the end of the last page lost: sqlite3 would read zeros in its place without a word
    file.write_bytes(data[:-100])
    with pytest.raises(BagError, match=f"{file} is truncated"):
        read_recording(target)
    # the type of each page (byte 0 of its header; page 1's follows the file's header)
    errors = 0
    for at in [100, *range(4096, len(data), 4096)]:
        _write_flipped(file, data, at, 0xFF)
        errors += _bag_error(target) is not None
    assert errors >= 10  # of 19 pages (unused ones may take a flip unnoticed)


@pytest.mark.parametrize(
    ("sql", "match"),
    [
        ("UPDATE messages SET data = 'text' WHERE id = 7", "lacks an integer time stamp or its"),
        ("UPDATE messages SET timestamp = 1.5 WHERE id = 7", "lacks an integer time stamp or its"),
        ("CREATE TABLE t AS SELECT * FROM topics; DROP TABLE topics; "
         "ALTER TABLE t RENAME TO topics; UPDATE topics SET type = NULL",
         "lacks its name, type or serialisation format"),
    ],
)  # fmt: skip
def test_sqlite3_values_of_another_type_are_a_bag_error(sql, match, recordings, tmp_path):
    import sqlite3

    target, file = _copy(recordings, "rosbag2-sqlite3", tmp_path)
    con = sqlite3.connect(file)
    con.executescript(sql)
    con.close()
    with pytest.raises(BagError, match=f"{file} is damaged: .*{match}"):
        read_recording(target)


@pytest.mark.parametrize("kind", ["mcap-zstd", "rosbag2-mcap"])
def test_flipping_bytes_all_over_a_recording_never_crashes(kind, recordings, tmp_path):
    target, file = _copy(recordings, kind, tmp_path)
    data = file.read_bytes()
    rng = np.random.default_rng(11)
    step = len(data) // 400 + 1
    errors = 0
    for at in range(int(rng.integers(step)), len(data), step):
        _write_flipped(file, data, at, int(rng.integers(1, 256)))
        errors += _bag_error(target) is not None
    assert errors >= 10  # the rest: unread bytes (and, without CRCs, flipped values)


def test_the_command_reports_a_damaged_bag_in_one_line(recordings, tmp_path, capsys):
    target, file = _copy(recordings, "mcap-zstd", tmp_path)
    file.write_bytes(file.read_bytes()[:5000])
    code = cli.main([str(target), "--emulator", "A", "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1
    assert err.startswith("terrain-replay: error: ") and str(target) in err


@pytest.mark.parametrize("name", ["emulator.npz", "emulator.h5", "emulator.gpmsa"])
def test_the_command_reports_a_damaged_emulator_file_in_one_line(
    name, recordings, tmp_path, capsys
):
    emulator = tmp_path / name
    emulator.write_bytes(np.random.default_rng(0).bytes(3000))
    target, _ = recordings["mcap-zstd"]
    code = cli.main([str(target), "--emulator", str(emulator), "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1
    assert err.startswith(f"terrain-replay: error: --emulator {str(emulator)!r}: ")
    assert "not a gpmsa emulator file" in err


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_an_interrupted_bag_write_leaves_nothing_and_the_next_one_succeeds(
    tmp_path, monkeypatch, storage
):
    import control.robot.bags as bags

    path = tmp_path / "sub" / "drive"
    seen_during_write = []
    real_merge = bags.merge_in_time

    def failing_merge(streams):
        for k, item in enumerate(real_merge(streams)):
            if k == N // 2:  # half the messages written
                seen_during_write.append(path.exists())
                raise KeyboardInterrupt
            yield item

    monkeypatch.setattr(bags, "merge_in_time", failing_merge)
    with pytest.raises(KeyboardInterrupt):
        write_sensor_bag(path, *_signals(), storage=storage)
    assert seen_during_write == [False]  # a killed writer leaves no half bag at path either
    assert not path.exists() and list(path.parent.iterdir()) == []  # the hidden folder went

    monkeypatch.setattr(bags, "merge_in_time", real_merge)
    write_sensor_bag(path, *_signals(), storage=storage)
    rec = read_recording(path)
    assert rec.storage == storage and rec.imu.stamp_ns.size == rec.odometry.stamp_ns.size == N
    assert [p.name for p in tmp_path.joinpath("sub").iterdir()] == ["drive"]
    with pytest.raises(ControlError, match="exists already"):
        write_sensor_bag(path, *_signals(), storage=storage)


def test_giving_chunks_crcs_names_a_record_that_runs_past_the_files_end(recordings, tmp_path):
    # a damaged length of a record between chunks (a message index) sent the writer seeking
    # 2**62 bytes on (an OSError "Invalid argument"), and a chunk's reading 2**40 bytes (a
    # MemoryError): neither named the file nor the damage
    from control.robot.storage import write_chunk_crcs

    _, file = _copy(recordings, "mcap-none", tmp_path)
    data = file.read_bytes()
    start, length = _chunks(file)[0]
    after = start + length  # the record after the first chunk
    assert data[after] != 0x06  # not a chunk: its length is only skipped
    huge = data[: after + 1] + (1 << 62).to_bytes(8, "little") + data[after + 9 :]
    huge_chunk = data[: start + 1] + (1 << 40).to_bytes(8, "little") + data[start + 9 :]
    for damaged, at in ((huge, after), (data[: after + 20], after), (huge_chunk, start)):
        file.write_bytes(damaged)  # a huge length; a file cut short in the record
        with pytest.raises(BagError, match=f"{file} is damaged: the record at byte {at} runs "
                           "past the file's end"):  # fmt: skip
            write_chunk_crcs(file)
