"""Review of s90 (gpmsa): a group's folder flush runs after its folder locks are released (a
reader of a study waited on the disk's fsync, a slow one up to LOCK_WAIT_S and then failed);
a separable= factor given as a 0-d array is named by GPMSAError (it raised a bare TypeError
"iteration over a 0-d array", as 1.0 and None did before s90)."""

import os
import sys

import numpy as np
import pytest

from gpmsa.errors import GPMSAError
from gpmsa.io import atomic
from gpmsa.model.kronecker import parse_groups


@pytest.mark.skipif(sys.platform == "win32", reason="no folder locks or folder fsync there")
def test_a_group_flushes_its_folder_after_releasing_its_lock(tmp_path, monkeypatch):
    import fcntl

    real, seen = atomic.flush_folder, []

    def flush(folder, error):
        fd = os.open(folder, os.O_RDONLY)  # another open file: its lock conflicts with the group's
        try:
            fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)  # a reader of the study (load_study)
            seen.append("free")
        except BlockingIOError:
            seen.append("held")
        finally:
            os.close(fd)
        real(folder, error)

    monkeypatch.setattr(atomic, "flush_folder", flush)
    with atomic.atomic_group() as stage:
        for name in ("a.gpmsa", "b.gpmsa"):
            with stage(tmp_path / name) as fh:
                fh.write(name.encode())
    assert seen == ["free"]
    assert (tmp_path / "b.gpmsa").read_bytes() == b"b.gpmsa"


@pytest.mark.parametrize(
    ("separable", "shown"),
    [([np.int64(0), np.array(1)], "array(1)"), ([[0], np.array("b")], "array('b', dtype='<U1')")],
)
def test_a_zero_d_array_factor_is_named(separable, shown):
    with pytest.raises(GPMSAError) as info:
        parse_groups(separable, ("a", "b"))
    assert str(info.value) == f"separable: an input is a name or an index, got {shown}"


def test_a_zero_d_array_for_separable_is_named():
    with pytest.raises(GPMSAError, match=r"^separable must be None, True or a sequence of factors"):
        parse_groups(np.array(0), ("a", "b"))


def test_sequences_of_inputs_read_as_before():
    names = ("a", "b", "c")
    assert parse_groups([{"a"}, ("b", "c")], names) == ((0,), (1, 2))
    assert parse_groups(np.array([[0], [1], [2]]), names) == ((0,), (1,), (2,))
    assert parse_groups([np.int64(2), ["a", np.str_("b")]], names) == ((2,), (0, 1))
