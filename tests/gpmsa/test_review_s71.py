"""Session 71 review of the day's gpmsa changes: a labelled pandas table as ``SimData(x_range=,
t_range=)`` is read by its labels (as SimData reads x, t and y: never by position)."""

import numpy as np
import pandas as pd
import pytest

import gpmsa

RNG = np.random.default_rng(0)
X = np.column_stack([RNG.uniform(0.0, 1.0, 20), RNG.uniform(100.0, 200.0, 20)])
T = RNG.uniform(size=(20, 1))


def _sim(x_range):
    return gpmsa.SimData(x=X, t=T, y=X[:, :1] + T, x_names=["a", "b"], x_range=x_range)


def test_a_table_with_one_column_per_input_is_read_by_its_labels():
    """SEPIA's (2, p) layout as a DataFrame with the inputs' names as columns: with p = 2 it has
    the (p, 2) shape and was read by position, a in (-1, 90) and b in (2, 210), silently."""
    sepia = pd.DataFrame({"a": [-1.0, 2.0], "b": [90.0, 210.0]})
    assert _sim(sepia).x_range == ((-1.0, 2.0), (90.0, 210.0))
    some = pd.DataFrame({"b": [90.0, 210.0]})  # one column: the other keeps the design's
    assert _sim(some).x_range == (None, (90.0, 210.0))


def test_a_table_with_one_row_per_input_is_read_by_its_labels():
    """One (min, max) row per input, the index naming the inputs in another order than x's
    columns: read by the index, not by position (which read a in [90, 210])."""
    rows = pd.DataFrame({"lo": [90.0, -1.0], "hi": [210.0, 2.0]}, index=["b", "a"])
    assert _sim(rows).x_range == ((-1.0, 2.0), (90.0, 210.0))
    plain = pd.DataFrame([[-1.0, 2.0], [90.0, 210.0]])  # no names: one row per column, in order
    assert _sim(plain).x_range == ((-1.0, 2.0), (90.0, 210.0))


def test_a_table_naming_an_input_twice_is_refused():
    twice = pd.DataFrame([[-1.0, 2.0], [90.0, 210.0]], index=["a", "a"])
    with pytest.raises(gpmsa.GPMSAError, match=r"x_range names an input twice"):
        _sim(twice)


def test_one_parameter_takes_its_range_as_a_pair():
    """q = 1: t_range=(lo, hi) is that parameter's (min, max) (it was refused as shape (2,));
    SEPIA's (2, 1) layout is refused with the hint to transpose it, a (3, 2) without it."""
    pair = gpmsa.SimData(x=X, t=T, y=X[:, :1] + T, x_names=["a", "b"], t_range=(-0.5, 1.5))
    assert pair.t_range == ((-0.5, 1.5),)
    with pytest.raises(gpmsa.GPMSAError, match=r"got shape \(2, 1\) \(SEPIA's"):
        gpmsa.SimData(x=X, t=T, y=X[:, :1] + T, t_range=[[-0.5], [1.5]])
    with pytest.raises(gpmsa.GPMSAError, match=r"got shape \(3, 2\)$"):
        _sim([[0.0, 1.0], [0.0, 1.0], [0.0, 1.0]])
