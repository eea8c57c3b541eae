"""CSV content users bring from spreadsheets, loggers and other tools, through ``gpmsa calibrate
--y-csv`` and through pandas tables given to SimData, ObsData and the Calibrator (s79 sweep).

Before: a spreadsheet's "#N/A" starting a line was skipped as a comment (a column of values
lost one silently; a file of "#N/A" first read "holds no values" or as a header row); a
separator ending every line (a spreadsheet's empty last column) read "column 4 is empty (a
missing value?)"; decimal commas and digit grouping read "'5;2' is not a number" or as a
header row of names "1,5"; a byte that is not UTF-8 was named by its offset, also in a
comment; a UTF-16 file (a spreadsheet's "Unicode text") was refused. Through pandas: a header
with blanks (" f") was refused; a column that pandas kept as text for one "-" was named by its
first entry, a number ("got str '0.0856'"); pandas' labels of an empty header ("Unnamed: 3"), a
repeated one ("f.1") or of a file without a header row were listed without a word."""

import io
import json
import re

import numpy as np
import pandas as pd
import pytest

import gpmsa
from gpmsa.cli.calibrate import _csv_row
from gpmsa.cli.main import main
from gpmsa.errors import GPMSAError

NAMES = ("a", "b", "c")


def _row(tmp_path, data: bytes, names=NAMES) -> np.ndarray:
    path = tmp_path / "y.csv"
    path.write_bytes(data)
    return _csv_row(str(path), names)


@pytest.mark.parametrize(
    "data",
    [
        b"a,b,c,\r\n1,2,3,\r\n",
        b"1,2,3,\n",
        b"1,\n2,\n3,\n",
        b"a;b;c;\n1;2;3;\n",
        b"c,a,b,\n3,1,2,\n",
    ],
    ids=["header and row, CRLF", "row", "column", "semicolons", "another order"],
)
def test_a_separator_ending_every_line_is_an_empty_last_column_dropped(tmp_path, data):
    np.testing.assert_array_equal(_row(tmp_path, data), [1.0, 2.0, 3.0])


def test_a_missing_last_value_is_still_refused(tmp_path):
    with pytest.raises(GPMSAError, match=r"1 row\(s\) x 3 column\(s\) of values \(the empty last "
                                         r"column, a separator ending every line, dropped\); the "
                                         r"file's outputs are 4"):  # fmt: skip
        _row(tmp_path, b"1,2,3,\n", ("a", "b", "c", "d"))
    with pytest.raises(GPMSAError, match=r"line 2, column 3 is empty \(a missing value\?\)"):
        _row(tmp_path, b"a,b,c,\n1,2,,\n")  # not every line ends so: the file as it is


@pytest.mark.parametrize(
    ("data", "line", "column"),
    [
        (b"1\n#N/A\n2\n3\n", 2, 1),  # before: [1, 2, 3], the value lost
        (b"#N/A,2,3\n", 1, 1),  # before: "the file holds no values"
        (b"#N/A\n1\n2\n", 1, 1),  # before: a header row "#N/A"
        (b"a,b,c\n#DIV/0!;2;3\n", 2, 1),
        (b"#N/A\t2\t3\n", 1, 1),
    ],
)
def test_a_spreadsheet_error_value_starting_a_line_is_a_missing_value_not_a_comment(
    tmp_path, data, line, column
):
    with pytest.raises(GPMSAError, match=rf"line {line}, column {column} '#[A-Z/0!]+' is not a "
                                         r"number \(a missing value\? give every"):  # fmt: skip
        _row(tmp_path, data)
    np.testing.assert_array_equal(_row(tmp_path, b"#N/A means missing\n# x\n1,2,3\n"), [1, 2, 3])


@pytest.mark.parametrize(
    ("data", "field"),
    [
        (b"1,5;2,5;3,5\n", "5;2"),  # a semicolon file with decimal commas
        (b"a;b;c\n1,5;2,5;3,5\n", "5;2"),
        (b'"1,5";"2,5";"3,5"\n', '1,5;"2'),  # before: a header row of names
        (b'"1,5","2,5","3,5"\n', "1,5"),  # before: a header row of names
        (b'"1,234.5",2,3\n', "1,234.5"),
        (b"1.234,5;2;3\n", "5;2;3"),
        ("1\u00a0234;2;3\n".encode(), r"1\\xa0234"),  # shown escaped
    ],
)
def test_decimal_commas_and_digit_grouping_are_refused_as_such(tmp_path, data, field):
    with pytest.raises(GPMSAError, match=rf"column \d '{re.escape(field)}' is not a number: a "
                                         r"decimal comma "
                                         r"or a thousands separator\?"):  # fmt: skip
        _row(tmp_path, data)


@pytest.mark.parametrize(
    ("field", "message"),
    [
        ("NA", r"'NA' is not a number \(a missing value\?"),
        ("-", r"'-' is not a number \(a missing value\?"),
        ("NaN", r"'NaN' is not a finite number \(a missing value\?"),
        ("1e400", r"'1e400' is not a finite number \(beyond float64's range\)"),
    ],
)
def test_missing_marks_and_overflow_are_named(tmp_path, field, message):
    with pytest.raises(GPMSAError, match=rf"line 2, column 2 {message}"):
        _row(tmp_path, f"a,b,c\n1,{field},3\n".encode())


def test_bytes_that_are_not_utf8_are_named_by_line_and_column_and_harmless_in_a_comment(tmp_path):
    with pytest.raises(GPMSAError, match=r"line 2, column 2 holds the byte 0xb0, which is not "
                                         r"UTF-8 .*save the file as UTF-8"):  # fmt: skip
        _row(tmp_path, b"# units\na,b \xb0C,c\n1,2,3\n")
    np.testing.assert_array_equal(_row(tmp_path, b"# b in \xb0C\na,b,c\n1,2,3\n"), [1, 2, 3])
    utf16 = "\ufeffa\tb\tc\r\n1\t2\t3\r\n".encode("utf-16-le")  # a spreadsheet's Unicode text
    np.testing.assert_array_equal(_row(tmp_path, utf16), [1, 2, 3])


def test_utf16_without_its_byte_order_mark_is_named(tmp_path):
    """Its NUL bytes read as fields of '\\x001\\x00' before."""
    bare = "a\tb\tc\r\n1\t2\t3\r\n".encode("utf-16-le")  # no mark
    with pytest.raises(GPMSAError, match=r"holds NUL bytes.*UTF-16 without its byte order mark"):
        _row(tmp_path, bare)


def test_header_names_match_without_blanks_and_case_is_named(tmp_path):
    np.testing.assert_array_equal(_row(tmp_path, b"b,a\n2,1\n", (" a ", "b")), [1, 2])
    with pytest.raises(GPMSAError, match=r"unknown \['A', 'B', 'C'\].*names are case-sensitive"):
        _row(tmp_path, b"A,B,C\n1,2,3\n")


def _emulator(x_names=("v",), y_names=("f", "g")) -> gpmsa.Emulator:
    rng = np.random.default_rng(3)
    x, t = rng.uniform(0, 1, 20), rng.uniform(0, 1, 20)
    sim = gpmsa.SimData(x=x[:, None], t=t[:, None], y=np.c_[x + t, x - t], x_names=x_names,
                        t_names=["E"], y_names=y_names)  # fmt: skip
    prm = {"betaU": [[1.0, 1.0], [1.0, 1.0]], "lamUz": [1.0, 1.0], "lamWs": [5e3, 5e3],
           "lamWOs": [5e3]}  # fmt: skip
    return gpmsa.Emulator.from_params(sim, prm)


def test_cli_reads_an_excel_csv_as_the_same_values_given_by_flags(tmp_path, capsys):
    emu_file = str(_emulator(x_names=(" v ",)).save(tmp_path / "e.gpmsa"))  # a header's " v "
    path = tmp_path / "y.csv"
    path.write_bytes(b"\xef\xbb\xbfg;f;\r\n0.25;1.1;\r\n")  # BOM, CRLF, an empty last column
    outs = []
    for given in (["--y-csv", str(path)], ["--y", "f=1.1", "--y", "g=0.25"]):
        code = main(["calibrate", emu_file, "--x", "v=0.5", *given, "--seed", "1", "--json"])
        out, err = capsys.readouterr()
        assert code == 0, err
        record = json.loads(out)
        outs.append((record["x"], record["y"], record["posterior"]))
    assert outs[0] == outs[1] and outs[0][1] == {"f": 1.1, "g": 0.25}


@pytest.fixture(scope="module")
def emu():
    return _emulator()


def _frame(text: str, **kw) -> pd.DataFrame:
    return pd.read_csv(io.StringIO(text), **kw)


def test_pandas_headers_with_blanks_are_read_by_name(emu):
    ref = gpmsa.Calibrator(emu, method="grid").update([[0.5]], [[1.0, 0.0]])
    df = _frame(" v , g , f \n0.5,0.0,1.0\n")  # pandas keeps the blanks: " g ", " f "
    post = gpmsa.Calibrator(emu, method="grid").update(df[[" v "]], df[[" g ", " f "]])
    obs = gpmsa.ObsData(x=df[[" v "]], y=df[[" g ", " f "]])
    post_obs = gpmsa.Calibrator(emu, method="grid").update(obs)
    for p in (post, post_obs):
        assert (p.mean("E"), p.sd("E"), p.quantile("E", 0.9)) == (
            ref.mean("E"), ref.sd("E"), ref.quantile("E", 0.9))  # fmt: skip


@pytest.mark.parametrize(
    ("text", "hint"),
    [
        ("f,g,\n1.0,0.0,\n", r"'Unnamed: 2' is pandas' label of a column without a header"),
        ("f,f\n1.0,0.0\n", r"'f.1' is pandas' label of a repeated header name"),
        ("F,G\n1.0,0.0\n", r"names are case-sensitive"),
        ("1.0,0.0\n1.1,0.1\n", r"a file without a header row.*header=None"),
        ("f,g,note\n1.0,0.0,3\n", r"select the columns: table\[\['f', 'g'\]\]"),
    ],
    ids=["trailing separator", "repeated name", "case", "no header row", "extra column"],
)
def test_pandas_labels_that_are_not_the_names_are_explained(emu, text, hint):
    y = _frame(text)
    with pytest.raises(GPMSAError, match=rf"y_obs has the columns .*\(in any order\) \(.*{hint}"):
        gpmsa.Calibrator(emu, method="grid").update(np.full((len(y), 1), 0.5), y)


@pytest.mark.parametrize(
    ("mark", "what"),
    [("-", r"a missing-value mark.*na_values=\['-'\]"), ('"1,000.5"', r"a decimal comma or a")],
)
def test_a_column_pandas_kept_as_text_is_named_by_its_entry_that_is_no_number(mark, what):
    rng = np.random.default_rng(1)
    lines = [f"{a!r},{b!r},{a + b!r}" for a, b in rng.uniform(0, 1, (12, 2)).tolist()]
    lines[3] = f"{mark}," + lines[3].split(",", 1)[1]
    df = _frame("v,E,f\n" + "\n".join(lines) + "\n")
    with pytest.raises(GPMSAError, match=r"x must be a numeric array, got str .*; the first that "
                                         rf"is not a number: '{mark.strip(chr(34))}' at row 3, "
                                         rf"column 'v' \({what}"):  # fmt: skip
        gpmsa.SimData(x=df[["v"]], t=df[["E"]], y=df[["f"]])
