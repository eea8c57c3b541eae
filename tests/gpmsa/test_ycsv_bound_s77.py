"""``gpmsa calibrate --y-csv`` stops reading at the line that takes the file past the fields an
observation's file can hold (`Y_CSV_FIELDS_PER_OUTPUT` per output: twice a header row and one
row of values). Before, every line was split into fields first, whatever their count: a file
under the 64 MiB limit of one line of "12," took 22 s and 2.5 GB, a column of "1" lines was
killed at 120 s holding 13.7 GB (here, a 3 MB line: about 1 s and 150 MB; 2 MB of lines: about
4 s and 500 MB, before the count was refused). Files within the bound read as before."""

from __future__ import annotations

import csv
import tracemalloc

import numpy as np
import pytest

from gpmsa.cli import calibrate
from gpmsa.cli.calibrate import _csv_row, _field_count
from gpmsa.errors import GPMSAError

NAMES = tuple(f"y{k}" for k in range(40))


@pytest.mark.parametrize(
    ("text", "line"),
    [
        ("12," * 1_000_000 + "12\n", 1),  # one line of many fields
        ("# values\n\n" + "1\n" * 1_000_000, 163),  # a column of many rows: 160 read, then 161
        ('"1",' * 500_000 + '"1"\n', 1),  # quoted fields
        ("1 " * 1_000_000 + "\n", 1),  # fields separated by blanks
    ],
    ids=["a line", "a column", "quoted", "blanks"],
)
def test_a_file_of_too_many_fields_is_refused_at_the_line_that_passes_the_bound(
    tmp_path, text, line
):
    path = tmp_path / "y.csv"
    path.write_text(text)
    tracemalloc.start()
    try:
        with pytest.raises(
            GPMSAError, match=rf"y\.csv: line {line} takes the file past 160 fields \(4 per output"
        ):
            _csv_row(str(path), NAMES)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 4 * len(text)  # the bytes and their text, not a list of fields


def test_files_within_the_bound_read_as_before(tmp_path):
    path = tmp_path / "y.csv"
    values = np.linspace(0.0, 1.0, 40)
    path.write_text("\n".join([",".join(NAMES), ",".join(map(str, values.tolist()))]) + "\n")
    assert np.array_equal(_csv_row(str(path), NAMES), values)
    path.write_text("# a comment\n\n" * 10_000 + "\n".join(map(str, values.tolist())) + "\n")
    assert np.array_equal(_csv_row(str(path), NAMES), values)
    path.write_text(("1," * 79 + "1\n") * 2)  # 160 fields: the message of a count, as before
    with pytest.raises(GPMSAError, match=r"2 row\(s\) x 80 column\(s\) of values"):
        _csv_row(str(path), NAMES)


def test_runs_of_blank_and_comment_lines_are_skipped(tmp_path):
    # (skipped a run at a time: 60 MiB of blank lines took 10 s and 0.7 GB line by line, 0.2 s
    # now; timed in no test: a loaded host varies by 2x)
    path = tmp_path / "y.csv"
    path.write_text((" \n\x0c\r\n" * 2000 + "# a comment\n") * 1000 + ";".join(["1"] * 40) + "\n")
    assert np.array_equal(_csv_row(str(path), NAMES), np.ones(40))


def test_the_field_count_is_csvs_count_of_every_line():
    """The bounded count equals ``len`` of the fields `_fields` reads, on seeded lines of
    separators, quotes, blanks and text."""
    rng = np.random.default_rng(77)
    chars = np.array(list(' ,;"a1\t'))
    for _ in range(3000):
        line = "".join(rng.choice(chars, size=int(rng.integers(0, 14))))
        try:
            fields = calibrate._fields(line)
        except csv.Error:
            continue
        assert _field_count(line, 100) == len(fields), repr(line)
        assert _field_count(line, 2) == min(len(fields), 3), repr(line)


def test_the_lines_read_are_splitlines_lines_that_hold_values():
    """`_lines` numbers and skips lines as ``str.splitlines`` and the blank and "#" checks do,
    on seeded texts of every line break, blanks, comments and values."""
    rng = np.random.default_rng(7)
    chars = np.array([*" \t\n\r#a1,", "\r\n", "\x0b", "\x0c", "\x1c", "\x85", "\u2028", "\xa0"])
    for _ in range(3000):
        text = "".join(rng.choice(chars, size=int(rng.integers(0, 16))))
        want = [(k, line) for k, line in enumerate(text.splitlines(), 1)
                if line.strip() and not line.lstrip().startswith("#")]  # fmt: skip
        assert list(calibrate._lines(text)) == want, repr(text)
