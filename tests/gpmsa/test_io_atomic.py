"""gpmsa.io.atomic: a file (or a group of files) is replaced whole or not at all."""

import os

import pytest

from gpmsa.errors import GPMSAError
from gpmsa.io.atomic import atomic_group, atomic_write


class Boom(Exception):
    pass


def test_a_clean_write_replaces_the_file_and_leaves_nothing_beside_it(tmp_path):
    path = tmp_path / "data.bin"
    path.write_bytes(b"old")
    with atomic_write(path) as fh:
        fh.write(b"new contents")
        fh.seek(0)
        assert fh.read() == b"new contents"  # a writer may check what it wrote
    assert path.read_bytes() == b"new contents"
    assert os.listdir(tmp_path) == ["data.bin"]


def test_a_failure_midway_leaves_the_old_file_and_no_temporary_file(tmp_path):
    path = tmp_path / "data.bin"
    path.write_bytes(b"old")
    with pytest.raises(Boom), atomic_write(path) as fh:
        fh.write(b"half of the new")
        raise Boom
    assert path.read_bytes() == b"old"
    assert os.listdir(tmp_path) == ["data.bin"]


def test_text_mode_writes_utf8_and_keeps_newlines_as_given(tmp_path):
    path = tmp_path / "t.csv"
    with atomic_write(path, text=True) as fh:
        fh.write("a,b\r\nGD ≈ 300\n")
    assert path.read_bytes() == "a,b\r\nGD ≈ 300\n".encode()


def test_a_new_file_gets_the_usual_permissions(tmp_path):
    path = tmp_path / "f"
    with atomic_write(path) as fh:
        fh.write(b"x")
    umask = os.umask(0)
    os.umask(umask)
    assert os.stat(path).st_mode & 0o777 == 0o666 & ~umask


class Refused(Exception):
    pass


def test_a_directory_or_a_missing_folder_raises_the_callers_error(tmp_path):
    (tmp_path / "d").mkdir()
    with pytest.raises(Refused, match="not a regular file"):
        with atomic_write(tmp_path / "d", error=Refused):
            pass
    with pytest.raises(GPMSAError, match="cannot write"):
        with atomic_write(tmp_path / "no" / "f"):
            pass
    assert sorted(os.listdir(tmp_path)) == ["d"]


def test_a_group_replaces_every_file_at_its_end_or_none(tmp_path):
    a, b = tmp_path / "a.bin", tmp_path / "b.bin"
    a.write_bytes(b"old a")
    b.write_bytes(b"old b")
    with pytest.raises(Boom), atomic_group() as stage:
        with stage(a) as fh:
            fh.write(b"new a")
        assert a.read_bytes() == b"old a"  # written, not moved yet
        with stage(b) as fh:
            fh.write(b"half of new b")
            raise Boom
    assert (a.read_bytes(), b.read_bytes()) == (b"old a", b"old b")
    assert sorted(os.listdir(tmp_path)) == ["a.bin", "b.bin"]
    with atomic_group() as stage:
        for path in (a, b):
            with stage(path) as fh:
                fh.write(b"new " + path.name.encode())
    assert (a.read_bytes(), b.read_bytes()) == (b"new a.bin", b"new b.bin")
    assert sorted(os.listdir(tmp_path)) == ["a.bin", "b.bin"]
