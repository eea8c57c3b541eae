"""Exact cases for gpmsa.model.data that the s93 mutation sample (every 3rd site session 89
left) found untested: each gives one input and the exact message or value expected."""

import re
import warnings

import numpy as np
import pytest

from gpmsa.errors import GPMSAError
from gpmsa.model import data


def _raises(message: str):
    return pytest.raises(GPMSAError, match=f"^{re.escape(message)}$")


def test_as_float_without_advice_names_only_the_bad_entry():
    with _raises("x must be a numeric array, got str 'a'"):
        data.as_float(["a"], "x", advice=False)


def test_check_probabilities_returns_the_valid_q_as_float64():
    out = data.check_probabilities([0, 0.5, 1], "q")
    assert out.dtype == np.float64
    np.testing.assert_array_equal(out, [0.0, 0.5, 1.0])


def test_quantile_keys_refuses_a_level_whose_upper_end_rounds_to_the_median():
    # 1 + 1e-16 is 1.0 in float64 while 1 - 1e-16 is not: the ends print as
    # 49.99999999999999 and 50, but the distance to the median is 0 (tolerance 0)
    with _raises(
        "level=1e-16 is too small: the ends of its interval, at probabilities (1 -+ level) / 2, "
        "are both the median (0.5) in float64; give a larger level"
    ):
        data.quantile_keys(1e-16)


def test_output_scale_accepts_a_spread_whose_square_is_exactly_tiny():
    # centred values 2**-511 * (1, 0, -1): sample sd 2**-511 exactly, square 2**-1022 = tiny
    s = 2.0**-511
    sd = data.output_scale(np.array([[s], [0.0], [-s]]))
    assert sd == s and sd * sd == np.finfo(np.float64).tiny


def test_given_scale_refuses_standardised_values_beyond_float64():
    # (2e200 - 0) / 1e-150 overflows; its square is no concern of the product y * y_sd
    with _raises(
        "y standardised by the given y_mean and y_sd overflows float64 (largest "
        "|y - y_mean| / y_sd = inf); give a y_sd of the order of y's spread"
    ):
        data._given_scale(0.0, 1e-150, np.array([[1e200], [2e200]]))


def test_units_refuses_a_string():
    with _raises("units must be a list of units, got the string 'm' (for one unit pass ['m'])"):
        data._units("m", 2, "units")


def test_index_labels_refuse_one_string_for_two_index_columns():
    with _raises(
        "index_names must be a list of 2 names, one per column of the output index (4, 2), "
        "got the string 's'"
    ):
        data._index_labels("s", 2, 4, "index_names")


def test_named_index_reorders_a_named_table_by_index_names():
    pd = pytest.importorskip("pandas")
    frame = pd.DataFrame({"b": [1.0, 2.0], "a": [3.0, 4.0]})
    index, names = data._named_index(frame, ("a", "b"))
    assert names == ("a", "b")
    np.testing.assert_array_equal(np.asarray(index), [[3.0, 1.0], [4.0, 2.0]])


def test_index_of_one_column_is_the_flat_grid():
    out = data._index(np.array([[0.0], [1.0], [2.0]]), 3, "index")
    assert out.shape == (3,)
    np.testing.assert_array_equal(out, [0.0, 1.0, 2.0])


def test_index_of_one_row_with_the_wrong_count_says_the_count():
    with _raises("index must have 3 entries (one per output column), got 4"):
        data._index(np.zeros((1, 4)), 3, "index")


def test_check_increasing_names_the_pair_that_steps_down():
    with _raises(
        "index must be strictly increasing, got 2.0 then 1.0 at positions 1, 2; sort the "
        "output columns (the index and the columns of y together)"
    ):
        data.check_increasing(np.array([0.0, 2.0, 1.0]), "index")


def test_ranges_given_by_name_carry_no_sepia_hint():
    with _raises("x_range[a] = (1.0, 0.0) must be finite numbers with min < max"):
        data._ranges({"a": (1.0, 0.0)}, np.array([[0.5], [0.6]]), ("a",), (), "x_range")


def test_ranges_accept_a_width_between_tiny_and_twice_tiny_near_zero():
    tiny = np.finfo(np.float64).tiny
    out = data._ranges({"a": (0.0, 1.5 * tiny)}, np.array([[0.0], [1.5 * tiny]]), ("a",), (), "r")
    assert out == ((0.0, 1.5 * tiny),)


def test_ranges_refuse_a_width_that_overflows():
    with _raises(
        "x_range[a] = (-1e+308, 1e+308): the width inf is not a finite, normal number; "
        "rescale the column"
    ):
        data._ranges({"a": (-1e308, 1e308)}, np.array([[0.0], [1.0]]), ("a",), (), "x_range")


def test_ranges_do_not_warn_at_exactly_the_minimum_cover():
    # span 1 of width 10: exactly RANGE_COVER_MIN (0.1 * 10.0 == 1.0 in float64)
    assert data.RANGE_COVER_MIN * 10.0 == 1.0
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        out = data._ranges({"a": (0.0, 10.0)}, np.array([[0.0], [1.0]]), ("a",), (), "x_range")
    assert out == ((0.0, 10.0),)


def test_check_resolution_ignores_a_large_constant_column():
    assert data._check_resolution(np.array([[1e20, 0.0], [1e20, 1.0]]), 0.7) is None


def test_check_resolution_refuses_a_spread_of_exactly_1e_13_of_the_size():
    with _raises(
        "y varies by only sd 1e-13 around values up to 1 (within 1e-13 of their size, near "
        "float64's resolution there: 2 distinct values in 2); subtract the offset before the "
        "values are rounded (in the simulator or its output file), or rescale y"
    ):
        data._check_resolution(np.array([[0.0], [1.0]]), 1e-13)


def test_simdata_reads_a_table_t_by_the_given_names():
    pd = pytest.importorskip("pandas")
    t = pd.DataFrame({"b": [0.0, 1.0, 2.0, 3.0], "a": [5.0, 3.0, 4.0, 7.0]})
    sim = data.SimData(t=t, y=[0.0, 1.0, 3.0, 2.0], t_names=["a", "b"])
    assert sim.t_names == ("a", "b")
    np.testing.assert_array_equal(sim.t, [[5.0, 0.0], [3.0, 1.0], [4.0, 2.0], [7.0, 3.0]])


def test_simdata_reads_a_table_index_by_index_names():
    pd = pytest.importorskip("pandas")
    index = pd.DataFrame({"v": [0.0, 1.0, 0.0], "u": [0.0, 0.0, 1.0]})
    y = np.arange(15.0).reshape(5, 3) ** 1.5
    sim = data.SimData(t=[0.0, 1.0, 2.0, 3.0, 4.0], y=y, index=index, index_names=["u", "v"])
    assert sim.index_names == ("u", "v")
    np.testing.assert_array_equal(sim.index, [[0.0, 0.0], [0.0, 1.0], [1.0, 0.0]])


def test_simdata_refuses_an_unknown_y_scale_string():
    with _raises(f"y_scale must be one of {data.Y_SCALES}, got 'bogus'"):
        data.SimData(t=[0.0, 1.0, 2.0, 3.0], y=[0.0, 1.0, 3.0, 2.0], y_scale="bogus")


def test_simdata_names_the_part_of_a_categorical_column_with_a_fraction():
    with _raises(
        "t t0 is categorical: its levels must be integers, got np.float64(0.5) (map labels to "
        "integer codes first)"
    ):
        data.SimData(t=[0.5, 1.0, 2.0, 3.0], y=[0.0, 1.0, 3.0, 2.0], t_categorical=[0])


def test_obsdata_stacks_experiments_of_one_length():
    obs = data.ObsData(y=[[1.0, 2.0], [3.0, 4.0]])
    assert isinstance(obs.y, np.ndarray)
    np.testing.assert_array_equal(obs.y, [[1.0, 2.0], [3.0, 4.0]])


def test_obsdata_refuses_no_experiments():
    with _raises(
        "y_obs has no experiments (shape (0, 3)): ObsData needs at least one observation (a "
        "study's every model needs its own)"
    ):
        data.ObsData(y=np.empty((0, 3)))


def test_simdata_refuses_a_constant_column_under_columnwise_scale_at_once():
    with _raises(
        "y column 'y0' is constant (0.0): y_scale='columnwise' divides each output element by "
        "its own sd; drop the column or use y_scale='scalar'"
    ):
        data.SimData(
            t=[0.0, 1.0, 2.0, 3.0],
            y=[[0.0, 1.0], [0.0, 3.0], [0.0, 2.0], [0.0, 5.0]],
            y_scale="columnwise",
        )
