"""Mutation testing of gpmsa.io.container (session 93, the sites session 89 left): each test
pins a check of the file container that a single-site mutant of it survived, with an exact
expectation (limits at their edges, hostile bytes refused by name, handles closed)."""

from __future__ import annotations

import io
import json
import os
import stat
import struct
import zipfile
from pathlib import Path

import numpy as np
import pytest
from test_container_mutants_s89 import CONTENT, _npy

from gpmsa import limits
from gpmsa.errors import EmulatorFileError, GPMSAError
from gpmsa.io import container
from gpmsa.io.container import _check_directory, _check_members, jsonable, read_raw, seal


def _end_record(entries: int, cd_size: int) -> bytes:
    return b"PK\x05\x06" + struct.pack("<HHHHIIH", 0, 0, entries, entries, cd_size, 0, 0)


def test_numpy_scalars_become_python_values():
    out = jsonable({"a": np.float32(2.5), "b": [np.int64(3), np.float32("nan"), np.bool_(True)]})
    assert out == {"a": 2.5, "b": [3, None, True]}
    assert [type(v) for v in (out["a"], *out["b"])] == [float, int, type(None), bool]


def test_a_directory_of_exactly_1024_bytes_per_member_passes_one_more_is_refused():
    _check_directory(io.BytesIO(_end_record(2, 2048)), 22, "f")  # no exception
    with pytest.raises(EmulatorFileError, match="f: zip directory of 2049 bytes for 2 members"):
        _check_directory(io.BytesIO(_end_record(2, 2049)), 22, "f")


def test_the_member_count_is_checked_again_on_the_parsed_directory(monkeypatch):
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        for name in ("manifest.json", "arrays/a.npy", "arrays/b.npy"):
            zf.writestr(name, b"{}")
    monkeypatch.setattr(limits, "MAX_MEMBERS", 2)
    with (
        zipfile.ZipFile(buf) as zf,
        pytest.raises(EmulatorFileError, match=r"f: 3 members \(limit 2\)"),
    ):
        _check_members(zf, "f")


def test_an_npy_header_of_a_refused_dtype_is_named_before_the_manifest_comparison(tmp_path):
    sealed, _ = seal(dict(CONTENT), {"a": np.zeros(2)})
    members = {"manifest.json": json.dumps(sealed).encode(),
               "arrays/a.npy": _npy(np.zeros(2, dtype="<f4"))}  # fmt: skip
    path = tmp_path / "f.gpmsa"
    with zipfile.ZipFile(path, "w") as zf:
        for name, data in members.items():
            zf.writestr(name, data)
    with pytest.raises(
        EmulatorFileError, match=r"array 'a' has dtype <f4 \(allowed \['<f8', '<i8', '\|b1'\]\)"
    ):
        read_raw(path)


def test_a_file_replaced_between_the_stat_and_the_open_is_refused_and_closed(tmp_path, monkeypatch):
    path = container.write_raw(tmp_path / "f.gpmsa", dict(CONTENT), {})
    opened = []
    real_fdopen, real_fstat = os.fdopen, os.fstat

    def fdopen(fd, *args, **kwargs):
        opened.append(real_fdopen(fd, *args, **kwargs))
        return opened[-1]

    def fstat(fd):
        st = list(real_fstat(fd))
        st[stat.ST_MODE] = stat.S_IFIFO | 0o644
        return os.stat_result(st)

    monkeypatch.setattr(container.os, "fdopen", fdopen)
    monkeypatch.setattr(container.os, "fstat", fstat)
    with pytest.raises(
        EmulatorFileError, match="not a regular file: gpmsa reads emulator files only"
    ):
        container._open_regular(Path(path))
    assert len(opened) == 1 and opened[0].closed


@pytest.mark.parametrize(
    ("names", "layout"),
    [(("manifest.json", "arrays/a.npy"), True), (("manifest.json", "notes.txt"), False),
     (("manifest.json", "arrays/notes.txt"), False), (("manifest.json", "a.npy"), False),
     (("arrays/a.npy",), False)],
)  # fmt: skip
def test_a_gpmsa_layout_needs_the_manifest_and_array_members_only(tmp_path, names, layout):
    path = tmp_path / "z.zip"
    with zipfile.ZipFile(path, "w") as zf:
        for name in names:
            zf.writestr(name, b"x")
    assert container._gpmsa_layout(path) is layout


def test_a_duplicate_member_is_refused_by_name(tmp_path):
    path = container.write_raw(tmp_path / "f.gpmsa", dict(CONTENT), {"a": np.ones(2)})
    with zipfile.ZipFile(path, "a") as zf, pytest.warns(UserWarning, match="Duplicate name"):
        zf.writestr("arrays/a.npy", _npy(np.zeros(2)))
    with pytest.raises(EmulatorFileError, match="duplicate member 'arrays/a.npy'"):
        read_raw(path)


def test_a_stored_member_with_unequal_sizes_is_refused(tmp_path):
    path = tmp_path / "s.gpmsa"
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_STORED) as zf:
        zf.writestr("manifest.json", b"{}")
    data = bytearray(path.read_bytes())
    at = data.index(b"PK\x01\x02") + 20  # the central header's compressed size
    data[at : at + 4] = struct.pack("<I", 3)
    path.write_bytes(bytes(data))
    with pytest.raises(EmulatorFileError, match="stored member 'manifest.json' has unequal sizes"):
        read_raw(path)


def test_a_classic_end_record_with_a_zip64_member_count_is_refused():
    with pytest.raises(EmulatorFileError, match="f: damaged zip64 end record"):
        _check_directory(io.BytesIO(_end_record(0xFFFF, 0)), 22, "f")


@pytest.mark.parametrize(("dtype", "shown"), [(5, "5"), ("<f8" * 8, repr("<f8" * 8))])
def test_a_manifest_dtype_that_is_no_short_str_is_shown_as_its_repr(tmp_path, dtype, shown):
    sealed, _ = seal(dict(CONTENT), {"a": np.zeros(2)})
    sealed["arrays"]["a"]["dtype"] = dtype
    path = tmp_path / "f.gpmsa"
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr("manifest.json", json.dumps(sealed))
        zf.writestr("arrays/a.npy", _npy(np.zeros(2)))
    with pytest.raises(EmulatorFileError) as info:
        read_raw(path)
    assert f"array 'a' has dtype {shown} (allowed" in str(info.value)


@pytest.mark.parametrize("shape", [[-1], [2.0]])
def test_a_manifest_shape_of_a_negative_or_float_length_is_malformed(tmp_path, shape):
    sealed, _ = seal(dict(CONTENT), {"a": np.zeros(2)})
    sealed["arrays"]["a"]["shape"] = shape
    path = tmp_path / "f.gpmsa"
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr("manifest.json", json.dumps(sealed))
        zf.writestr("arrays/a.npy", _npy(np.zeros(2)))
    with pytest.raises(EmulatorFileError, match="manifest entry of array 'a' is malformed"):
        read_raw(path)


def test_the_writer_counts_65552_header_bytes_per_array(monkeypatch):
    arrays = {"a": np.zeros(2), "b": np.zeros(3)}  # 16 and 24 bytes of data
    monkeypatch.setattr(limits, "MAX_ARRAY_BYTES", 40 + 2 * 65552)
    container.check_writable(dict(CONTENT), arrays)  # exactly at the limit
    monkeypatch.setattr(limits, "MAX_ARRAY_BYTES", 40 + 2 * 65552 - 1)
    with pytest.raises(GPMSAError, match="the arrays take 131144 bytes"):
        container.check_writable(dict(CONTENT), arrays)


class _Member:
    """A zip whose member ``open`` gives ``data`` (a short or long read of the member)."""

    def __init__(self, data: bytes):
        self.data = data

    def open(self, info):
        return io.BytesIO(self.data)


@pytest.mark.parametrize("data", [b"ab", b"abcd"])
def test_a_member_read_shorter_or_longer_than_declared_is_refused(data):
    info = zipfile.ZipInfo("arrays/a.npy")
    info.file_size = 3
    with pytest.raises(
        EmulatorFileError, match="f: member 'arrays/a.npy' size differs from its zip header"
    ):
        container._read_member(_Member(data), info, "f")


def _deep(depth: int) -> dict:
    value: dict = {}
    for _ in range(depth - 1):
        value = {"a": value}
    return value


def test_a_manifest_nested_72_levels_passes_the_depth_check_73_do_not():
    with pytest.raises(EmulatorFileError, match="f: format is None, expected"):
        container._parse_manifest(json.dumps(_deep(72)).encode(), "f")
    with pytest.raises(EmulatorFileError, match="f: manifest.json nests deeper than 72 levels"):
        container._parse_manifest(json.dumps(_deep(73)).encode(), "f")


def test_a_manifest_without_a_schema_field_is_refused_by_name():
    sealed, _ = seal(dict(CONTENT), {})
    del sealed["units"]
    with pytest.raises(EmulatorFileError, match="f: manifest field 'units' missing or not a dict"):
        container._parse_manifest(json.dumps(sealed).encode(), "f")


def test_a_member_of_another_compression_method_is_refused(tmp_path):
    path = tmp_path / "b.gpmsa"
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_BZIP2) as zf:
        zf.writestr("manifest.json", b"{}")
    with pytest.raises(
        EmulatorFileError, match=r"member 'manifest.json' uses compression method 12 \(only"
    ):
        read_raw(path)


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="no FIFOs")
def test_a_fifo_that_stat_saw_as_a_file_is_opened_without_blocking_and_refused(
    tmp_path, monkeypatch
):
    fifo = tmp_path / "p.gpmsa"
    os.mkfifo(fifo)
    regular = os.stat(container.write_raw(tmp_path / "f.gpmsa", dict(CONTENT), {}))
    real_stat = os.stat
    monkeypatch.setattr(
        container.os,
        "stat",
        lambda p, *a, **k: regular if str(p) == str(fifo) else real_stat(p, *a, **k),
    )
    with pytest.raises(
        EmulatorFileError, match="not a regular file: gpmsa reads emulator files only"
    ):
        container._open_regular(fifo)  # without O_NONBLOCK the open would wait for a writer


def test_an_end_record_beyond_the_longest_comment_is_not_found():
    data = _end_record(0, 0) + bytes(65536)  # 65536 bytes after it: longer than any comment
    with pytest.raises(
        EmulatorFileError, match=r"f: not a gpmsa emulator file \(not a readable zip: no end"
    ):
        _check_directory(io.BytesIO(data), len(data), "f")


def test_an_end_record_followed_by_the_longest_comment_is_found():
    # 65535 bytes after it (the longest comment a zip may have): the tail read, 22 + 65535
    # bytes, still starts at its signature, so the record is found (and then refused, its
    # comment length being 0: appended bytes), not "no end record" as one byte further
    data = _end_record(0, 0) + bytes(65535)
    with pytest.raises(EmulatorFileError, match=r"^f: damaged zip: 65535 bytes follow the end "):
        _check_directory(io.BytesIO(data), len(data), "f")


def test_an_empty_directory_may_take_1024_bytes():
    _check_directory(io.BytesIO(_end_record(0, 1024)), 22, "f")  # no exception
    with pytest.raises(EmulatorFileError, match="f: zip directory of 1025 bytes for 0 members"):
        _check_directory(io.BytesIO(_end_record(0, 1025)), 22, "f")


def test_the_zip64_record_before_its_locator_gives_the_member_count():
    rec = b"PK\x06\x06" + bytes(28) + struct.pack("<QQ", 10**6, 0) + bytes(8)  # 56 bytes
    data = rec + b"PK\x06\x07" + bytes(16) + _end_record(0xFFFF, 0xFFFFFFFF)
    with pytest.raises(
        EmulatorFileError, match=r"f: 1000000 members \(limit gpmsa.limits.MAX_MEMBERS"
    ):
        _check_directory(io.BytesIO(data), len(data), "f")


@pytest.mark.parametrize(
    ("extra", "message"), [(10, "bad .npy header"), (9, "its member holds 25 bytes")]
)
def test_an_array_member_of_ten_bytes_beyond_its_data_reaches_the_header_check(
    tmp_path, extra, message
):
    sealed, _ = seal(dict(CONTENT), {"a": np.zeros(2)})
    path = tmp_path / "f.gpmsa"
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr("manifest.json", json.dumps(sealed))
        zf.writestr("arrays/a.npy", b"\x93NUMPY\x01\x00\x00\x00"[:extra] + bytes(16))
    with pytest.raises(EmulatorFileError, match=f"array 'a'.*{message}"):
        read_raw(path)


def test_an_arrays_member_not_ending_in_npy_is_refused(tmp_path):
    path = tmp_path / "t.gpmsa"
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr("manifest.json", b"{}")
        zf.writestr("arrays/ab.txt", b"x")
    with pytest.raises(EmulatorFileError, match="unexpected member 'arrays/ab.txt'"):
        read_raw(path)


def test_members_are_dated_1980_01_01_midnight(tmp_path):
    path = container.write_raw(tmp_path / "f.gpmsa", dict(CONTENT), {"a": np.ones(2)})
    with zipfile.ZipFile(path) as zf:
        assert [i.date_time for i in zf.infolist()] == [(1980, 1, 1, 0, 0, 0)] * 2


def test_the_repeated_key_is_the_one_named():
    with pytest.raises(EmulatorFileError, match="key 'b' appears twice in one object"):
        container._parse_manifest(b'{"a": 1, "b": 2, "b": 3}', "f")


def test_the_content_hash_does_not_depend_on_the_manifests_key_order():
    arrays = {"a": np.ones(2)}
    assert container.content_hash(
        arrays, {"b": 1, "a": {"d": 2, "c": 3}}
    ) == container.content_hash(arrays, {"a": {"c": 3, "d": 2}, "b": 1})
