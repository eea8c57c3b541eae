"""Exact tests of `control.robot.storage` from its mutation testing (session 90).

The files are built by hand, byte by byte (records, chunks, CRCs by `zlib.crc32`), or written
with the mcap package and then changed at a chosen offset; each refusal is checked word for
word, each limit at its value and one past it.
"""

import sqlite3
import struct
import zlib
from types import SimpleNamespace

import pytest

from control.errors import BagError, ControlError
from control.robot import storage as st

MAGIC = b"\x89MCAP0\r\n"


def _record(op: int, body: bytes) -> bytes:
    """An MCAP record: opcode, little-endian length, body."""
    return bytes([op]) + struct.pack("<Q", len(body)) + body


def _message(channel: int, log: int, data: bytes, seq: int = 0) -> bytes:
    """A Message record (publish time = log time)."""
    return _record(0x05, struct.pack("<HIQQ", channel, seq, log, log) + data)


def _chunk(records: bytes, crc: int | None = None, compression: str = "", stored=None) -> bytes:
    """A Chunk record of ``records`` (CRC by zlib unless given; ``stored``: the bytes kept, by
    default ``records`` themselves)."""
    stored = records if stored is None else stored
    crc = zlib.crc32(records) if crc is None else crc
    name = compression.encode()
    body = struct.pack("<QQQI", 0, 0, len(records), crc) + struct.pack("<I", len(name)) + name
    return _record(0x06, body + struct.pack("<Q", len(stored)) + stored)


def _header(profile: bytes = b"", library: bytes = b"") -> bytes:
    body = struct.pack("<I", len(profile)) + profile + struct.pack("<I", len(library)) + library
    return _record(0x01, body)


FOOTER = _record(0x02, bytes(20))


def _out(*topics: str) -> st.RawTopics:
    out = st.RawTopics()
    for topic in topics:
        out.log_ns[topic], out.data[topic], out.schema_index[topic] = [], [], []
    return out


def _damage(call) -> str:
    with pytest.raises(st._Damaged) as info:
        call()
    return str(info.value)


# --- module constants -----------------------------------------------------------------------


def test_the_smallest_mcap_file_is_62_bytes_and_a_message_starts_31_bytes_in():
    smallest = MAGIC + _header() + FOOTER + MAGIC
    assert st.MIN_MCAP_BYTES == len(smallest) == 62
    assert st._MESSAGE_DATA == len(_message(1, 0, b"")) == 31
    assert (st.OP_MESSAGE, st.OP_CHUNK, st.OP_DATA_END) == (5, 6, 15)


# --- _read_at_most ----------------------------------------------------------------------------


def _reader(source: bytes, asked: list[int]):
    pending = [source]

    def read(n: int) -> bytes:
        asked.append(n)
        data = pending[0]
        pending[0] = data[n:]
        return data[:n]

    return read


def test_reading_at_most_stops_at_the_limit_and_asks_for_no_more_than_it():
    asked = []
    assert st._read_at_most(_reader(b"abcdefghij", asked), 4) == b"abcd"
    assert asked == [4]


def test_reading_at_most_takes_four_mebibytes_at_a_time():
    asked = []
    limit = 2 * (1 << 22) + 5
    assert len(st._read_at_most(_reader(bytes(limit + 7), asked), limit)) == limit
    assert asked == [1 << 22, 1 << 22, 5]


def test_reading_at_most_ends_with_the_data_and_a_zero_limit_reads_nothing():
    asked = []
    assert st._read_at_most(_reader(b"abc", asked), 10) == b"abc"
    assert asked == [10, 7]
    asked.clear()
    assert st._read_at_most(_reader(b"abc", asked), 0) == b""
    assert asked == []


# --- decompression ----------------------------------------------------------------------------


def test_a_zstd_frame_is_inflated_to_its_declared_size_and_one_byte_more_at_most():
    zstandard = pytest.importorskip("zstandard")
    data = bytes(range(200)) * 3
    plain = zstandard.ZstdCompressor(write_content_size=False).compress(data)
    assert st._unzstd(plain, 600) == data
    assert st._unzstd(plain, 100) == data[:101]  # the frame does not say: stopped at size + 1
    assert st._decompress(zstandard.ZstdCompressor().compress(data), "zstd", 600) == data


def test_a_zstd_frame_declaring_another_size_is_named():
    zstandard = pytest.importorskip("zstandard")
    frame = zstandard.ZstdCompressor().compress(b"abcd")
    assert _damage(lambda: st._unzstd(frame, 5)) == "its zstd frame declares 4 bytes, its header 5"
    assert _damage(lambda: st._unzstd(b"not zstd", 5)).startswith("zstd: ")


def test_an_lz4_frame_is_inflated_to_its_size_and_one_byte_more_at_most():
    lz4 = pytest.importorskip("lz4.frame")
    data = bytes(range(200)) * 3
    frame = lz4.compress(data)
    assert st._unlz4(frame, 600) == data
    assert st._unlz4(frame, 100) == data[:101]
    assert st._decompress(frame, "lz4", 600) == data
    assert _damage(lambda: st._unlz4(b"\x04\x22\x4d\x18garbage!", 5)).startswith("lz4: ")


def test_a_chunk_whose_records_are_not_its_declared_size_is_named_both_ways():
    assert st._decompress(b"abcd", "", 4) == b"abcd"
    short = _damage(lambda: st._decompress(b"abc", "", 4))
    assert short == "its records hold 3 bytes, not the 4 bytes its header declares"
    long = _damage(lambda: st._decompress(b"abcde", "", 4))
    assert long == "its records hold more than the 4 bytes its header declares"
    odd = _damage(lambda: st._decompress(b"abcd", "gzip", 4))
    assert odd == "its compression 'gzip' is none of MCAP's ('', zstd, lz4)"


# --- _chunk_records ---------------------------------------------------------------------------


def test_a_chunks_records_come_back_checked_against_a_hand_computed_crc():
    records = _message(1, 7, b"xyz")
    assert st._chunk_records(_chunk(records)) == records
    assert st._chunk_records(_chunk(records, crc=0)) == records  # 0: not computed
    bad = _chunk(records, crc=zlib.crc32(records) ^ 1)
    assert _damage(lambda: st._chunk_records(bad)) == "its records do not match their CRC"


def test_a_chunk_cut_short_by_one_byte_is_named_and_a_whole_one_is_not():
    raw = _chunk(b"abcdefgh", crc=0)
    assert st._chunk_records(raw) == b"abcdefgh"
    cut = _damage(lambda: st._chunk_records(raw[:-1]))
    assert cut == "it is cut short: 7 of its 8 bytes of records"
    # bytes past the declared records are not the chunk's
    assert st._chunk_records(raw + b"more") == b"abcdefgh"


def test_a_chunk_index_pointing_at_another_record_is_named_with_its_opcode():
    raw = _message(1, 0, b"") + bytes(40)
    assert _damage(lambda: st._chunk_records(raw)) == (
        "the summary's chunk index points at a record of opcode 0x5"
    )


def test_a_chunks_compression_name_is_read_at_its_length():
    zstandard = pytest.importorskip("zstandard")
    records = _message(2, 1, b"abc")
    raw = _chunk(records, compression="zstd", stored=zstandard.ZstdCompressor().compress(records))
    assert st._chunk_records(raw) == records
    name = raw.index(b"zstd")
    bad = raw[:name] + b"\xff" + raw[name + 1 :]
    assert _damage(lambda: st._chunk_records(bad)) == "its compression's name is not UTF-8 text"


# --- _walk ------------------------------------------------------------------------------------


def test_walking_records_keeps_the_wanted_channels_messages_with_their_schema_index():
    out = _out("/a", "/b")
    records = (
        _message(1, 5, b"ab")
        + _record(0x07, b"\x00" * 6)  # another record between the messages
        + _message(3, 6, b"not wanted")
        + _message(2, 8, b"cde")
        + _message(1, 9, b"")  # the shortest message record: 22 bytes
    )
    st._walk(records, {1: ("/a", 0), 2: ("/b", 1)}, out)
    assert out.log_ns == {"/a": [5, 9], "/b": [8]}
    assert out.data == {"/a": [b"ab", b""], "/b": [b"cde"]}
    assert out.schema_index == {"/a": [0, 0], "/b": [1]}


def test_a_message_record_one_byte_shorter_than_its_fields_is_named_at_its_offset():
    first = _message(1, 5, b"ab")
    short = _record(0x05, bytes(21)) + bytes(30)  # 21 < 22 bytes of fields, then more records
    out = _out("/a")
    why = _damage(lambda: st._walk(first + short, {1: ("/a", 0)}, out))
    assert why == f"a message record at byte {len(first)} of its records is too short"


def test_a_short_message_record_among_the_last_bytes_is_named_at_its_offset():
    first = _message(1, 5, b"ab")
    out = _out("/a")
    st._walk(first + _record(0x07, bytes(13)), {1: ("/a", 0)}, out)  # 22 bytes: not a message
    assert out.log_ns["/a"] == [5]
    why = _damage(lambda: st._walk(first + _record(0x05, bytes(13)), {1: ("/a", 0)}, _out("/a")))
    assert why == f"a message record at byte {len(first)} of its records is too short"


def test_a_last_record_one_byte_past_the_end_is_named_and_one_ending_there_is_not():
    for last in (_message(1, 6, b"xyz"), _record(0x07, bytes(5))):
        records = _message(1, 5, b"ab") + last
        out = _out("/a")
        st._walk(records, {1: ("/a", 0)}, out)
        assert len(out.log_ns["/a"]) == 1 + (last[0] == 5)
        why = _damage(lambda r=records: st._walk(r[:-1], {1: ("/a", 0)}, _out("/a")))
        assert why == "its last record runs past its end"


def test_walking_no_records_finds_nothing():
    out = _out("/a")
    st._walk(b"", {1: ("/a", 0)}, out)
    assert out.log_ns == {"/a": []}


# --- mcap_messages, _mcap_file, indexed_metadata ----------------------------------------------

SCHEMA_A = ("pkg/msg/A", "ros2msg", "int32 x")
SCHEMA_B = ("pkg/msg/B", "ros2msg", "float64 y")


def _mcap(path, channels, messages, metadata=(), chunk_size=1 << 20, **options):
    """An MCAP file written by the mcap package (chunks uncompressed): ``channels`` a list of
    (topic, (schema name, encoding, text) or None, message encoding), ``messages`` a list of
    (index in ``channels``, log time, data), ``metadata`` a list of (name, dict)."""
    from mcap.writer import CompressionType, Writer

    with open(path, "wb") as f:
        w = Writer(f, chunk_size=chunk_size, compression=CompressionType.NONE, **options)
        w.start(profile="ros2", library="test")
        ids, schemas = [], {}
        for topic, schema, encoding in channels:
            sid = 0
            if schema is not None:
                if schema not in schemas:
                    schemas[schema] = w.register_schema(schema[0], schema[1], schema[2].encode())
                sid = schemas[schema]
            ids.append(w.register_channel(topic, encoding, sid))
        for k, log, data in messages:
            w.add_message(ids[k], log_time=log, data=data, publish_time=log)
        for name, data in metadata:
            w.add_metadata(name, data)
        w.finish()
    return path


def _summary(path):
    from mcap.reader import make_reader

    with open(path, "rb") as f:
        return make_reader(f).get_summary()


def _change_summary(monkeypatch, change) -> None:
    """The summary `_mcap_file` reads changed by ``change(summary)``."""
    import mcap.reader

    real = mcap.reader.make_reader

    def make_reader(f):
        summary = real(f).get_summary()
        change(summary)
        return SimpleNamespace(get_summary=lambda: summary)

    monkeypatch.setattr(mcap.reader, "make_reader", make_reader)


def test_a_topics_channels_give_its_definitions_schema_index_type_and_encoding(tmp_path):
    pytest.importorskip("mcap")
    channels = [
        ("/a", SCHEMA_A, "cdr"),
        ("/a", SCHEMA_B, "json"),
        ("/a", None, "cdr"),
        ("/a", SCHEMA_A, "protobuf"),
        ("/b", SCHEMA_B, "cdr"),
        ("/c", SCHEMA_A, "cdr"),
    ]
    messages = [(0, 1, b"a0"), (1, 2, b"a1"), (2, 3, b"a2"), (3, 4, b"a3"), (4, 5, b"b"),
                (5, 6, b"c")]  # fmt: skip
    path = _mcap(tmp_path / "x.mcap", channels, messages)
    out = st.mcap_messages([path], ["/a", "/b"])
    assert out.types == {"/a": None, "/b": "pkg/msg/B", "/c": "pkg/msg/A"}
    assert out.encodings == {"/a": "json", "/b": "cdr"}
    assert out.definitions == {
        "/a": [("ros2msg", "int32 x"), ("ros2msg", "float64 y"), ("", "")],
        "/b": [("ros2msg", "float64 y")],
    }
    assert out.log_ns == {"/a": [1, 2, 3, 4], "/b": [5]}
    assert out.data == {"/a": [b"a0", b"a1", b"a2", b"a3"], "/b": [b"b"]}
    assert out.schema_index == {"/a": [0, 1, 2, 0], "/b": [0]}
    assert out.metadata == {}


def test_messages_of_several_files_and_chunks_come_in_file_and_chunk_order(tmp_path):
    pytest.importorskip("mcap")
    one = [("/a", SCHEMA_A, "cdr")]
    first = _mcap(tmp_path / "1.mcap", one, [(0, t, bytes([t]) * 200) for t in range(5)],
                  chunk_size=300)  # fmt: skip
    second = _mcap(tmp_path / "2.mcap", one, [(0, 10 + t, b"s") for t in range(3)])
    assert len(_summary(first).chunk_indexes) > 2
    out = st.mcap_messages([first, second], ["/a"])
    assert out.log_ns["/a"] == [0, 1, 2, 3, 4, 10, 11, 12]
    assert out.data["/a"][:5] == [bytes([t]) * 200 for t in range(5)]
    assert out.schema_index["/a"] == [0] * 8
    assert out.definitions == {"/a": [("ros2msg", "int32 x")]}


def test_chunks_are_read_in_file_order_whatever_the_index_order(tmp_path, monkeypatch):
    pytest.importorskip("mcap")
    path = _mcap(tmp_path / "x.mcap", [("/a", SCHEMA_A, "cdr")],
                 [(0, t, bytes(300)) for t in range(4)], chunk_size=300)  # fmt: skip
    _change_summary(monkeypatch, lambda s: s.chunk_indexes.reverse())
    assert st.mcap_messages([path], ["/a"]).log_ns["/a"] == [0, 1, 2, 3]


def test_a_damaged_chunk_of_unwanted_channels_only_is_not_read(tmp_path):
    pytest.importorskip("mcap")
    channels = [("/a", SCHEMA_A, "cdr"), ("/b", SCHEMA_A, "cdr")]
    messages = [(1, 1, bytes(300)), (0, 2, bytes(300)), (0, 3, bytes(300))]
    path = _mcap(tmp_path / "x.mcap", channels, messages, chunk_size=300)
    chunks = sorted(_summary(path).chunk_indexes, key=lambda c: c.chunk_start_offset)
    assert list(chunks[0].message_index_offsets) == [2]  # the first holds /b's message alone
    data = bytearray(path.read_bytes())
    data[chunks[0].chunk_start_offset + chunks[0].chunk_length - 1] ^= 0xFF  # its last byte
    path.write_bytes(bytes(data))
    assert st.mcap_messages([path], ["/a"]).log_ns == {"/a": [2, 3]}
    with pytest.raises(BagError) as info:
        st.mcap_messages([path], ["/b"])
    start = chunks[0].chunk_start_offset
    assert str(info.value) == (
        f"{path} is damaged: the chunk at byte {start}: its records do not match their CRC"
    )


def test_a_chunk_running_one_byte_past_the_file_is_named(tmp_path, monkeypatch):
    pytest.importorskip("mcap")
    path = _mcap(tmp_path / "x.mcap", [("/a", SCHEMA_A, "cdr")], [(0, 1, b"abc")])
    size = path.stat().st_size
    (index,) = _summary(path).chunk_indexes
    length = index.chunk_length

    def move(to):
        def change(summary):
            summary.chunk_indexes[0].chunk_start_offset = to

        return change

    _change_summary(monkeypatch, move(size - length + 1))
    with pytest.raises(BagError) as info:
        st.mcap_messages([path], ["/a"])
    assert str(info.value) == (
        f"{path} is damaged: the chunk at byte {size - length + 1}: its {length} bytes run "
        f"past the file's {size}"
    )
    _change_summary(monkeypatch, move(size - length))  # ends at the file's end: its bytes read
    with pytest.raises(BagError) as info:
        st.mcap_messages([path], ["/a"])
    assert str(info.value).startswith(
        f"{path} is damaged: the chunk at byte {size - length}: the summary's chunk index "
        "points at a record of opcode"
    )


def test_a_chunk_shorter_than_its_header_is_named_cut_short(tmp_path, monkeypatch):
    pytest.importorskip("mcap")
    path = _mcap(tmp_path / "x.mcap", [("/a", SCHEMA_A, "cdr")], [(0, 1, b"abc")])
    (index,) = _summary(path).chunk_indexes

    def change(summary):
        summary.chunk_indexes[0].chunk_length = 20

    _change_summary(monkeypatch, change)
    with pytest.raises(BagError) as info:
        st.mcap_messages([path], ["/a"])
    why = str(info.value)
    assert why.startswith(
        f"{path} is damaged: the chunk at byte {index.chunk_start_offset}: a record is cut "
        "short (unpack_from requires a buffer of at least"
    )
    assert isinstance(info.value.__cause__, st._Damaged)


@pytest.mark.parametrize("what", ["none", "no chunks", "no statistics"])
def test_a_file_that_is_not_the_simple_case_is_left_to_the_generic_readers(tmp_path, what):
    pytest.importorskip("mcap")
    path = tmp_path / "x.mcap"
    if what == "none":
        path.write_bytes(MAGIC + b"not a recording")
    else:
        options = {"use_chunking": False} if what == "no chunks" else {"use_statistics": False}
        _mcap(path, [("/a", SCHEMA_A, "cdr")], [(0, 1, b"abc")], **options)
    good = _mcap(tmp_path / "good.mcap", [("/a", SCHEMA_A, "cdr")], [(0, 1, b"abc")])
    assert st.mcap_messages([good], ["/a"]) is not None
    assert st.mcap_messages([good, path], ["/a"]) is None


def test_messages_outside_chunks_leave_the_file_to_the_generic_readers(tmp_path, monkeypatch):
    pytest.importorskip("mcap")
    channels = [("/a", SCHEMA_A, "cdr"), ("/a", SCHEMA_B, "cdr"), ("/b", SCHEMA_A, "cdr")]
    path = _mcap(tmp_path / "x.mcap", channels, [(0, 1, b"a"), (1, 2, b"b"), (2, 3, b"c")])
    counts = _summary(path).statistics.channel_message_counts
    assert counts == {1: 1, 2: 1, 3: 1}

    def counted(new):
        def change(summary):
            summary.statistics.channel_message_counts = new

        return change

    _change_summary(monkeypatch, counted({1: 1, 2: 2, 3: 1}))  # one of /a's not in a chunk
    assert st.mcap_messages([path], ["/a"]) is None
    _change_summary(monkeypatch, counted({1: 1, 2: 1, 3: 5}))  # /b's: not asked for
    assert st.mcap_messages([path], ["/a"]).log_ns == {"/a": [1, 2]}
    _change_summary(monkeypatch, counted({1: 1}))  # a channel not counted: nothing to check
    assert st.mcap_messages([path], ["/a"]).log_ns == {"/a": [1, 2]}


def test_a_schema_that_is_not_utf8_names_its_topic(tmp_path):
    pytest.importorskip("mcap")
    path = _mcap(tmp_path / "x.mcap", [("/a", ("pkg/msg/A", "ros2msg", "int32 \u00e9"), "cdr")],
                 [(0, 1, b"a")])  # fmt: skip
    data = path.read_bytes()
    path.write_bytes(data.replace("\u00e9".encode(), b"\xff\xfe"))
    with pytest.raises(BagError) as info:
        st.mcap_messages([path], ["/a"])
    assert str(info.value) == f"{path} is damaged: the schema of '/a' is not UTF-8 text"
    # a topic not asked for: its schema is not read
    assert st.mcap_messages([path], ["/b"]).types == {"/a": "pkg/msg/A"}


def _metadata_file(tmp_path):
    path = _mcap(tmp_path / "m.mcap", [("/a", SCHEMA_A, "cdr")], [(0, 1, b"a")],
                 metadata=[("m", {"k": "v"}), ("n", {}), ("m", {"k": "w", "j": ""})])  # fmt: skip
    return path, _summary(path).metadata_indexes


def test_metadata_records_up_to_the_limit_are_read_and_one_byte_more_is_refused(tmp_path):
    pytest.importorskip("mcap")
    path, indexes = _metadata_file(tmp_path)
    longest = max(i.length for i in indexes if i.name == "m")
    out = st.mcap_messages([path, path], ["/a"], ["m", "x"], limit=longest)
    assert out.metadata == {"m": [{"k": "v"}, {"k": "w", "j": ""}] * 2, "x": []}
    assert out.log_ns == {"/a": [1, 1]}
    with pytest.raises(BagError) as info:
        st.mcap_messages([path], ["/a"], ["m"], limit=longest - 1)
    assert str(info.value) == (
        f"{path} is damaged: its 'm' metadata record is {longest} bytes long, more than "
        f"{longest - 1} allowed"
    )


def test_metadata_asked_for_without_a_limit_is_refused_at_zero_bytes(tmp_path):
    pytest.importorskip("mcap")
    path, indexes = _metadata_file(tmp_path)
    (n,) = [i.length for i in indexes if i.name == "n"]
    with pytest.raises(BagError) as info:
        st.mcap_messages([path], ["/a"], ["n"])
    assert str(info.value) == (
        f"{path} is damaged: its 'n' metadata record is {n} bytes long, more than 0 allowed"
    )
    assert st.mcap_messages([path], ["/a"]).metadata == {}


def test_a_metadata_index_pointing_at_another_record_is_named(tmp_path):
    pytest.importorskip("mcap")
    path, indexes = _metadata_file(tmp_path)
    n = next(i for i in indexes if i.name == "n")
    first_m = next(i for i in indexes if i.name == "m")
    with open(path, "rb") as f:
        summary = SimpleNamespace(metadata_indexes=[SimpleNamespace(
            name="n", offset=first_m.offset, length=n.length)])  # fmt: skip
        with pytest.raises(BagError) as info:
            st.indexed_metadata(path, f, summary, ["n"], 1000)
        assert str(info.value) == (
            f"{path} is damaged: its 'n' metadata record: the summary's index points at "
            "another record"
        )
        chunk = _summary(path).chunk_indexes[0]
        summary.metadata_indexes[0].offset = chunk.chunk_start_offset  # a Chunk record
        with pytest.raises(BagError) as info:
            st.indexed_metadata(path, f, summary, ["n"], 1000)
        assert str(info.value).endswith("the summary's index points at another record")
        summary.metadata_indexes[0].offset = n.offset + 1  # inside it
        with pytest.raises(BagError) as info:
            st.indexed_metadata(path, f, summary, ["n"], 1000)
        assert str(info.value).startswith(
            f"{path} is damaged: its 'n' metadata record cannot be read ("
        )
        summary.metadata_indexes[0].offset = n.offset
        assert st.indexed_metadata(path, f, summary, ["n", "m"], 1000) == {"n": [{}], "m": []}


# --- writer_library, check_mcap_target, truncation --------------------------------------------


def test_the_writer_library_is_read_from_a_whole_header_only():
    head = MAGIC + _header(b"ros2", b"lib")
    assert st.writer_library(head) == "lib"
    assert st.writer_library(head + b"more") == "lib"
    assert st.writer_library(head[:-1]) is None  # the library's last byte missing
    assert st.writer_library(MAGIC + _header()) == ""
    assert st.writer_library(MAGIC + _header(b"", b"\xffx")) == "\ufffdx"
    assert st.writer_library(MAGIC + _record(0x02, bytes(20))) is None  # not a Header
    assert st.writer_library(head[:17]) is None
    assert st.writer_library(head[:16]) is None
    assert st.writer_library(head[: 21 + 4 + 3]) is None  # the library's length cut short
    assert st.writer_library(b"") is None


def _refused(path, what: str) -> str:
    return (
        f"out={str(path)!r} holds {what}; a recording replaces only an earlier MCAP file of "
        "record_run: remove it or choose another path"
    )


def _target_error(path) -> str | None:
    try:
        st.check_mcap_target(path, "out")
    except ControlError as exc:
        return str(exc)
    return None


def test_a_recording_target_is_refused_by_what_it_holds(tmp_path):
    path = tmp_path / "x.mcap"
    assert _target_error(path) is None  # a new path
    path.write_bytes(b"")
    assert _target_error(path) is None
    ours = MAGIC + _header(b"ros2", st.LIBRARY.encode()) + FOOTER + MAGIC
    path.write_bytes(ours + bytes(10000))
    assert _target_error(path) is None
    path.write_bytes(MAGIC + _header(b"ros2", b"rosbag2") + FOOTER + MAGIC)
    assert _target_error(path) == _refused(
        path, "an MCAP recording written by 'rosbag2', not by record_run"
    )
    path.write_bytes(b"\x89MCAP0\r")  # one byte short of the magic
    assert _target_error(path) == _refused(path, "a file that is not an MCAP recording")
    assert _target_error(tmp_path) == (
        f"out={str(tmp_path)!r} is a folder; name the .mcap file to write"
    )


def test_an_unreadable_header_is_refused_from_the_smallest_mcap_size_on(tmp_path):
    path = tmp_path / "x.mcap"
    path.write_bytes(MAGIC + b"\x02" + bytes(st.MIN_MCAP_BYTES - 10))  # 61 bytes
    assert _target_error(path) is None  # a stub shorter than any MCAP file
    path.write_bytes(MAGIC + b"\x02" + bytes(st.MIN_MCAP_BYTES - 9))  # 62 bytes
    assert _target_error(path) == _refused(
        path, "an MCAP file whose header does not say which program wrote it"
    )


def test_a_header_is_read_from_the_first_4096_bytes(tmp_path):
    path = tmp_path / "x.mcap"
    library = st.LIBRARY.encode()
    fits = MAGIC + _header(bytes(4096 - 25 - len(library)), library)
    assert len(fits) == 4096
    path.write_bytes(fits + FOOTER + MAGIC)
    assert _target_error(path) is None
    path.write_bytes(MAGIC + _header(bytes(4097 - 25 - len(library)), library) + FOOTER + MAGIC)
    assert _target_error(path) == _refused(
        path, "an MCAP file whose header does not say which program wrote it"
    )


def test_a_target_that_is_not_a_plain_file_or_cannot_be_read_is_refused(tmp_path, monkeypatch):
    import errno
    import os

    fifo = tmp_path / "fifo"
    if not hasattr(os, "mkfifo"):
        pytest.skip("no named pipes")
    os.mkfifo(fifo)
    assert _target_error(fifo) == _refused(fifo, "something other than a plain file")
    path = tmp_path / "x.mcap"
    path.write_bytes(b"")

    def fstat(fd):
        raise OSError(errno.EIO, os.strerror(errno.EIO))

    monkeypatch.setattr(st.os, "fstat", fstat)
    assert _target_error(path) == (
        f"out={str(path)!r} cannot be read to check it: [Errno {errno.EIO}] "
        f"{os.strerror(errno.EIO)}"
    )


def _truncation(tmp_path, data: bytes) -> str:
    path = tmp_path / "t.mcap"
    path.write_bytes(data)
    with open(path, "rb") as f:
        return st.truncation(f)


def test_truncation_is_named_at_the_smallest_mcap_size_and_the_end_magic(tmp_path):
    smallest = MAGIC + _header() + FOOTER + MAGIC
    assert _truncation(tmp_path, smallest) == ""
    assert _truncation(tmp_path, smallest + MAGIC) == ""
    cut = "is truncated: {} bytes, shorter than an MCAP file's magic bytes, header and footer " \
          "(62 bytes at least)"  # fmt: skip
    assert _truncation(tmp_path, smallest[:-1]) == cut.format(61)
    assert _truncation(tmp_path, b"") == cut.format(0)
    assert _truncation(tmp_path, MAGIC[:3]) == cut.format(3)
    assert _truncation(tmp_path, smallest[:-1] + b"\x00") == (
        "is truncated: its 62 bytes do not end with MCAP's magic bytes (a file cut short, e.g. "
        "an interrupted recording, or damaged at its end)"
    )
    not_mcap = "is not an MCAP file: it does not start with MCAP's magic bytes"
    assert _truncation(tmp_path, b"\x89MX") == not_mcap
    assert _truncation(tmp_path, b"\x00" + smallest[1:]) == not_mcap


def test_noting_types_and_encodings():
    types: dict = {}
    st.note_type(types, "/a", "A")
    st.note_type(types, "/a", "A")
    assert types == {"/a": "A"}
    st.note_type(types, "/a", "B")
    st.note_type(types, "/a", "A")
    assert types == {"/a": None}
    encodings: dict = {}
    st.note_encoding(encodings, "/a", "cdr")
    assert encodings == {"/a": "cdr"}
    st.note_encoding(encodings, "/a", "json")
    st.note_encoding(encodings, "/a", "cdr")
    st.note_encoding(encodings, "/a", "protobuf")
    assert encodings == {"/a": "json"}


# --- write_chunk_crcs -------------------------------------------------------------------------


def _crc_at(data: bytes, chunk_at: int) -> int:
    return struct.unpack_from("<I", data, chunk_at + 9 + 24)[0]


def test_chunk_crcs_are_written_where_0_and_only_before_the_data_end(tmp_path):
    zstandard = pytest.importorskip("zstandard")
    one, two = _message(1, 1, b"first"), _message(1, 2, b"second") * 2
    three = _message(1, 3, b"third")
    head = MAGIC + _header(b"ros2", b"x")
    chunks = [
        _chunk(one, crc=0),
        _chunk(two, crc=zlib.crc32(two)),
        _chunk(three, crc=0, compression="zstd", stored=zstandard.ZstdCompressor().compress(three)),
    ]
    after = _chunk(one, crc=0)  # past the Data End record: not a chunk of the data section
    data = head + b"".join(chunks) + _record(0x0F, bytes(4)) + after + FOOTER + MAGIC
    path = tmp_path / "x.mcap"
    path.write_bytes(data)
    st.write_chunk_crcs(path)
    at = [len(head), len(head) + len(chunks[0]), len(head) + len(chunks[0]) + len(chunks[1])]
    written = path.read_bytes()
    assert len(written) == len(data)
    assert [_crc_at(written, a) for a in at] == [zlib.crc32(one), zlib.crc32(two),
                                                 zlib.crc32(three)]  # fmt: skip
    expected = bytearray(data)
    for a, records in ((at[0], one), (at[2], three)):
        expected[a + 33 : a + 37] = struct.pack("<I", zlib.crc32(records))
    assert written == bytes(expected)  # no other byte changed
    st.write_chunk_crcs(path)  # a second time: nothing to do
    assert path.read_bytes() == bytes(expected)


def test_giving_crcs_stops_at_a_data_end_record_even_before_damaged_bytes(tmp_path):
    path = tmp_path / "x.mcap"
    past = b"\x07" + struct.pack("<Q", 1 << 40)  # a record whose length runs past the end
    data = MAGIC + _header() + _record(0x0F, bytes(4)) + past
    path.write_bytes(data)
    st.write_chunk_crcs(path)
    assert path.read_bytes() == data


def test_giving_crcs_names_a_record_one_byte_past_the_end_and_not_one_ending_there(tmp_path):
    path = tmp_path / "x.mcap"
    head = MAGIC + _header()
    whole = head + _record(0x07, bytes(10))
    path.write_bytes(whole)
    st.write_chunk_crcs(path)
    assert path.read_bytes() == whole
    path.write_bytes(whole[:-1])
    with pytest.raises(BagError) as info:
        st.write_chunk_crcs(path)
    assert str(info.value) == (
        f"{path} is damaged: the record at byte {len(head)} runs past the file's end "
        "(10 bytes declared, 9 left)"
    )


def test_giving_crcs_names_a_damaged_chunk_and_a_file_without_magic(tmp_path):
    path = tmp_path / "x.mcap"
    head = MAGIC + _header()
    records = _message(1, 1, b"abc")
    path.write_bytes(head + _chunk(records, crc=zlib.crc32(records) + 1) + FOOTER + MAGIC)
    with pytest.raises(BagError) as info:
        st.write_chunk_crcs(path)
    assert str(info.value) == (
        f"{path} is damaged: the chunk at byte {len(head)}: its records do not match their CRC"
    )
    path.write_bytes(head + _record(0x06, bytes(10)) + FOOTER + MAGIC)  # a chunk cut short
    with pytest.raises(BagError) as info:
        st.write_chunk_crcs(path)
    assert str(info.value).startswith(
        f"{path} is damaged: the chunk at byte {len(head)}: unpack_from requires"
    )
    path.write_bytes(b"\x00" + head[1:])
    with pytest.raises(BagError) as info:
        st.write_chunk_crcs(path)
    assert str(info.value) == f"{path} is not an MCAP file (no magic bytes)"


# --- sqlite3 ----------------------------------------------------------------------------------


def _db(path, topics, messages, definitions=None):
    """A minimal rosbag2 sqlite3 file: ``topics`` (id, name, type, format) rows, ``messages``
    (id, topic id, time stamp, data) rows, ``definitions`` (type, encoding, text) rows of a
    message_definitions table (none: no such table)."""
    con = sqlite3.connect(path)
    con.execute("CREATE TABLE topics (id INTEGER PRIMARY KEY, name, type, serialization_format)")
    con.execute("CREATE TABLE messages (id INTEGER PRIMARY KEY, topic_id, timestamp, data)")
    con.executemany("INSERT INTO topics VALUES (?, ?, ?, ?)", topics)
    con.executemany("INSERT INTO messages VALUES (?, ?, ?, ?)", messages)
    if definitions is not None:
        con.execute(
            "CREATE TABLE message_definitions (id INTEGER PRIMARY KEY, topic_type, encoding, "
            "encoded_message_definition)"
        )
        con.executemany(
            "INSERT INTO message_definitions (topic_type, encoding, encoded_message_definition) "
            "VALUES (?, ?, ?)",
            definitions,
        )
    con.commit()
    con.close()
    return path


TOPICS = [(1, "/a", "pkg/msg/A", "cdr"), (2, "/b", "pkg/msg/B", "cdr"), (3, "/c", "pkg/msg/A", "x")]


def test_sqlite_messages_come_by_time_stamp_then_id_with_types_and_encodings(tmp_path):
    messages = [(1, 1, 30, b"a30"), (2, 1, 10, b"a10a"), (3, 2, 5, b"b5"), (4, 1, 10, b"a10b"),
                (5, 3, 1, b"c1")]  # fmt: skip
    first = _db(tmp_path / "1.db3", TOPICS, messages)
    second = _db(tmp_path / "2.db3", TOPICS[:1], [(1, 1, 0, b"later")])
    out = st.sqlite_messages([first, second], ["/a", "/c", "/none"])
    assert out.types == {"/a": "pkg/msg/A", "/b": "pkg/msg/B", "/c": "pkg/msg/A"}
    assert out.encodings == {"/a": "cdr", "/c": "x"}
    assert out.log_ns == {"/a": [10, 10, 30, 0], "/c": [1], "/none": []}
    assert out.data == {"/a": [b"a10a", b"a10b", b"a30", b"later"], "/c": [b"c1"], "/none": []}
    assert out.definitions == {}


@pytest.mark.parametrize(
    "topics, messages, why",
    [
        ([(1, "/a", None, "cdr")], [], "the topic of id 1 lacks its name, type or serialisation "
         "format"),
        ([(7, "/a", "A", b"cdr")], [], "the topic of id 7 lacks its name, type or serialisation "
         "format"),
        ([(1, 5, "A", "cdr")], [], "the topic of id 1 lacks its name, type or serialisation "
         "format"),
        ([(1, "/a", "A", "cdr")], [(1, 1, 1.5, b"x")], "a message of the topic '/a' lacks an "
         "integer time stamp or its data"),
        ([(1, "/a", "A", "cdr")], [(1, 1, 1, "x")], "a message of the topic '/a' lacks an "
         "integer time stamp or its data"),
    ],
)  # fmt: skip
def test_sqlite_values_of_another_type_are_named(tmp_path, topics, messages, why):
    path = _db(tmp_path / "x.db3", topics, messages)
    with pytest.raises(BagError) as info:
        st.sqlite_messages([path], ["/a"])
    assert str(info.value) == f"{path} is damaged: {why}"


def test_a_message_of_a_topic_not_asked_for_is_not_checked(tmp_path):
    path = _db(tmp_path / "x.db3", TOPICS, [(1, 2, "text", None), (2, 1, 4, b"a")])
    assert st.sqlite_messages([path], ["/a"]).log_ns == {"/a": [4]}


def test_a_topic_name_that_is_not_utf8_and_a_file_that_is_not_sqlite_are_named(tmp_path):
    path = _db(tmp_path / "x.db3", [(1, "/\u00e9", "A", "cdr")], [])
    data = path.read_bytes()
    path.write_bytes(data.replace("/\u00e9".encode(), b"/\xff\xfe"))  # as many bytes
    with pytest.raises(BagError) as info:
        st.sqlite_messages([path], ["/a"])
    assert str(info.value) == (
        f"{path} is damaged: a topic's name, type or serialisation format is not UTF-8 text"
    )
    other = tmp_path / "other.db3"
    other.write_bytes(b"not a database" * 100)
    with pytest.raises(BagError) as info:
        st.sqlite_messages([other], ["/a"])
    assert str(info.value) == (
        f"{other} is not a readable rosbag2 sqlite3 file: file is not a database"
    )


def test_the_first_definition_of_a_type_is_each_topics_and_a_topic_keeps_its_first(tmp_path):
    definitions = [("pkg/msg/A", "ros2msg", b"int32 a"), ("pkg/msg/A", "idl", b"other"),
                   ("pkg/msg/B", "ros2msg", "float64 b")]  # fmt: skip
    first = _db(tmp_path / "1.db3", TOPICS, [], definitions)
    second = _db(tmp_path / "2.db3", [(1, "/a", "pkg/msg/A", "cdr")], [],
                 [("pkg/msg/A", "ros2msg", b"int32 changed")])  # fmt: skip
    out = st.sqlite_messages([first, second], ["/a", "/b"])
    assert out.definitions == {"/a": [("ros2msg", "int32 a")], "/b": [("ros2msg", "float64 b")]}
    # a topic whose type has no definition, or several types: none
    third = _db(tmp_path / "3.db3", TOPICS, [], [("pkg/msg/C", "ros2msg", b"x")])
    assert st.sqlite_messages([third], ["/a"]).definitions == {}


@pytest.mark.parametrize(
    "definition, why",
    [
        (("pkg/msg/A", "ros2msg", b"\xff"), "the message definition of the topic '/a' is not "
         "UTF-8 text"),
        ((None, "ros2msg", b"x"), "a message definition lacks its type, encoding or text"),
        (("pkg/msg/A", 3, b"x"), "a message definition lacks its type, encoding or text"),
        (("pkg/msg/A", "ros2msg", None), "a message definition lacks its type, encoding or "
         "text"),
    ],
)  # fmt: skip
def test_a_damaged_message_definition_is_named(tmp_path, definition, why):
    path = _db(tmp_path / "x.db3", TOPICS, [], [definition])
    with pytest.raises(BagError) as info:
        st.sqlite_messages([path], ["/a"])
    assert str(info.value) == f"{path} is damaged: {why}"


def test_a_bad_definition_of_a_type_not_asked_for_is_not_decoded(tmp_path):
    path = _db(tmp_path / "x.db3", TOPICS, [], [("pkg/msg/B", "ros2msg", b"\xff")])
    assert st.sqlite_messages([path], ["/a"]).definitions == {}


def _pages(tmp_path):
    path = _db(tmp_path / "x.db3", TOPICS, [(k, 1, k, bytes(3000)) for k in range(1, 6)])
    con = sqlite3.connect(path)
    try:
        page = con.execute("PRAGMA page_size").fetchone()[0]
        pages = con.execute("PRAGMA page_count").fetchone()[0]
    finally:
        con.close()
    data = path.read_bytes()
    assert len(data) == page * pages
    return path, data, page, pages


def _sqlite_error(path) -> str:
    with pytest.raises(BagError) as info:
        st.sqlite_messages([path], ["/a"])
    return str(info.value)


def test_a_sqlite3_file_one_byte_short_is_truncated_and_one_page_short_unreadable(tmp_path):
    path, data, page, pages = _pages(tmp_path)
    assert st.sqlite_messages([path], ["/a"]).log_ns == {"/a": [1, 2, 3, 4, 5]}
    path.write_bytes(data[:-1])
    assert _sqlite_error(path) == (
        f"{path} is truncated: {len(data) - 1} bytes, its header declares {pages} pages of {page}"
    )
    path.write_bytes(data[:-page])  # sqlite3 itself refuses fewer pages than its header's
    assert _sqlite_error(path) == (
        f"{path} is not a readable rosbag2 sqlite3 file: database disk image is malformed"
    )


def test_a_sqlite3_file_with_bytes_appended_is_named_damaged_not_truncated(tmp_path):
    path, data, page, pages = _pages(tmp_path)
    path.write_bytes(data + b"\x00")
    assert _sqlite_error(path) == (
        f"{path} is damaged: {len(data) + 1} bytes, not a whole number of its {page}-byte "
        f"pages ({pages} declared)"
    )
    path.write_bytes(data + bytes(page))  # a whole page more: sqlite3 reads the pages declared
    assert st.sqlite_messages([path], ["/a"]).log_ns == {"/a": [1, 2, 3, 4, 5]}


def test_a_sqlite3_file_beside_a_write_ahead_log_is_not_checked(tmp_path):
    path, data, _, _ = _pages(tmp_path)
    path.write_bytes(data + b"\x00")
    (tmp_path / "x.db3-wal").write_bytes(b"")
    con = sqlite3.connect(f"{path.resolve().as_uri()}?mode=ro", uri=True)
    try:
        st._check_complete(con, path)
    finally:
        con.close()
    (tmp_path / "x.db3-wal").unlink()
    con = sqlite3.connect(f"{path.resolve().as_uri()}?mode=ro", uri=True)
    try:
        with pytest.raises(BagError, match="is damaged"):
            st._check_complete(con, path)
    finally:
        con.close()


def test_reading_a_sqlite3_file_closes_it(tmp_path, monkeypatch):
    path = _db(tmp_path / "x.db3", TOPICS, [(1, 1, 1, b"a")])
    opened, real = [], sqlite3.connect

    def connect(*args, **kwargs):
        opened.append(real(*args, **kwargs))
        return opened[-1]

    monkeypatch.setattr(st.sqlite3, "connect", connect)
    st.sqlite_messages([path], ["/a"])
    (con,) = opened
    with pytest.raises(sqlite3.ProgrammingError):
        con.execute("SELECT 1")
