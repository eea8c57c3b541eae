"""Review of session 91's atomic_group(on_moved=) (s91): an on_moved that raises leaves the
files in place, so the folders are still flushed to disk, and its error is raised."""

import os
import sys

import pytest

from gpmsa.io import atomic
from gpmsa.io.atomic import atomic_group
from tests._fsync import record_folder_fsyncs

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="no fsync of a folder there")


def test_an_on_moved_that_raises_still_has_the_folders_flushed(tmp_path, monkeypatch):
    flushed = record_folder_fsyncs(monkeypatch, atomic)

    def on_moved():
        raise RuntimeError("the caller's record failed")

    (tmp_path / "a").mkdir()
    with pytest.raises(RuntimeError, match="the caller's record failed"):
        with atomic_group(on_moved=on_moved) as stage:
            for path in (tmp_path / "f", tmp_path / "a" / "g"):
                with stage(path) as fh:
                    fh.write(b"new")
    assert (tmp_path / "f").read_bytes() == b"new" == (tmp_path / "a" / "g").read_bytes()
    assert sorted(flushed) == sorted(os.stat(p).st_ino for p in (tmp_path, tmp_path / "a"))
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []
