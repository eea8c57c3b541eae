"""Review of session 76's commits (rev4): ``gpmsa calibrate --y-csv`` reads a CSV file as CSV
writers write it (quoted names, a spreadsheet's semicolons, numeric output names in a header),
and the reprs of SimData stay one concise line whatever the names.

Before: '"y0","y1","y2"' over a row of values was refused as a header naming unknown outputs
['"y0"', ...]; "1;2;3" was read as a header row naming an unknown output '1;2;3'; a header of
numeric names (wavelengths "400,410,420") over its row was read as two rows of values and
refused; a 10,000-character name made a 10,000-character repr, a newline in a name broke it."""

from __future__ import annotations

import numpy as np
import pytest

import gpmsa
from gpmsa.cli.calibrate import _csv_row
from gpmsa.errors import GPMSAError

NAMES = ("y0", "y1", "y2")


@pytest.mark.parametrize(
    "text",
    [
        '"y0","y1","y2"\n1,2,3\n',  # R's write.csv, Excel: names quoted
        '"y2", "y0", "y1"\r\n3, 1, 2\r\n',  # any order, blanks after the commas, CRLF
        "1;2;3\n",  # a spreadsheet's CSV in a locale whose decimal mark is a comma
        "\ufeffy0;y1;y2\n1;2;3\n",  # with a byte-order mark
        '"1","2","3"\n',  # values quoted
        "1,2,3\n",  # as before
        "1\n2\n3\n",
        "1 2 3\n",
    ],
)
def test_csv_files_as_writers_write_them(tmp_path, text):
    path = tmp_path / "y.csv"
    path.write_bytes(text.encode())
    np.testing.assert_array_equal(_csv_row(str(path), NAMES), [1.0, 2.0, 3.0])


def test_a_header_of_numeric_output_names_is_read_by_name(tmp_path):
    path = tmp_path / "y.csv"
    path.write_text("420,400,410\n3,1,2\n")
    np.testing.assert_array_equal(_csv_row(str(path), ("400", "410", "420")), [1.0, 2.0, 3.0])
    path.write_text("400,410,420\n")  # one row: the values, as before
    np.testing.assert_array_equal(_csv_row(str(path), ("400", "410", "420")), [400, 410, 420])


def test_a_field_beyond_csvs_limit_is_refused_by_name(tmp_path):
    path = tmp_path / "y.csv"
    path.write_text("1," + "9" * 200_000 + ",3\n")
    with pytest.raises(GPMSAError, match=r"--y-csv .*y\.csv: cannot read it as CSV"):
        _csv_row(str(path), NAMES)


def test_sim_data_repr_stays_one_concise_line_whatever_the_names():
    rng = np.random.default_rng(0)
    x, t = rng.random((6, 1)), rng.random((6, 1))
    sim = gpmsa.SimData(x, t, x[:, 0] + t[:, 0], x_names=["a" * 10_000], t_names=["b\nc"])
    text = repr(sim)
    assert "\n" not in text and len(text) < 200, text
    assert f"x: {'a' * 37}... [" in text and "t: b\\nc [" in text
    obs = gpmsa.ObsData(x=np.array([[0.2], [0.4]]), y=np.array([[1.0], [2.0]]))
    assert (
        repr(obs) == "ObsData(2 experiments; x: x_obs[:, 0] [0.2, 0.4]; y: 1 value(s) each [1, 2])"
    )
