"""Raw messages of chosen topics straight from MCAP and sqlite3 storage files, fast.

rosbags and the mcap package build a Python object per record (10-25 us a message on this
project's machine), which alone would hold a replay of a 120 Hz IMU below 200x real time. Here
an MCAP file's chunks are found through its summary (the mcap package reads it) and their
records walked with `struct` (~1 us a message); a sqlite3 file is one query per topic. Each
`mcap_messages` returns None where the file is not the simple, common case (no summary, chunk
index or statistics; messages outside chunks): the caller then reads with rosbags or the mcap
package. A file whose bytes contradict its own structure (a truncated or corrupted chunk, a CRC
that does not match, a chunk compression MCAP does not define, a truncated or damaged sqlite3
database) raises `BagError` naming the file and what is wrong. `write_chunk_crcs` gives the
chunks of an MCAP file written without CRCs (rosbags' writer) theirs.
"""

from __future__ import annotations

import os
import sqlite3
import struct
import zlib
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import partial
from pathlib import Path

from control.errors import BagError, ControlError
from control.robot.extra import require
from control.validation import check_lookup

_RECORD = struct.Struct("<BQ")  # opcode, length
_RECORD_MESSAGE = struct.Struct("<BQHIQ")  # a record's opcode and length, a message's fields
_MESSAGE_DATA = 9 + 2 + 4 + 8 + 8  # offset of a Message record's data from the record's start
_CHUNK = struct.Struct("<QQQI")  # start and end time, uncompressed size, crc
OP_MESSAGE, OP_CHUNK, OP_DATA_END = 0x05, 0x06, 0x0F
MAGIC = b"\x89MCAP0\r\n"
_PIECE = 1 << 22  # bytes decompressed at a time (the chunk's declared size bounds the total)
_FOOTER = 9 + 8 + 8 + 4  # a Footer record: opcode, length, summary start and offset, CRC
MIN_MCAP_BYTES = 2 * len(MAGIC) + 9 + 4 + 4 + _FOOTER
"""Size of the smallest MCAP file: magic bytes, a Header record (two empty strings), a Footer
record and the magic bytes again, bytes."""
LIBRARY = "terrain-gpmsa"
"""The ``library`` field of the Header record of the MCAP files `control.record_run` writes."""
_HEADER_BYTES = 1 << 12  # bytes read to find a Header record's library field


class _Damaged(Exception):
    """Bytes that contradict the structure around them (the caller names the file)."""


@dataclass
class RawTopics:
    """Messages of some topics, each in the order read.

    Attributes:
        types: every topic of the files and its message type (None: several types).
        log_ns: topic -> receive times (int ns).
        data: topic -> serialised messages (bytes).
        definitions: topic -> the (schema encoding, schema text) of each distinct schema its
            channels carry, in the order met (("", "") for a channel without one).
        schema_index: topic -> per message, the index in ``definitions[topic]`` of its
            channel's schema (an MCAP file's; absent: the topic's one definition, if any, is
            every message's).
        encodings: topic -> message encoding ("cdr" for ROS 2; where its channels differ,
            the first other than "cdr").
        metadata: name -> the metadata (a dict) of each Metadata record of that name, for
            the names asked for (an MCAP file's, found through its summary).
    """

    types: dict[str, str | None] = field(default_factory=dict)
    log_ns: dict[str, list[int]] = field(default_factory=dict)
    data: dict[str, list[bytes]] = field(default_factory=dict)
    definitions: dict[str, list[tuple[str, str]]] = field(default_factory=dict)
    schema_index: dict[str, list[int]] = field(default_factory=dict)
    encodings: dict[str, str] = field(default_factory=dict)
    metadata: dict[str, list[dict[str, str]]] = field(default_factory=dict)


def _read_at_most(read, limit: int) -> bytes:
    """Up to ``limit`` bytes of a decompressor, ``read(n)`` giving at most n bytes more (b"" at
    the end), taken ``_PIECE`` at a time: memory follows the data, not a declared size."""
    parts, got = [], 0
    while got < limit and (piece := read(min(_PIECE, limit - got))):
        parts.append(piece)
        got += len(piece)
    return b"".join(parts)


def _unzstd(data: bytes, size: int) -> bytes:
    """A zstd frame decompressed to at most ``size + 1`` bytes, whatever the frame declares."""
    zstandard = require("zstandard", "reading a zstd-compressed MCAP file")
    try:
        declared = zstandard.frame_content_size(data)
        if declared not in (-1, size):  # -1: the frame does not say
            raise _Damaged(f"its zstd frame declares {declared} bytes, its header {size}")
        with zstandard.ZstdDecompressor().stream_reader(data) as reader:
            return _read_at_most(reader.read, size + 1)
    except zstandard.ZstdError as exc:
        raise _Damaged(f"zstd: {exc}") from exc


def _unlz4(data: bytes, size: int) -> bytes:
    """An lz4 frame decompressed to at most ``size + 1`` bytes."""
    lz4 = require("lz4.frame", "reading an lz4-compressed MCAP file")
    decompressor, pending = lz4.LZ4FrameDecompressor(), [data]

    def read(n: int) -> bytes:  # the data first, then what the decompressor holds back
        return decompressor.decompress(pending.pop() if pending else b"", max_length=n)

    try:
        return _read_at_most(read, size + 1)
    except RuntimeError as exc:  # lz4's error for a damaged frame
        raise _Damaged(f"lz4: {exc}") from exc


def _decompress(data: bytes, compression: str, size: int) -> bytes:
    """The records of a chunk, ``size`` bytes declared."""
    if compression == "":
        out = data
    elif compression == "zstd":
        out = _unzstd(data, size)
    elif compression == "lz4":
        out = _unlz4(data, size)
    else:  # the mcap package would take such a chunk as uncompressed: garbage, or none
        raise _Damaged(f"its compression {compression!r} is none of MCAP's ('', zstd, lz4)")
    if len(out) != size:
        got = "more than" if len(out) > size else f"{len(out)} bytes, not"
        raise _Damaged(f"its records hold {got} the {size} bytes its header declares")
    return out


def _chunk_records(raw: bytes) -> bytes:
    """The (decompressed) records of a Chunk record, checked against its sizes and CRC."""
    op, _length = _RECORD.unpack_from(raw, 0)
    if op != OP_CHUNK:
        raise _Damaged(f"the summary's chunk index points at a record of opcode {op:#x}")
    _start, _end, size, crc = _CHUNK.unpack_from(raw, 9)
    pos = 9 + _CHUNK.size
    (n_comp,) = struct.unpack_from("<I", raw, pos)
    compression = _text(raw[pos + 4 : pos + 4 + n_comp], "its compression's name")
    pos += 4 + n_comp
    (n_rec,) = struct.unpack_from("<Q", raw, pos)
    data = raw[pos + 8 : pos + 8 + n_rec]
    if len(data) != n_rec:
        raise _Damaged(f"it is cut short: {len(data)} of its {n_rec} bytes of records")
    records = _decompress(data, compression, size)
    if crc and zlib.crc32(records) != crc:  # crc 0: not computed
        raise _Damaged("its records do not match their CRC")
    return records


def _text(data: bytes, what: str) -> str:
    """``data`` as UTF-8 text; `_Damaged` naming ``what`` where it is not."""
    try:
        return data.decode()
    except UnicodeDecodeError as exc:
        raise _Damaged(f"{what} is not UTF-8 text") from exc


def _walk(records: bytes, wanted: dict[int, tuple[str, int]], out: RawTopics) -> None:
    """Append the Message records of the wanted channels (id -> (topic, the index of its
    schema in ``out.definitions[topic]``))."""
    pos, end = 0, len(records)
    full, head = _RECORD_MESSAGE.unpack_from, _RECORD.unpack_from
    logs = {channel: out.log_ns[topic] for channel, (topic, _) in wanted.items()}
    datas = {channel: out.data[topic] for channel, (topic, _) in wanted.items()}
    marks = {channel: partial(out.schema_index[topic].append, i)
             for channel, (topic, i) in wanted.items()}  # fmt: skip
    last = end - _RECORD_MESSAGE.size  # from here on a record may end before a message's fields
    while pos <= last:  # one unpack a record: its opcode and length, a message's fields
        op, length, channel, _seq, log = full(records, pos)
        if op == OP_MESSAGE:
            if length < _MESSAGE_DATA - 9:
                raise _Damaged(f"a message record at byte {pos} of its records is too short")
            times = logs.get(channel)
            if times is not None:
                times.append(log)
                datas[channel].append(records[pos + _MESSAGE_DATA : pos + 9 + length])
                marks[channel]()
        pos += 9 + length
    # the records left start within a message's fields of the end: none is a whole message (a
    # message record holds >= _MESSAGE_DATA bytes), so one of opcode Message is damaged
    while pos < end:
        op, length = head(records, pos)
        if op == OP_MESSAGE and length < _MESSAGE_DATA - 9:
            raise _Damaged(f"a message record at byte {pos} of its records is too short")
        pos += 9 + length
    if pos != end:
        raise _Damaged("its last record runs past its end")


def mcap_messages(
    paths: Sequence[Path],
    topics: Sequence[str],
    metadata: Sequence[str] = (),
    limit: int = 0,
) -> RawTopics | None:
    """The messages of ``topics`` in MCAP files (None where a file is not the simple case),
    and the Metadata records named in ``metadata`` (`indexed_metadata`, at most ``limit`` bytes
    each). Raises `BagError` for a file whose chunks, chunk index, schemas or those records
    are damaged."""
    out = RawTopics(metadata={name: [] for name in metadata})
    for topic in topics:
        out.log_ns[topic], out.data[topic], out.schema_index[topic] = [], [], []
    for path in paths:
        with open(path, "rb") as f:
            try:
                summary = _mcap_file(f, out)
            except _Damaged as exc:
                raise BagError(f"{path} is damaged: {exc}") from exc
            if summary is None:
                return None
            for name, found in indexed_metadata(path, f, summary, metadata, limit).items():
                out.metadata[name].extend(found)
    return out


def indexed_metadata(
    path: Path, f, summary, names: Sequence[str], limit: int
) -> dict[str, list[dict[str, str]]]:
    """{name: the metadata of each Metadata record of that name} of the open MCAP file ``f``
    (``path``), found through its ``summary``'s metadata index; `BagError` for a record over
    ``limit`` bytes, one that does not read or an index that points at another record."""
    out: dict[str, list[dict[str, str]]] = {name: [] for name in names}
    for index in summary.metadata_indexes:
        if index.name not in out:
            continue
        where = f"{path} is damaged: its {index.name!r} metadata record"
        if index.length > limit:
            raise BagError(f"{where} is {index.length} bytes long, more than {limit} allowed")
        stream = require("mcap.stream_reader", "reading an MCAP file")
        try:
            f.seek(index.offset)
            record = next(stream.StreamReader(f, skip_magic=True, record_size_limit=limit).records)
        except Exception as exc:  # the mcap package raises its own errors for damaged files
            why = " ".join(str(exc).split())
            raise BagError(f"{where} cannot be read ({type(exc).__name__}: {why})") from exc
        if type(record).__name__ != "Metadata" or record.name != index.name:
            raise BagError(f"{where}: the summary's index points at another record")
        out[index.name].append(dict(record.metadata))
    return out


def writer_library(head: bytes) -> str | None:
    """The ``library`` field of the Header record that follows MCAP's magic bytes in ``head``
    (the first bytes of a file): the program that wrote the file; None where ``head`` ends
    before it or holds no Header record there."""
    pos = len(MAGIC) + _RECORD.size
    if len(head) < pos or head[len(MAGIC)] != 0x01:  # opcode of a Header record
        return None
    try:
        (n_profile,) = struct.unpack_from("<I", head, pos)
        (n_library,) = struct.unpack_from("<I", head, pos + 4 + n_profile)
    except struct.error:
        return None
    start = pos + 8 + n_profile
    if len(head) < start + n_library:
        return None
    return head[start : start + n_library].decode(errors="replace")


def check_mcap_target(path: Path, name: str) -> None:
    """ControlError naming ``name`` when a recording written to ``path`` would destroy something
    that is not an earlier recording of `control.record_run`: a folder, something other than a
    plain file, a non-empty file that does not start with MCAP's magic bytes (someone's data,
    an emulator file), or an MCAP file written by another program (whose Header record does
    not name `LIBRARY` as its writer: a robot's recording, a bag's file, Foxglove's; one of
    at least `MIN_MCAP_BYTES` whose header cannot be read too). An earlier recording of
    `control.record_run`, an empty file, a stub shorter than any MCAP file or a new path may
    be written; a path the OS cannot look up (`check_lookup`: a name too long, say) may not."""
    check_lookup(path, name)
    if not path.exists():
        return
    if path.is_dir():
        raise ControlError(f"{name}={str(path)!r} is a folder; name the .mcap file to write")

    def refused(what: str) -> ControlError:
        return ControlError(
            f"{name}={str(path)!r} holds {what}; a recording replaces only an earlier MCAP "
            "file of record_run: remove it or choose another path"
        )

    if not path.is_file():
        raise refused("something other than a plain file")
    try:
        with path.open("rb") as f:
            head = f.read(_HEADER_BYTES)
            size = os.fstat(f.fileno()).st_size
    except OSError as exc:
        raise ControlError(f"{name}={str(path)!r} cannot be read to check it: {exc}") from None
    if head and head[: len(MAGIC)] != MAGIC:
        raise refused("a file that is not an MCAP recording")
    library = writer_library(head)
    if library is None and size >= MIN_MCAP_BYTES:
        raise refused("an MCAP file whose header does not say which program wrote it")
    if library is not None and library != LIBRARY:
        raise refused(f"an MCAP recording written by {library!r}, not by record_run")


def truncation(f) -> str:
    """Why the open MCAP file ``f`` is cut short ("is truncated: ...", to follow its name), or
    "" where it opens and ends with MCAP's magic bytes and is no shorter than `MIN_MCAP_BYTES`;
    "is not an MCAP file ..." where its first bytes are not MCAP's magic."""
    size = os.fstat(f.fileno()).st_size
    f.seek(0)
    head = f.read(len(MAGIC))
    if head != MAGIC[: len(head)]:
        return "is not an MCAP file: it does not start with MCAP's magic bytes"
    if size < MIN_MCAP_BYTES:
        return (
            f"is truncated: {size} bytes, shorter than an MCAP file's magic bytes, header and "
            f"footer ({MIN_MCAP_BYTES} bytes at least)"
        )
    f.seek(size - len(MAGIC))
    if f.read(len(MAGIC)) != MAGIC:
        return (
            f"is truncated: its {size} bytes do not end with MCAP's magic bytes (a file cut "
            "short, e.g. an interrupted recording, or damaged at its end)"
        )
    return ""


def note_type(types: dict[str, str | None], topic: str, msgtype: str) -> None:
    """Record that ``topic`` holds ``msgtype``: None once it holds several types."""
    if types.setdefault(topic, msgtype) != msgtype:
        types[topic] = None


def note_encoding(encodings: dict[str, str], topic: str, encoding: str) -> None:
    """Record that a channel of ``topic`` holds messages of ``encoding``: the first other than
    "cdr" once its channels differ (the replay reads cdr only and names it)."""
    if encodings.setdefault(topic, encoding) == "cdr":
        encodings[topic] = encoding


def _mcap_file(f, out: RawTopics):
    """Append the messages of ``out``'s topics in one MCAP file; its summary, None where it
    is not the simple case."""
    reader_mod = require("mcap.reader", "reading an MCAP file")
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
        note_type(out.types, channel.topic, name)
        if channel.topic in out.log_ns:
            note_encoding(out.encodings, channel.topic, channel.message_encoding)
            definition = ("", "")
            if schema is not None:
                text = _text(schema.data, f"the schema of {channel.topic!r}")
                definition = (schema.encoding, text)
            known = out.definitions.setdefault(channel.topic, [])
            if definition not in known:
                known.append(definition)
            wanted[cid] = (channel.topic, known.index(definition))
    before = {t: len(v) for t, v in out.log_ns.items()}
    size = os.fstat(f.fileno()).st_size
    for index in sorted(summary.chunk_indexes, key=lambda c: c.chunk_start_offset):
        if not set(index.message_index_offsets) & set(wanted):
            continue
        start = index.chunk_start_offset
        try:
            if start + index.chunk_length > size:
                raise _Damaged(f"its {index.chunk_length} bytes run past the file's {size}")
            f.seek(start)
            _walk(_chunk_records(f.read(index.chunk_length)), wanted, out)
        except struct.error as exc:
            raise _Damaged(f"the chunk at byte {start}: a record is cut short ({exc})") from exc
        except _Damaged as exc:
            raise _Damaged(f"the chunk at byte {start}: {exc}") from exc
    counts = summary.statistics.channel_message_counts
    for topic in before:
        channels = [cid for cid, (t, _) in wanted.items() if t == topic]
        found = len(out.log_ns[topic]) - before[topic]
        if all(c in counts for c in channels) and sum(counts[c] for c in channels) != found:
            return None  # messages outside chunks
    return summary


def write_chunk_crcs(path: Path) -> None:
    """Write into each chunk of an MCAP file whose CRC field is 0 ("not computed"; rosbags'
    writer leaves it so) the CRC32 of its (decompressed) records, in place, so that this module,
    rosbags and the mcap package (``validate_crcs``) refuse a chunk whose bytes changed.
    `BagError` for a file that is not an MCAP file, whose chunks are damaged or one of whose
    records runs past its end."""
    with open(path, "r+b") as f:
        if f.read(len(MAGIC)) != MAGIC:
            raise BagError(f"{path} is not an MCAP file (no magic bytes)")
        pos, size = len(MAGIC), os.fstat(f.fileno()).st_size
        while len(head := f.read(_RECORD.size)) == _RECORD.size:
            op, length = _RECORD.unpack(head)
            if op == OP_DATA_END:
                break
            if pos + _RECORD.size + length > size:  # a damaged length, or a file cut short
                raise BagError(
                    f"{path} is damaged: the record at byte {pos} runs past the file's end "
                    f"({length} bytes declared, {size - pos - _RECORD.size} left)"
                )
            if op == OP_CHUNK:
                raw = head + f.read(length)
                try:
                    records = _chunk_records(raw)
                except (_Damaged, struct.error) as exc:
                    raise BagError(f"{path} is damaged: the chunk at byte {pos}: {exc}") from exc
                if _CHUNK.unpack_from(raw, 9)[3] == 0:
                    f.seek(pos + 9 + _CHUNK.size - 4)
                    f.write(struct.pack("<I", zlib.crc32(records)))
            pos += 9 + length
            f.seek(pos)


def sqlite_messages(paths: Sequence[Path], topics: Sequence[str]) -> RawTopics:
    """The messages of ``topics`` in rosbag2 sqlite3 files, by receive time, and their message
    definitions where a file holds them (`_sqlite_definitions`). Raises `BagError`
    for a file sqlite3 cannot read, a truncated one, or one whose topics or definitions are not
    UTF-8 text (or NULL) or whose messages are not (int, bytes)."""
    out = RawTopics()
    for topic in topics:
        out.log_ns[topic], out.data[topic] = [], []
    for path in paths:
        try:
            _sqlite_file(Path(path), out)
        except sqlite3.Error as exc:
            raise BagError(f"{path} is not a readable rosbag2 sqlite3 file: {exc}") from exc
    return out


def _sqlite_file(path: Path, out: RawTopics) -> None:
    """Append the messages of ``out``'s topics in one rosbag2 sqlite3 file."""
    # as_uri: a '#', '?' or '%' in the path is percent-encoded, not read as the URI's parts
    con = sqlite3.connect(f"{path.resolve().as_uri()}?mode=ro", uri=True)
    # sqlite3's own decoding turns TEXT that is not UTF-8 into an OperationalError ("Could not
    # decode ...", as if the file could not be read): decoded here, it raises UnicodeDecodeError,
    # named by the query that met it (`_fetch`)
    con.text_factory = _utf8
    try:
        _check_complete(con, path)
        rows = _fetch(
            con, path, "SELECT id, name, type, serialization_format FROM topics", (),
            "a topic's name, type or serialisation format is not UTF-8 text",
        )  # fmt: skip
        ids = {}
        for tid, name, msgtype, encoding in rows:
            if not all(type(v) is str for v in (name, msgtype, encoding)):
                raise BagError(
                    f"{path} is damaged: the topic of id {tid!r} lacks its name, type or "
                    "serialisation format"
                )
            note_type(out.types, name, msgtype)
            if name in out.log_ns:
                ids[tid] = name
                out.encodings[name] = encoding
        _sqlite_definitions(con, path, {name: out.types[name] for name in ids.values()}, out)
        for tid, name in ids.items():
            lacks = f"a message of the topic {name!r} lacks an integer time stamp or its data"
            rows = _fetch(
                con, path,
                "SELECT timestamp, data FROM messages WHERE topic_id = ? ORDER BY timestamp, id",
                (tid,), lacks,  # TEXT there, UTF-8 or not, is neither
            )  # fmt: skip
            stamps, data = zip(*rows, strict=True) if rows else ((), ())
            if set(map(type, stamps)) - {int} or set(map(type, data)) - {bytes}:
                raise BagError(f"{path} is damaged: {lacks}")
            out.log_ns[name].extend(stamps)
            out.data[name].extend(data)
    finally:
        con.close()


def _utf8(data: bytes) -> str:
    """A TEXT value of a sqlite3 file as text; UnicodeDecodeError where it is not UTF-8."""
    return data.decode()


def _fetch(con: sqlite3.Connection, path: Path, query: str, args: tuple, why: str) -> list:
    """The rows of ``query``; `BagError` "``path`` is damaged: ``why``" where a TEXT value
    among them is not UTF-8 (`_utf8`)."""
    try:
        return con.execute(query, args).fetchall()
    except UnicodeDecodeError as exc:
        raise BagError(f"{path} is damaged: {why}") from exc


def _sqlite_definitions(
    con: sqlite3.Connection, path: Path, types: dict[str, str | None], out: RawTopics
) -> None:
    """Record the definitions of the topics ``types`` (topic -> message type) that a bag of
    rosbag2's schema 4 on (Iron) holds in its message_definitions table, the first of a type
    (as rosbags reads them); a bag without that table has none."""
    tables = "SELECT 1 FROM sqlite_master WHERE type = 'table' AND name = 'message_definitions'"
    if con.execute(tables).fetchone() is None:
        return
    rows = _fetch(
        con, path,
        "SELECT topic_type, encoding, CAST(encoded_message_definition AS BLOB) "
        "FROM message_definitions ORDER BY id", (),
        "a message definition's type or encoding is not UTF-8 text",
    )  # fmt: skip
    found: dict[str, tuple[str, bytes]] = {}
    for msgtype, encoding, text in rows:
        if type(msgtype) is not str or type(encoding) is not str or type(text) is not bytes:
            raise BagError(
                f"{path} is damaged: a message definition lacks its type, encoding or text"
            )
        found.setdefault(msgtype, (encoding, text))
    for topic, msgtype in types.items():
        if msgtype in found and topic not in out.definitions:
            encoding, text = found[msgtype]
            try:
                out.definitions[topic] = [(encoding, text.decode())]
            except UnicodeDecodeError as exc:
                raise BagError(
                    f"{path} is damaged: the message definition of the topic {topic!r} is not "
                    "UTF-8 text"
                ) from exc


def _check_complete(con: sqlite3.Connection, path: Path) -> None:
    """`BagError` for a database file shorter than its header says (sqlite3 reads the missing
    part of its last page as zeros: a truncated bag would lose the end of its last messages
    unnoticed), or one whose size is not a whole number of pages (bytes appended). A file with
    a write-ahead log beside it is not checked (the log holds pages the file lacks)."""
    if Path(f"{path}-wal").exists():
        return
    ((page,),) = con.execute("PRAGMA page_size").fetchall()
    ((pages,),) = con.execute("PRAGMA page_count").fetchall()
    size = path.stat().st_size
    if size < page * pages:
        raise BagError(
            f"{path} is truncated: {size} bytes, its header declares {pages} pages of {page}"
        )
    if size % page:
        raise BagError(
            f"{path} is damaged: {size} bytes, not a whole number of its {page}-byte pages "
            f"({pages} declared)"
        )
