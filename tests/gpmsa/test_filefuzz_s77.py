"""Findings of the s77 file fuzz of ``gpmsa calibrate --y-csv``: a header row over a row of
fewer values raised an IndexError (the command: "unexpected IndexError ... please report it"),
over a row of more values dropped the extra ones without a word; an endless source
(``/dev/zero``, a pipe that never ends) was read without bound (the command hung, its memory
growing). Now each is a GPMSAError naming the file and what is wrong."""

import numpy as np
import pytest

from gpmsa.cli import calibrate
from gpmsa.cli.calibrate import _csv_row
from gpmsa.errors import GPMSAError

NAMES = ("a", 'b "c"', "é", "d,e")
GOOD = 'a,"b ""c""",é,"d,e"\n0.5,1.0,1.5,2.0\n'.encode()


@pytest.mark.parametrize("row", ["0.5", "0.5,1.0,1.5,2.0,9.0"])
def test_a_row_of_another_length_than_its_header_is_refused_by_line(tmp_path, row):
    path = tmp_path / "y.csv"
    path.write_text(f"a,b,c\n{row}\n")
    with pytest.raises(
        GPMSAError, match=r"y\.csv: line 2 has \d fields, the header row \(line 1\) 3"
    ):
        _csv_row(str(path), ("a", "b", "c"))


def test_seeded_damage_of_a_csv_reads_its_values_or_is_refused(tmp_path):
    """Truncations and single-byte changes (seeded): every outcome is the values or a
    GPMSAError naming the file, never another exception."""
    rng = np.random.default_rng(77)
    cases = [GOOD[:k] for k in range(len(GOOD))]
    for _ in range(300):
        b = bytearray(GOOD)
        b[int(rng.integers(len(b)))] ^= int(rng.integers(1, 256))
        cases.append(bytes(b))
    path = tmp_path / "y.csv"
    read = 0
    for data in cases:
        path.write_bytes(data)
        try:
            values = _csv_row(str(path), NAMES)
        except GPMSAError as exc:
            assert "y.csv" in str(exc), str(exc)
            continue
        assert values.shape == (4,) and np.all(np.isfinite(values))
        read += 1
    assert read >= 1  # the whole file, at least


def test_a_source_beyond_the_size_limit_is_refused_without_reading_it_all(tmp_path, monkeypatch):
    monkeypatch.setattr(calibrate, "Y_CSV_MAX_BYTES", 100)
    path = tmp_path / "y.csv"
    path.write_text("1\n" * 60)  # 120 bytes
    with pytest.raises(GPMSAError, match=r"y\.csv: it holds more than 100 bytes"):
        _csv_row(str(path), ("y",))


@pytest.mark.skipif(not __import__("os").path.exists("/dev/zero"), reason="no /dev/zero")
def test_an_endless_device_is_refused(monkeypatch):
    monkeypatch.setattr(calibrate, "Y_CSV_MAX_BYTES", 4096)
    with pytest.raises(GPMSAError, match=r"/dev/zero: it holds more than 4096 bytes"):
        _csv_row("/dev/zero", ("y",))
