"""Emulator and study files: forged shapes numpy cannot hold, the file-size limit on writing,
and study saves that would replace another study's model files."""

import json
import os
import struct
import time
import zipfile
from functools import cache

import numpy as np
import pytest

import gpmsa
from gpmsa import limits
from gpmsa.io import container
from tests.gpmsa._study_cases import emulator, observations


def _small() -> gpmsa.Emulator:
    rng = np.random.default_rng(1)
    x, t = rng.random((8, 1)), rng.random((8, 1))
    grid = np.linspace(0, 1, 3)
    y = (1 + t) * np.sin(np.pi * grid * (0.5 + x)) + 0.3 * t
    sim = gpmsa.SimData(x=x, t=t, y=y, index=grid)
    params = {"betaU": [[1.0, 1.0], [1.0, 1.0]], "lamUz": [1.0, 1.0], "lamWs": [5000.0, 5000.0],
              "lamWOs": [5000.0]}  # fmt: skip
    return gpmsa.Emulator.from_params(sim, params, n_pc=2)


@cache
def _study() -> gpmsa.Study:
    rng = np.random.default_rng(4)
    data = [observations(th, 3, 0.03, rng) for th in (0.35, 0.5)]
    return gpmsa.calibrate_study(
        [emulator(None)] * 2, [d[0] for d in data], [d[1] for d in data], labels=["a", "b"],
        hierarchical=["t"], n_samples=20, n_burn=10, seed=5, tune_rounds=2,
    )  # fmt: skip


def _npy_header(shape) -> bytes:
    """A .npy preamble (version 1.0) declaring a float64 array of ``shape``, without data."""
    head = f"{{'descr': '<f8', 'fortran_order': False, 'shape': {tuple(shape)}, }}"
    head += " " * ((64 - (10 + len(head) + 1) % 64) % 64) + "\n"
    return b"\x93NUMPY\x01\x00" + len(head).to_bytes(2, "little") + head.encode()


@pytest.mark.parametrize("shape", [[0, 2**70], [0, 2**40, 2**40], [2**62, 0, 4]])
def test_an_empty_array_declaring_dimensions_numpy_cannot_hold_is_a_file_error(tmp_path, shape):
    path = _small().save(tmp_path / "e.gpmsa")
    with zipfile.ZipFile(path) as zf:
        members = {n: zf.read(n) for n in zf.namelist()}
    manifest = json.loads(members["manifest.json"])
    manifest["arrays"]["extra"] = {"shape": shape, "dtype": "<f8"}
    members["manifest.json"] = json.dumps(manifest).encode()
    members["arrays/extra.npy"] = _npy_header(shape)
    with zipfile.ZipFile(path, "w") as zf:
        for name, data in members.items():
            zf.writestr(name, data)
    with pytest.raises(gpmsa.EmulatorFileError, match="array 'extra' declares shape"):
        gpmsa.load(path)


def test_the_writer_refuses_an_empty_array_numpy_could_not_read_back(tmp_path):
    arrays = {"a": np.zeros((0, 2**40, 2**10))}  # empty, but 8 TiB counting the 0 as 1
    with pytest.raises(gpmsa.GPMSAError, match="array 'a' declares shape"):
        container.write_raw(tmp_path / "r.gpmsa", {}, arrays)
    assert not os.listdir(tmp_path)


def test_save_refuses_a_file_beyond_max_file_bytes_and_keeps_the_old_one(tmp_path, monkeypatch):
    emu = _small()
    path = emu.save(tmp_path / "e.gpmsa")
    before = path.read_bytes()
    monkeypatch.setattr(limits, "MAX_FILE_BYTES", len(before) - 1)
    with pytest.raises(gpmsa.GPMSAError, match="MAX_FILE_BYTES") as err:
        emu.save(path)
    assert not isinstance(err.value, gpmsa.EmulatorFileError)
    assert path.read_bytes() == before and os.listdir(tmp_path) == ["e.gpmsa"]
    with pytest.raises(gpmsa.GPMSAError, match="MAX_FILE_BYTES"):
        emu.save(tmp_path / "new.gpmsa")
    assert os.listdir(tmp_path) == ["e.gpmsa"]


def test_a_study_save_never_replaces_the_model_files_of_another_study(tmp_path):
    study = _study()
    study.save(tmp_path / "run.gpmsa")
    time.sleep(1.1)  # another second: the model files' hashes (created_utc) would differ
    for other in ("run", "run.bak"):
        with pytest.raises(gpmsa.GPMSAError, match=r"run\.gpmsa"):
            study.save(tmp_path / other)
        assert not (tmp_path / other).exists()
    gpmsa.load_study(tmp_path / "run.gpmsa")
    study.save(tmp_path / "run.gpmsa")  # the study itself may still be saved again
    gpmsa.load_study(tmp_path / "run.gpmsa")
    study.save(tmp_path / "run.v2.gpmsa")  # another stem: its own model files
    assert sorted(os.listdir(tmp_path)) == [
        "run.a.gpmsa", "run.b.gpmsa", "run.gpmsa",
        "run.v2.a.gpmsa", "run.v2.b.gpmsa", "run.v2.gpmsa",
    ]  # fmt: skip


def test_a_study_can_replace_its_own_files_under_another_suffix_once_the_old_study_is_gone(
    tmp_path,
):
    study = _study()
    study.save(tmp_path / "run.gpmsa")
    (tmp_path / "run.gpmsa").unlink()
    study.save(tmp_path / "run")
    gpmsa.load_study(tmp_path / "run")


def _with_zip64_end(path, copies: int, entries_delta: int = 0) -> None:
    """Rewrite ``path`` with ``copies`` more copies of its first directory entry and a zip64
    end record giving the directory's real size, while the classic end record keeps the small
    values (zipfile reads the zip64 record whenever its locator is there)."""
    data = path.read_bytes()
    at = data.rfind(b"PK\x05\x06")
    entries, cd_size, cd_off = struct.unpack("<HII", data[at + 10 : at + 20])
    cd = data[cd_off : cd_off + cd_size]
    one = cd[: 46 + sum(struct.unpack("<HHH", cd[28:34]))]
    big = cd + one * copies
    n = entries + copies + entries_delta
    z64 = struct.pack("<4sQHHIIQQQQ", b"PK\x06\x06", 44, 45, 45, 0, 0, n, n, len(big), cd_off)
    loc = struct.pack("<4sIQI", b"PK\x06\x07", 0, cd_off + len(big), 1)
    end = struct.pack("<4sHHHHIIH", b"PK\x05\x06", 0, 0, entries, entries, cd_size, cd_off, 0)
    path.write_bytes(data[:cd_off] + big + z64 + loc + end)


def test_a_zip64_end_record_cannot_hide_a_large_directory(tmp_path, monkeypatch):
    path = _small().save(tmp_path / "e.gpmsa")
    _with_zip64_end(path, 0)
    gpmsa.load(path)  # a zip64 end record with the true values reads as before
    parsed = []
    real = zipfile.ZipFile._RealGetContents
    monkeypatch.setattr(
        zipfile.ZipFile, "_RealGetContents", lambda zf: parsed.append(1) or real(zf)
    )
    _with_zip64_end(path, 5000)
    with pytest.raises(gpmsa.EmulatorFileError, match=r"limit gpmsa\.limits\.MAX_MEMBERS"):
        gpmsa.load(path)
    path = _small().save(tmp_path / "f.gpmsa")
    _with_zip64_end(path, 5000, entries_delta=-5000)  # few entries declared, a large directory
    with pytest.raises(gpmsa.EmulatorFileError, match=r"zip directory of \d+ bytes for 19"):
        gpmsa.load(path)
    assert parsed == [1]  # only the save's own check: zipfile never parsed the forged ones
