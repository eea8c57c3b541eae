"""Saving to a path the file system's encoding cannot write (a lone surrogate) is a GPMSAError
naming the character, not a UnicodeEncodeError from deep in the atomic write."""

import os

import pytest

import gpmsa
from gpmsa.io.atomic import atomic_write
from tests.gpmsa.test_file_io_edges_s56 import _small


def test_an_emulator_saved_to_a_name_the_file_system_cannot_encode_is_a_gpmsa_error(tmp_path):
    with pytest.raises(gpmsa.GPMSAError, match=r"holds '\\ud800', which the file system"):
        _small().save(tmp_path / "e\ud800.gpmsa")
    assert os.listdir(tmp_path) == []


def test_atomic_write_names_the_character_and_raises_the_callers_error(tmp_path):
    class Mine(Exception):
        pass

    with pytest.raises(Mine, match="ud800"), atomic_write(tmp_path / "\ud800" / "x", error=Mine):
        pass
