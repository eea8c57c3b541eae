"""Exact tests of `control.robot.storage` from the mutation testing of its odd half of sites
(session 92): the limit of a message record's length among a chunk's last bytes (fewer than a
message's fields left), at its value and one byte below. Records are built by hand."""

import struct

import pytest

from control.robot import storage as st


def _record(op: int, body: bytes) -> bytes:
    """An MCAP record: opcode, little-endian length, body."""
    return bytes([op]) + struct.pack("<Q", len(body)) + body


def _out(*topics: str) -> st.RawTopics:
    out = st.RawTopics()
    for topic in topics:
        out.log_ns[topic], out.data[topic], out.schema_index[topic] = [], [], []
    return out


def _walk_damage(records: bytes) -> str:
    with pytest.raises(st._Damaged) as info:
        st._walk(records, {1: ("/a", 0)}, _out("/a"))
    return str(info.value)


def test_a_message_header_among_the_last_22_bytes_with_21_bytes_of_fields_is_too_short():
    # fewer than 23 bytes (opcode, length and a message's first fields) left: only the
    # trailing loop reads the record's opcode and length; 21 < 22 bytes of fields is named so
    # although the record also runs past the end
    assert st._RECORD_MESSAGE.size == 23
    cut = _record(0x05, bytes(21))[:22]
    assert _walk_damage(cut) == "a message record at byte 0 of its records is too short"
    assert _walk_damage(cut[:9]) == "a message record at byte 0 of its records is too short"
    first = _record(0x07, bytes(30))  # 39 bytes of another record before it
    assert _walk_damage(first + cut) == "a message record at byte 39 of its records is too short"


def test_a_message_header_among_the_last_22_bytes_with_22_bytes_of_fields_runs_past_the_end():
    # 22 bytes of fields (an empty message) is long enough: cut short, the record is named as
    # running past the records' end, not as too short
    shortest = _record(0x05, struct.pack("<HIQQ", 1, 0, 9, 9))
    assert len(shortest) == st._MESSAGE_DATA == 31
    assert _walk_damage(shortest[:22]) == "its last record runs past its end"
    assert _walk_damage(shortest[:9]) == "its last record runs past its end"
    first = _record(0x07, bytes(30))
    assert _walk_damage(first + shortest[:22]) == "its last record runs past its end"
