"""Review of ``SimData(index_names=, index_units=)`` (a8ede46): an output index given as a pandas
table or Series, which now names the index's columns. Before: a Series named "" or " ", or a
table with duplicate or blank column labels, read by position up to a8ede46, was refused naming
``index_names`` (an argument the user never gave: "index_names[0] must be a non-empty name");
a Series read from a frame of default labels (``frame[0]``) was named "0", where the frame
itself names nothing; an unnamed Series with a float row index was refused with
``index_names="time"`` ("give one point as a Series indexed by ['time']", an input's advice),
and a Series named otherwise than ``index_names`` got that advice too. Now labels that are no
usable names (blank, repeated, a frame's default 0, 1, ...) name nothing and the index reads
as before; a Series whose name differs from ``index_names`` is refused naming both."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

import gpmsa

GRID = np.linspace(0.0, 1.0, 8)
POINTS = np.column_stack([np.repeat(np.linspace(0.0, 1.0, 4), 5), np.tile(np.linspace(0, 2, 5), 4)])


def _sim(index, **kw) -> gpmsa.SimData:
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(12, 1)), rng.uniform(size=(12, 1))
    cols = np.asarray(index, dtype=float).reshape(len(index), -1)
    return gpmsa.SimData(x=x, t=t, y=np.sin(np.pi * x * cols[:, 0]) + t * cols[:, -1], index=index,
                         **kw)  # fmt: skip


@pytest.mark.parametrize(
    "index",
    [
        pd.Series(GRID, name=""),
        pd.Series(GRID, name="  "),
        pd.DataFrame(GRID[:, None])[0],  # a default frame's column: named 0
        pd.DataFrame(POINTS, columns=["a", "a"]),
        pd.DataFrame(POINTS, columns=["", "angle"]),
    ],
    ids=["series ''", "series blank", "series 0", "repeated columns", "a blank column"],
)
def test_labels_that_are_no_names_name_nothing_and_read_as_before(index):
    sim = _sim(index)
    assert sim.index_names is None
    assert np.array_equal(sim.index, np.asarray(index, dtype=float))


def test_a_series_index_with_the_given_name_or_none_is_read_as_its_values():
    plain = _sim(pd.Series(GRID, index=GRID), index_names="time")  # float row labels
    named = _sim(pd.Series(GRID, name="time"), index_names="time")
    for sim in (plain, named):
        assert np.array_equal(sim.index, GRID) and sim.index_names == ("time",)


def test_a_series_index_named_otherwise_is_refused_naming_both():
    with pytest.raises(gpmsa.GPMSAError, match=r"index is a pandas Series named 't', but "
                                               r"index_names gives \('time',\)"):  # fmt: skip
        _sim(pd.Series(GRID, name="t"), index_names="time")
