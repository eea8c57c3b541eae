"""Mutation testing of gpmsa.io.container (session 89): each test pins a check of the file
container that a single-site mutant of it survived, with an exact expectation (limits at their
edges, hostile members the reader must refuse by name, the writer's compression choice)."""

from __future__ import annotations

import hashlib
import io
import json
import os
import pwd
import struct
import zipfile
from pathlib import Path

import numpy as np
import pytest

from gpmsa import limits
from gpmsa.errors import EmulatorFileError, GPMSAError
from gpmsa.io import container
from gpmsa.io.container import (
    STUDY_FORMAT,
    _deflated_size,
    _short,
    check_expected_sha256,
    check_writable,
    home_path,
    read_manifest,
    read_raw,
    refuse_to_replace,
    seal,
    write_raw,
    write_sealed,
)

CONTENT = {"names": {}, "units": {}, "priors": {}, "settings": {}, "metadata": {},
           "diagnostics": {}}  # fmt: skip


def _npy(arr: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.save(buf, arr, allow_pickle=False)
    return buf.getvalue()


def _zip(path: Path, members: dict[str, bytes]) -> Path:
    """A zip of exactly these members (deflated), as a hostile writer makes one."""
    with zipfile.ZipFile(path, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for name, data in members.items():
            zf.writestr(name, data)
    return path


def _hostile(path: Path, manifest: dict, members: dict[str, bytes], arrays) -> Path:
    """A file whose manifest lists ``arrays`` (as loaded) with their hash recomputed, and whose
    array members are ``members`` (the bytes a hostile writer chose)."""
    sealed, _ = seal(dict(CONTENT, **manifest), arrays)
    raw = json.dumps(sealed).encode()
    return _zip(path, {"manifest.json": raw, **{f"arrays/{k}.npy": v for k, v in members.items()}})


# --- the writer's limits at their edges -----------------------------------------------------
def test_an_array_of_the_most_dimensions_is_written_and_read_one_more_is_refused(tmp_path):
    eight = np.arange(2.0**8).reshape((2,) * 8)
    _, arrays = read_raw(write_raw(tmp_path / "d.gpmsa", dict(CONTENT), {"a": eight}))
    np.testing.assert_array_equal(arrays["a"], eight)
    with pytest.raises(GPMSAError, match=r"has 9 dimensions \(limit 8\)"):
        check_writable(dict(CONTENT), {"a": eight[..., None]})


def test_arrays_exactly_at_the_array_byte_limit_are_writable(monkeypatch):
    arrays = {"a": np.zeros(5), "b": np.ones(3)}
    total = 8 * 8 + 2 * container.NPY_HEADER_MAX  # the writer counts a header's longest
    monkeypatch.setattr(limits, "MAX_ARRAY_BYTES", total)
    check_writable(dict(CONTENT), arrays)
    monkeypatch.setattr(limits, "MAX_ARRAY_BYTES", total - 1)
    with pytest.raises(GPMSAError, match=f"the arrays take {total} bytes"):
        check_writable(dict(CONTENT), arrays)


def test_a_manifest_exactly_at_the_manifest_byte_limit_is_writable(monkeypatch):
    manifest = dict(CONTENT, metadata={"note": "x" * 50})
    size = len(json.dumps(manifest, indent=1, sort_keys=True).encode())
    monkeypatch.setattr(limits, "MAX_MANIFEST_BYTES", size)
    assert len(check_writable(manifest, {})) == size
    monkeypatch.setattr(limits, "MAX_MANIFEST_BYTES", size - 1)
    with pytest.raises(GPMSAError, match=f"the manifest takes {size} bytes"):
        check_writable(manifest, {})


def test_a_file_exactly_at_the_file_byte_limit_is_written(tmp_path, monkeypatch):
    arrays = {"x": np.arange(7.0)}
    _, raw = seal(dict(CONTENT), arrays)
    size = write_sealed(tmp_path / "a.gpmsa", raw, arrays).stat().st_size  # no time in the zip
    monkeypatch.setattr(limits, "MAX_FILE_BYTES", size)
    assert write_sealed(tmp_path / "b.gpmsa", raw, arrays).stat().st_size == size
    monkeypatch.setattr(limits, "MAX_FILE_BYTES", size - 1)
    with pytest.raises(GPMSAError, match=f"would take {size} bytes"):
        write_sealed(tmp_path / "c.gpmsa", raw, arrays)
    assert not (tmp_path / "c.gpmsa").exists()


def test_the_deflated_size_is_the_size_zipfile_deflates_to(tmp_path):
    data = _npy(np.arange(20000.0) % 7)  # compresses, but not as a zip bomb does
    with zipfile.ZipFile(tmp_path / "z.zip", "w", compression=zipfile.ZIP_DEFLATED) as zf:
        zf.writestr("d", data)
    with zipfile.ZipFile(tmp_path / "z.zip") as zf:
        assert _deflated_size(data) == zf.getinfo("d").compress_size


def test_members_are_deflated_and_one_beyond_the_ratio_is_stored(tmp_path):
    path = write_raw(tmp_path / "c.gpmsa", dict(CONTENT),
                     {"zeros": np.zeros(200_000), "ramp": np.arange(2000.0)})  # fmt: skip
    with zipfile.ZipFile(path) as zf:
        kinds = {i.filename: i.compress_type for i in zf.infolist()}
        assert zf.getinfo("manifest.json").external_attr >> 16 == 0o644
    assert kinds == {"manifest.json": zipfile.ZIP_DEFLATED,
                     "arrays/zeros.npy": zipfile.ZIP_STORED,
                     "arrays/ramp.npy": zipfile.ZIP_DEFLATED}  # fmt: skip
    assert read_raw(path)[1]["zeros"].shape == (200_000,)


# --- the reader's limits at their edges -----------------------------------------------------
def test_array_members_exactly_at_the_array_byte_limit_are_read(tmp_path, monkeypatch):
    # the reader counts the array members' declared sizes, not the manifest's
    path = write_raw(tmp_path / "r.gpmsa", dict(CONTENT), {"a": np.ones(4), "b": np.arange(3)})
    with zipfile.ZipFile(path) as zf:
        total = sum(i.file_size for i in zf.infolist() if i.filename != "manifest.json")
    monkeypatch.setattr(limits, "MAX_ARRAY_BYTES", total)
    assert read_raw(path)[1]["b"].tolist() == [0, 1, 2]
    monkeypatch.setattr(limits, "MAX_ARRAY_BYTES", total - 1)
    with pytest.raises(EmulatorFileError, match=f"arrays of {total} bytes"):
        read_raw(path)


# --- hostile members ------------------------------------------------------------------------
def test_an_array_whose_npy_header_disagrees_with_the_manifest_is_refused(tmp_path):
    # same bytes of data, another shape: the hash is recomputed over what the reader would load
    path = _hostile(
        tmp_path / "h.gpmsa", {}, {"a": _npy(np.zeros((3, 2)))}, {"a": np.zeros((2, 3))}
    )
    with pytest.raises(EmulatorFileError, match=r"'a' is <f8\[3, 2\], manifest says <f8\[2, 3\]"):
        read_raw(path)


def test_an_array_member_with_bytes_after_its_data_is_refused(tmp_path):
    a = np.arange(4.0)
    path = _hostile(tmp_path / "t.gpmsa", {}, {"a": _npy(a) + bytes(8)}, {"a": a})
    with pytest.raises(EmulatorFileError, match=r"its data are 40 bytes, its shape needs 32"):
        read_raw(path)


def _manifest_only(path: Path, text: str) -> Path:
    return _zip(path, {"manifest.json": text.encode()})


def test_a_manifest_with_a_nan_constant_is_refused(tmp_path):
    manifest = dict(CONTENT, format="gpmsa-emulator", schema_version=1, arrays={},
                    content_sha256="0" * 64, metadata={"x": float("nan")})  # fmt: skip
    path = _manifest_only(tmp_path / "n.gpmsa", json.dumps(manifest))  # writes NaN
    with pytest.raises(EmulatorFileError, match="non-standard JSON constant NaN"):
        read_manifest(path)


def test_a_manifest_that_is_no_json_object_is_refused(tmp_path):
    path = _manifest_only(tmp_path / "l.gpmsa", "[1, 2]")
    with pytest.raises(EmulatorFileError, match="manifest.json must hold a JSON object"):
        read_manifest(path)


def test_a_folder_is_refused_as_a_directory(tmp_path):
    with pytest.raises(EmulatorFileError, match=r"not a regular file \(a directory\)"):
        read_raw(tmp_path)


def test_a_file_that_cannot_be_opened_is_refused_naming_why(tmp_path, monkeypatch):
    path = write_raw(tmp_path / "p.gpmsa", dict(CONTENT), {})

    def denied(*args, **kw):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(container.os, "open", denied)
    with pytest.raises(EmulatorFileError, match=r"cannot read \(Permission denied\)"):
        read_raw(path)


# --- paths, arguments, messages -------------------------------------------------------------
def test_a_tilde_before_a_user_name_is_a_name_not_that_users_home():
    name = "~" + pwd.getpwuid(os.getuid()).pw_name
    assert home_path(name) == Path(name)
    assert home_path(name + "/f.gpmsa") == Path(name, "f.gpmsa")


@pytest.mark.parametrize("bad", ["z" * 64, "a" * 63, "a" * 65, 12])
def test_an_expected_sha256_must_be_64_hexadecimal_digits(bad):
    with pytest.raises(GPMSAError, match="sha256 must be 64 hexadecimal digits"):
        check_expected_sha256(bad)


def test_an_expected_sha256_is_read_in_lower_case_without_spaces():
    assert check_expected_sha256(" " + "AB" * 32 + "\n") == "ab" * 32


def test_a_value_from_a_file_is_cut_to_sixty_characters_in_messages():
    assert _short("x" * 58) == repr("x" * 58)
    assert _short("x" * 59) == "'" + "x" * 56 + "..."


def test_a_newer_schema_emulator_file_is_not_replaced_by_a_study(tmp_path):
    manifest = dict(CONTENT, format="gpmsa-emulator", schema_version=2, arrays={},
                    content_sha256="0" * 64)  # fmt: skip
    target = _manifest_only(tmp_path / "new.gpmsa", json.dumps(manifest))
    with pytest.raises(GPMSAError, match="it holds an emulator file"):
        refuse_to_replace(target, STUDY_FORMAT)
    refuse_to_replace(target, container.FORMAT)  # an emulator file may replace it


def _nested(depth: int) -> dict:
    out: dict = {}
    for _ in range(depth):
        out = {"a": out}
    return out


@pytest.mark.parametrize(
    "bad", [float("nan"), {1, 2}, _nested(100_000)], ids=["nan", "set", "deep"]
)
def test_a_manifest_that_is_not_json_able_is_refused_by_the_writer(tmp_path, bad):
    manifest = dict(CONTENT, metadata={"x": bad})
    with pytest.raises(GPMSAError, match="the manifest is not JSON-able"):
        check_writable(manifest, {})
    with pytest.raises(GPMSAError, match="the manifest is not JSON-able"):
        write_raw(tmp_path / "j.gpmsa", manifest, {})  # not a ValueError from json
    assert not (tmp_path / "j.gpmsa").exists()


def test_the_members_carry_a_fixed_time_so_one_record_gives_one_file(tmp_path):
    path = write_raw(tmp_path / "t.gpmsa", dict(CONTENT), {"a": np.ones(2)})
    with zipfile.ZipFile(path) as zf:
        assert {i.date_time for i in zf.infolist()} == {(1980, 1, 1, 0, 0, 0)}


def test_edited_array_data_fail_the_content_hash(tmp_path):
    path = write_raw(tmp_path / "e.gpmsa", dict(CONTENT), {"a": np.arange(4.0)})
    with zipfile.ZipFile(path) as zf:
        members = {n: zf.read(n) for n in zf.namelist()}
    members["arrays/a.npy"] = _npy(np.arange(4.0) + 1)  # same shape, other data
    with pytest.raises(EmulatorFileError, match="content hash mismatch"):
        read_raw(_zip(tmp_path / "f.gpmsa", members))


# --- the zip's structure ----------------------------------------------------------------------
def _end_record(entries: int, cd_size: int, cd_offset: int = 0) -> bytes:
    return b"PK\x05\x06" + struct.pack("<HHHHIIH", 0, 0, entries, entries, cd_size, cd_offset, 0)


def test_an_empty_zip_is_named_so(tmp_path):
    path = tmp_path / "e.gpmsa"
    path.write_bytes(_end_record(0, 0))
    with pytest.raises(EmulatorFileError, match="an empty zip: no manifest.json"):
        read_raw(path)


def test_one_byte_after_the_end_record_is_named(tmp_path):
    path = write_raw(tmp_path / "a.gpmsa", dict(CONTENT), {})
    path.write_bytes(path.read_bytes() + b"x")
    with pytest.raises(EmulatorFileError, match="damaged zip: 1 bytes follow the end record"):
        read_raw(path)


def test_a_classic_end_record_with_a_zip64_directory_size_is_refused(tmp_path):
    path = tmp_path / "z.gpmsa"
    path.write_bytes(bytes(64) + _end_record(1, 0xFFFFFFFF))
    with pytest.raises(EmulatorFileError, match="damaged zip64 end record"):
        read_raw(path)


def test_an_end_record_pointing_at_no_directory_is_not_a_readable_zip(tmp_path):
    path = tmp_path / "d.gpmsa"
    path.write_bytes(bytes(46) + _end_record(1, 46))
    with pytest.raises(EmulatorFileError, match="not a readable zip: "):
        read_raw(path)


def test_a_zip_of_one_npy_member_is_named_as_an_npz(tmp_path):
    path = _zip(tmp_path / "v.gpmsa", {"x.npy": _npy(np.ones(2))})
    with pytest.raises(EmulatorFileError, match=r"its first member 'x.npy': a numpy .npz"):
        read_raw(path)


def test_an_encrypted_member_is_refused(tmp_path):
    path = tmp_path / "c.gpmsa"
    _zip(path, {"manifest.json": b"{}"})
    data = bytearray(path.read_bytes())
    for sig, at in ((b"PK\x03\x04", 6), (b"PK\x01\x02", 8)):  # local and central headers
        data[data.index(sig) + at] |= 0x1  # the general purpose flag's bit 0: encrypted
    path.write_bytes(bytes(data))
    with pytest.raises(EmulatorFileError, match="member 'manifest.json' is encrypted"):
        read_raw(path)


def test_a_manifest_member_exactly_at_the_manifest_byte_limit_is_read(tmp_path, monkeypatch):
    path = write_raw(tmp_path / "m.gpmsa", dict(CONTENT), {})
    with zipfile.ZipFile(path) as zf:
        size = zf.getinfo("manifest.json").file_size
    monkeypatch.setattr(limits, "MAX_MANIFEST_BYTES", size)
    assert read_manifest(path)["format"] == "gpmsa-emulator"
    monkeypatch.setattr(limits, "MAX_MANIFEST_BYTES", size - 1)
    with pytest.raises(EmulatorFileError, match=f"manifest.json declares {size} bytes"):
        read_manifest(path)


def test_a_gpmsa_file_cut_short_is_named_so_when_a_save_would_replace_it(tmp_path):
    path = write_raw(tmp_path / "c.gpmsa", dict(CONTENT), {"a": np.arange(50.0)})
    path.write_bytes(path.read_bytes()[:200])
    with pytest.raises(GPMSAError, match="it holds a gpmsa file cut short"):
        refuse_to_replace(path, container.FORMAT)


# --- the manifest ---------------------------------------------------------------------------
def test_the_nesting_depth_counts_the_outer_value_as_one():
    assert container._nesting(1) == 1
    assert container._nesting({"a": [1, {"b": [[]]}]}) == 5
    assert container._nesting([[[1]], 2]) == 4


def test_a_schema_version_of_zero_is_refused(tmp_path):
    manifest = dict(CONTENT, format="gpmsa-emulator", schema_version=0, arrays={},
                    content_sha256="0" * 64)  # fmt: skip
    with pytest.raises(EmulatorFileError, match="schema_version must be a positive integer"):
        read_manifest(_manifest_only(tmp_path / "s.gpmsa", json.dumps(manifest)))


def test_an_array_shape_that_is_no_list_is_malformed(tmp_path):
    path = _hostile(tmp_path / "s.gpmsa", {}, {"a": _npy(np.ones(2))}, {"a": np.ones(2)})
    with zipfile.ZipFile(path) as zf:
        members = {n: zf.read(n) for n in zf.namelist()}
    manifest = json.loads(members["manifest.json"])
    manifest["arrays"]["a"]["shape"] = "x"
    members["manifest.json"] = json.dumps(manifest).encode()
    with pytest.raises(EmulatorFileError, match="manifest entry of array 'a' is malformed"):
        read_raw(_zip(tmp_path / "t.gpmsa", members))


# --- .npy versions --------------------------------------------------------------------------
def _npy_version(arr: np.ndarray, version: tuple[int, int]) -> bytes:
    buf = io.BytesIO()
    np.lib.format.write_array(buf, arr, version=version, allow_pickle=False)
    return buf.getvalue()


def test_an_npy_member_of_format_version_2_is_read(tmp_path):
    a = np.arange(6.0).reshape(2, 3)
    path = _hostile(tmp_path / "v.gpmsa", {}, {"a": _npy_version(a, (2, 0))}, {"a": a})
    np.testing.assert_array_equal(read_raw(path)[1]["a"], a)


def test_an_npy_member_of_an_unknown_format_version_is_refused(tmp_path):
    a = np.arange(3.0)
    member = bytearray(_npy_version(a, (1, 0)))
    member[6] = 3  # the format's major version
    path = _hostile(tmp_path / "u.gpmsa", {}, {"a": bytes(member)}, {"a": a})
    with pytest.raises(EmulatorFileError, match=r"bad .npy header \(npy version 3.0\)"):
        read_raw(path)


def test_the_content_hash_is_the_documented_sha256_so_saved_files_stay_readable():
    # names sorted; each "name\0dtype\0shape\0" then the data's bytes; then the manifest's
    # compact sorted JSON without content_sha256. A change here makes every saved file unreadable.
    arrays = {"b": np.array([True, False]), "a": np.arange(3.0)}
    manifest = {"x": 1, "content_sha256": "ignored"}
    want = hashlib.sha256(
        b"a\0<f8\0(3,)\0" + np.arange(3.0).tobytes() + b"b\0|b1\0(2,)\0\x01\x00" + b'{"x":1}'
    ).hexdigest()
    assert want == "2e9b0daa76c27d39cf8d09b3fc51d9386de0a8f57f8cbfff5b68096e0bcfb061"
    assert container.content_hash(arrays, manifest) == want


@pytest.mark.parametrize(
    ("metadata", "where"),
    [
        ({2: 1, 10: 2}, r"manifest\['metadata'\]: key 2 \(int\)"),
        ({"runs": [{"a": 1}, {1.5: 2}]}, r"manifest\['metadata'\]\['runs'\]\[1\]: key 1.5"),
        ({"ok": {True: 1}}, r"key True \(bool\)"),
    ],
)
def test_a_manifest_with_keys_that_are_not_strings_is_refused_by_the_writer(
    tmp_path, metadata, where
):
    # JSON writes 2 as "2": the writer hashed the keys sorted as numbers, the reader as strings,
    # and the file it wrote failed its own content hash ("edited or damaged")
    with pytest.raises(GPMSAError, match=where + ".*keys must be strings"):
        write_raw(tmp_path / "k.gpmsa", dict(CONTENT, metadata=metadata), {"x": np.ones(3)})
    assert not (tmp_path / "k.gpmsa").exists()
