"""``gpmsa calibrate --y-csv`` past its size limit: refused for its size, whatever its bytes."""

import pytest

from gpmsa.cli import calibrate
from gpmsa.cli.calibrate import _csv_row
from gpmsa.errors import GPMSAError


@pytest.mark.parametrize("tail", ["é", "\udcff"], ids=["a character cut at the limit", "not UTF-8"])
def test_a_file_past_the_limit_is_refused_for_its_size_not_its_encoding(tmp_path, monkeypatch,
                                                                       tail):  # fmt: skip
    # Before: the bounded read was decoded first, so a 2-byte character cut at the limit (or
    # any byte that is not UTF-8 past it) read "cannot read it (UnicodeDecodeError ...)".
    monkeypatch.setattr(calibrate, "Y_CSV_MAX_BYTES", 100)
    path = tmp_path / "y.csv"
    path.write_bytes(b"1\n" + b"#" * 98 + tail.encode("utf-8", "surrogateescape"))
    with pytest.raises(GPMSAError, match=r"y\.csv: it holds more than 100 bytes"):
        _csv_row(str(path), ("y",))
