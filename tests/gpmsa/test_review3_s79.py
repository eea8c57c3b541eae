"""Review of the s79 CSV-input and study-sweep commits (helper review3).

- a list or tuple holding text that is not a number (``[1.0, "a"]``) raised a TypeError from
  the new message hint (``list.index`` taken for a table's row labels) instead of the
  GPMSAError naming the argument;
- the hint showed numpy's reprs (``np.str_('x')``, ``row np.int64(20)``, also inside the
  ``na_values=[...]`` it suggests) and "index ()" for one text value;
- ``--y-csv``: a blank-separated line starting with a spreadsheet's "#N/A" was still skipped as
  a comment ("under a header row give one row of values, got 0"; docs/calibration.md says such
  a line is a missing value);
- ``--y-csv``: a header row holding a name that is also a missing-value mark (``a,NA,c``) was
  read as a row of values ("line 1, column 1 'a' is not a number") instead of a header whose
  names are not the outputs';
- a pandas Series (``df.iloc[0]``) of a table whose labels carry a CSV header's blanks was
  refused, though the table itself is read by name;
- y of such labels in another order than an ObsData's index was read by position silently (the
  same labels without blanks are refused as ambiguous).
"""

import numpy as np
import pandas as pd
import pytest

import gpmsa
from gpmsa.cli.calibrate import _csv_row
from gpmsa.errors import GPMSAError
from gpmsa.model.data import as_float, series_by_names

NAMES = ("a", "b", "c")


def _row(tmp_path, data: bytes, names=NAMES) -> np.ndarray:
    path = tmp_path / "y.csv"
    path.write_bytes(data)
    return _csv_row(str(path), names)


@pytest.mark.parametrize("value", [[1.0, "a"], (1.0, "a"), ["1", "a"]])
def test_a_list_of_text_is_a_gpmsa_error_naming_its_entry(value):
    first = r"; the first that is not a number: 'a' at index \(1,\) \("
    with pytest.raises(GPMSAError, match=rf"^x must be a numeric array, got str .*{first}"):
        as_float(value, "x")


def test_the_text_hint_shows_plain_text_and_labels():
    with pytest.raises(GPMSAError, match=r"the first that is not a number: 'x' at row 20 \(.*"
                                         r"na_values=\['x'\]\)"):  # fmt: skip
        as_float(pd.Series(["1", "x"], index=np.array([10, 20])), "x")
    for value in ("abc", np.array(["abc"])):
        with pytest.raises(GPMSAError, match=r"not a number: 'abc'( at index \(0,\))? \(.*"
                                             r"na_values=\['abc'\]\)") as err:  # fmt: skip
            as_float(value, "x")
        assert "np.str_" not in str(err.value) and "index ()" not in str(err.value)


@pytest.mark.parametrize(
    ("data", "line"),
    [(b"a b c\n#N/A 2 3\n", 2), (b"#N/A 2 3\n", 1), (b"1 #N/A 3\n", 1), (b"#N/A #N/A -1\n", 1)],
)
def test_an_error_value_starting_a_blank_separated_line_is_a_missing_value(tmp_path, data, line):
    with pytest.raises(GPMSAError, match=rf"line {line}, column \d '#N/A' is not a number \(a "
                                         r"missing value\?"):  # fmt: skip
        _row(tmp_path, data)
    # a comment that starts with the mark is still a comment
    np.testing.assert_array_equal(_row(tmp_path, b"#N/A - missing\n#N/A 1st\n1 2 3\n"), [1, 2, 3])


def test_a_header_with_a_name_that_is_a_missing_mark_is_a_header(tmp_path):
    for name in ("NA", "-", "none"):
        names = rf"must name the file's outputs .*unknown \['{name}'\], missing \['b'\]"
        with pytest.raises(GPMSAError, match=names):
            _row(tmp_path, f"a,{name},c\n1,2,3\n".encode())
    # a row of marks alone is a row of missing values, as the commit made it
    with pytest.raises(GPMSAError, match=r"line 1, column 1 'NA' is not a number \(a missing"):
        _row(tmp_path, b"NA,NA,NA\n")
    # an output named as a mark is read under its header
    np.testing.assert_array_equal(_row(tmp_path, b"a,NA,c\n1,2,3\n", ("NA", "a", "c")), [2, 1, 3])


def test_a_series_of_a_csv_tables_row_is_read_by_its_labels_without_blanks():
    row = pd.DataFrame([[1.0, 2.0]], columns=[" b", " a"]).iloc[0]
    np.testing.assert_array_equal(series_by_names(row, ["a", "b"], "x"), [[2.0, 1.0]])
    ambiguous = pd.DataFrame([[1.0, 2.0]], columns=["a", " a"]).iloc[0]
    with pytest.raises(GPMSAError, match="x is a pandas Series"):
        series_by_names(ambiguous, ["a", "b"], "x")


def test_y_columns_with_blanks_in_another_order_than_an_index_are_refused():
    """With an index, y's columns follow it by position; labels that are the outputs' names in
    another order are ambiguous and refused, also where they carry a CSV header's blanks (before:
    read by position silently, while the same table without the index was read by name)."""
    for cols in (["b", "a"], [" b", " a"]):
        obs = gpmsa.ObsData(x=[[0.5]], y=pd.DataFrame([[1.0, 2.0]], columns=cols), index=[0, 1])
        with pytest.raises(GPMSAError, match=r"ObsData y has the columns .* another order, and "
                                             r"an index"):  # fmt: skip
            obs.outputs(["a", "b"])
    same = gpmsa.ObsData(x=[[0.5]], y=pd.DataFrame([[1.0, 2.0]], columns=[" a", "b "]),
                         index=[0, 1])  # fmt: skip
    np.testing.assert_array_equal(same.outputs(["a", "b"])[0], [1.0, 2.0])
