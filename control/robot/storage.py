"""Raw messages of chosen topics straight from MCAP and sqlite3 storage files, fast.

rosbags and the mcap package build a Python object per record (10-25 us a message on this
project's machine), which alone would hold a replay of a 120 Hz IMU below 200x real time. Here
an MCAP file's chunks are found through its summary (the mcap package reads it) and their
records walked with `struct` (~1 us a message); a sqlite3 file is one query per topic. Each
function returns None where the file is not the simple, common case (no summary or chunk
index, messages outside chunks, an unknown chunk compression, a schema it does not know): the
caller then reads with rosbags or the mcap package.
"""

from __future__ import annotations

import sqlite3
import struct
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

from control.robot.extra import require

_RECORD = struct.Struct("<BQ")  # opcode, length
_MESSAGE = struct.Struct("<HIQ")  # channel id, sequence, log time (publish time follows)
_MESSAGE_DATA = 9 + 2 + 4 + 8 + 8  # offset of a Message record's data from the record's start
_CHUNK = struct.Struct("<QQQI")  # start and end time, uncompressed size, crc
OP_MESSAGE, OP_CHUNK = 0x05, 0x06


@dataclass
class RawTopics:
    """Messages of some topics, each in the order read.

    Attributes:
        types: every topic of the files and its message type.
        log_ns: topic -> receive times (int ns).
        data: topic -> serialised messages (bytes).
        definitions: topic -> (schema encoding, schema text) where the file has one.
        encodings: topic -> message encoding ("cdr" for ROS 2).
    """

    types: dict[str, str] = field(default_factory=dict)
    log_ns: dict[str, list[int]] = field(default_factory=dict)
    data: dict[str, list[bytes]] = field(default_factory=dict)
    definitions: dict[str, tuple[str, str]] = field(default_factory=dict)
    encodings: dict[str, str] = field(default_factory=dict)


def _decompress(data: bytes, compression: str, size: int) -> bytes | None:
    if compression == "":
        return data
    if compression == "zstd":
        zstandard = require("zstandard", "reading a zstd-compressed MCAP file")
        return zstandard.ZstdDecompressor().decompress(data, max_output_size=size)
    if compression == "lz4":
        return require("lz4.frame", "reading an lz4-compressed MCAP file").decompress(data)
    return None


def _chunk_records(raw: bytes) -> bytes | None:
    """The (decompressed) records of a Chunk record, or None if it is not one we know."""
    op, _length = _RECORD.unpack_from(raw, 0)
    if op != OP_CHUNK:
        return None
    _start, _end, size, _crc = _CHUNK.unpack_from(raw, 9)
    pos = 9 + _CHUNK.size
    (n_comp,) = struct.unpack_from("<I", raw, pos)
    compression = raw[pos + 4 : pos + 4 + n_comp].decode()
    pos += 4 + n_comp
    (n_rec,) = struct.unpack_from("<Q", raw, pos)
    return _decompress(raw[pos + 8 : pos + 8 + n_rec], compression, size)


def _walk(records: bytes, wanted: dict[int, str], out: RawTopics) -> None:
    """Append the Message records of the wanted channels (id -> topic)."""
    pos, end = 0, len(records)
    head, message = _RECORD.unpack_from, _MESSAGE.unpack_from
    while pos < end:
        op, length = head(records, pos)
        if op == OP_MESSAGE:
            channel, _seq, log = message(records, pos + 9)
            topic = wanted.get(channel)
            if topic is not None:
                out.log_ns[topic].append(log)
                out.data[topic].append(records[pos + _MESSAGE_DATA : pos + 9 + length])
        pos += 9 + length


def mcap_messages(paths: Sequence[Path], topics: Sequence[str]) -> RawTopics | None:
    """The messages of ``topics`` in MCAP files (None where a file is not the simple case)."""
    reader_mod = require("mcap.reader", "reading an MCAP file")
    out = RawTopics()
    for topic in topics:
        out.log_ns[topic], out.data[topic] = [], []
    for path in paths:
        with open(path, "rb") as f:
            try:
                summary = reader_mod.make_reader(f).get_summary()
            except Exception:  # a damaged or unindexed file: the generic reader reports it
                return None
            if summary is None or not summary.chunk_indexes or summary.statistics is None:
                return None
            wanted = {}
            for cid, channel in summary.channels.items():
                schema = summary.schemas.get(channel.schema_id)
                name = schema.name if schema is not None else ""
                out.types.setdefault(channel.topic, name)
                if channel.topic in out.log_ns:
                    wanted[cid] = channel.topic
                    out.encodings[channel.topic] = channel.message_encoding
                    if schema is not None:
                        out.definitions[channel.topic] = (schema.encoding, schema.data.decode())
            before = {t: len(v) for t, v in out.log_ns.items()}
            for index in sorted(summary.chunk_indexes, key=lambda c: c.chunk_start_offset):
                if not set(index.message_index_offsets) & set(wanted):
                    continue
                f.seek(index.chunk_start_offset)
                records = _chunk_records(f.read(index.chunk_length))
                if records is None:
                    return None
                _walk(records, wanted, out)
            counts = summary.statistics.channel_message_counts
            for cid, topic in wanted.items():
                found = len(out.log_ns[topic]) - before[topic]
                if counts.get(cid, found) != found:  # messages outside chunks
                    return None
    return out


def sqlite_messages(paths: Sequence[Path], topics: Sequence[str]) -> RawTopics:
    """The messages of ``topics`` in rosbag2 sqlite3 files, by receive time."""
    out = RawTopics()
    for topic in topics:
        out.log_ns[topic], out.data[topic] = [], []
    for path in paths:
        con = sqlite3.connect(f"file:{Path(path).resolve()}?mode=ro", uri=True)
        try:
            rows = con.execute("SELECT id, name, type, serialization_format FROM topics")
            ids = {}
            for tid, name, msgtype, encoding in rows.fetchall():
                out.types.setdefault(name, msgtype)
                if name in out.log_ns:
                    ids[tid] = name
                    out.encodings[name] = encoding
            for tid, name in ids.items():
                rows = con.execute(
                    "SELECT timestamp, data FROM messages WHERE topic_id = ? "
                    "ORDER BY timestamp, id",
                    (tid,),
                ).fetchall()
                out.log_ns[name].extend(r[0] for r in rows)
                out.data[name].extend(r[1] for r in rows)
        finally:
            con.close()
    return out
