"""Exact input checks of gpmsa.model.data that mutation testing found untested (s89): each
test gives one input and the exact message or array expected."""

import hashlib
import re

import numpy as np
import pytest

from gpmsa.errors import GPMSAError
from gpmsa.model import data


def _raises(message: str):
    return pytest.raises(GPMSAError, match=f"^{re.escape(message)}$")


def test_as_real_refuses_an_array_of_two_numbers():
    with _raises("y_sd must be a single number, got array([1., 2.])"):
        data.as_real(np.array([1.0, 2.0]), "y_sd")
    assert data.as_real(np.float32(0.5), "y_sd") == 0.5


def test_as_matrix_reads_ncols_entries_as_one_row_and_others_as_a_column():
    np.testing.assert_array_equal(data.as_matrix([1.0, 2.0], "x", ncols=2), [[1.0, 2.0]])
    np.testing.assert_array_equal(data.as_matrix([3.0], "x", ncols=1), [[3.0]])
    with _raises("x must have 2 columns, got shape (3,)"):
        data.as_matrix([1.0, 2.0, 3.0], "x", ncols=2)


def test_as_matrix_refuses_no_rows_and_three_dimensions():
    with _raises("t must be a non-empty 2-D array (rows x columns), got shape (0, 2)"):
        data.as_matrix(np.empty((0, 2)), "t")
    with _raises("y must be a non-empty 2-D array (rows x columns), got shape (2, 2, 2)"):
        data.as_matrix(np.zeros((2, 2, 2)), "y")
    with _raises("x must be a non-empty 2-D array (rows x columns), got shape (3, 0)"):
        data.as_matrix(np.empty((3, 0)), "x")
    assert data.as_matrix(np.empty((3, 0)), "x", no_columns=True).shape == (3, 0)


@pytest.mark.parametrize("level", [0.0, 1.0, 2.0, -0.5])
def test_check_level_refuses_the_ends_and_outside(level):
    with _raises(f"level must be a number in (0, 1), got {level!r}"):
        data.check_level(level)


def test_check_level_takes_a_numpy_float_inside():
    assert data.check_level(np.float64(0.9)) == 0.9


def test_check_seed_takes_the_last_integer_below_2_128_and_refuses_2_128():
    assert data.check_seed(2**128 - 1) == 2**128 - 1
    assert data.check_seed(np.uint8(0)) == 0
    with _raises(f"seed={2**128} is out of range: allowed integers in [0, 2**128)"):
        data.check_seed(2**128)
    with _raises("seed=-1 is out of range: allowed integers in [0, 2**128)"):
        data.check_seed(-1)


def test_check_seed_refuses_a_string_a_bool_and_a_generator_unless_allowed():
    with _raises("seed must be None or an integer, got '1' (str)"):
        data.check_seed("1")
    with _raises("rng must be None, an integer or a numpy Generator, got True (bool)"):
        data.check_seed(True, "rng", generator=True)
    gen = np.random.default_rng(0)
    assert data.check_seed(gen, generator=True) is gen
    with _raises(f"seed must be None or an integer, got {gen!r} (Generator)"):
        data.check_seed(gen)


def test_output_scale_centres_before_scaling_exactly():
    # centred [-1, 0, 1]: sd exactly 1 (an uncentred 2e6 + ... loses digits: 1.000000000004)
    y = np.array([[0.0], [1.0], [2.0]]) + 1e6
    assert data.output_scale(y) == 1.0


def test_output_scale_refuses_a_spread_whose_square_overflows():
    y = np.array([[0.0], [1e160], [2e160]])
    with _raises(
        "y is too large to standardise: its spread overflows float64 (largest |y| = 2e+160); "
        "rescale y (e.g. other units)"
    ):
        data.output_scale(y)


def test_output_scale_names_zero_spread_not_underflow():
    with _raises("y has zero spread after centring each column; the output must vary"):
        data.output_scale(np.full((3, 2), 5.0))


def test_column_scales_each_columns_sd_exactly():
    y = np.array([[0.0, 0.0], [1.0, 2.0], [2.0, 4.0]])  # sd (ddof=1) 1 and 2
    np.testing.assert_array_equal(data.column_scales(y, ("a", "b")), [1.0, 2.0])
    y = np.array([[0.0, 0.0], [0.5, 2.0], [1.0, 4.0]])  # a span of exactly 1 is not constant
    np.testing.assert_array_equal(data.column_scales(y, ("a", "b")), [0.5, 2.0])


def test_column_scales_names_a_constant_column():
    y = np.array([[0.0, 2.0], [1.0, 2.0], [2.0, 2.0]])
    with _raises(
        "y column 'b' is constant (2.0): y_scale='columnwise' divides each output element by "
        "its own sd; drop the column or use y_scale='scalar'"
    ):
        data.column_scales(y, ("a", "b"))


def test_column_scales_checks_each_columns_resolution():
    # 2**30 + (0, 1, 2) 2**-20, exact in float64: sd 2**-20 within 1e-13 of 2**30
    y = np.column_stack([[0.0, 1.0, 2.0], 2.0**30 + np.array([0.0, 1.0, 2.0]) * 2.0**-20])
    with _raises(
        "y column 'b': y varies by only sd 9.54e-07 around values up to 1.07374e+09 (within "
        "1e-13 of their size, near float64's resolution there: 3 distinct values in 3); "
        "subtract the offset before the values are rounded (in the simulator or its output "
        "file), or rescale y"
    ):
        data.column_scales(y, ("a", "b"))


def test_given_scale_names_the_first_non_positive_element_of_a_y_sd_array():
    y = np.array([[0.0, 1.0], [1.0, 3.0], [2.0, 2.0]])
    with _raises("y_sd must be positive, got y_sd[1] = -2.0"):
        data._given_scale(None, np.array([1.0, -2.0]), y)


def test_given_scale_checks_a_given_y_mean_alone_for_overflow():
    y = np.array([[0.0], [1.0], [2.0]])
    with _raises(
        "y standardised by the given y_mean and y_sd overflows float64 (largest |y - y_mean| / "
        "y_sd = 1e+308); give a y_sd of the order of y's spread"
    ):
        data._given_scale(-1e308, None, y)
    assert data._given_scale(None, None, y) == (None, None)


def test_given_scale_centres_each_column_by_its_own_mean():
    y = np.array([[0.0, 10.0], [1.0, 30.0], [2.0, 20.0]])
    assert data._given_scale(None, 2.0, y) == (None, 2.0)


def test_given_scale_refuses_standardised_values_whose_square_overflows():
    y = np.array([[0.0], [1e200]])
    with _raises(
        "y standardised by the given y_mean and y_sd overflows float64 (largest |y - y_mean| / "
        "y_sd = 5e+199); give a y_sd of the order of y's spread"
    ):
        data._given_scale(None, 1.0, y)


def test_label_text_reads_a_number_label_and_refuses_none_and_bytes():
    assert data._label_text(20, 0, "y_names", "name") == "20"
    with _raises("x_names[1] must be a name (a string), got NoneType None"):
        data._label_text(None, 1, "x_names", "name")
    with _raises("x_units[0] must be a unit (a string), got bytes b'm': decode it (.decode())"):
        data._label_text(b"m", 0, "x_units", "unit")


def test_names_hint_for_one_y_name_only():
    with _raises(
        "y_names must have 3 entries, got 1: ('a',) (one name per output value, a functional "
        "output's too: they are the keys by which y_obs tables and `gpmsa calibrate --y` read "
        'it; to name them after one: [f"a{k}" for k in range(3)])'
    ):
        data._names(["a"], 3, "y", "y_names")
    with _raises("y_names must have 3 entries, got 2: ('a', 'b')"):
        data._names(["a", "b"], 3, "y", "y_names")
    with _raises("x_names must have 3 entries, got 1: ('a',)"):
        data._names(["a"], 3, "x", "x_names")


def test_index_labels_checks_names_but_not_units_for_blanks_and_repeats():
    with _raises("index_names must be unique, got ('t', 't')"):
        data._index_labels(["t", "t"], 2, 5, "index_names")
    with _raises("index_names[0] must be a non-empty name, got ' '"):
        data._index_labels(" ", 1, 5, "index_names")
    assert data._index_labels(["", ""], 2, 5, "index_units") == ("", "")
    assert data._index_labels("s", 1, 5, "index_units") == ("s",)


def test_named_index_takes_a_series_name_and_reads_default_labels_by_position():
    pd = pytest.importorskip("pandas")
    named = pd.Series([0.0, 1.0, 2.0], name="time")
    assert data._named_index(named, None) == (named, ("time",))
    unnamed = pd.Series([0.0, 1.0, 2.0])
    assert data._named_index(unnamed, None) == (unnamed, None)
    frame = pd.DataFrame(np.arange(6.0).reshape(3, 2))  # labels 0, 1: no names
    index, names = data._named_index(frame, ["time", "angle"])
    assert index is frame and names == ["time", "angle"]
    arr = np.arange(3.0)
    assert data._named_index(arr, ["time"]) == (arr, ["time"])


def test_check_spans_refuses_a_column_of_zeros():
    with _raises(
        "design column x[:, 0] is constant (0.0); every input must vary (a dummy x, as SEPIA's "
        "0.5 for a simulator without known inputs: leave x out, SimData(t=..., y=...))"
    ):
        data._check_spans(np.zeros((3, 1)), "x", None)
    with _raises("design column b is constant (0.0); every input must vary"):
        data._check_spans(np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]]), "t", ("a", "b"))


def test_ranges_takes_one_columns_min_max_alone():
    arr = np.array([[0.0], [1.0], [2.0]])
    assert data._ranges([0.0, 2.0], arr, ("a",), (), "x_range") == ((0.0, 2.0),)


def test_check_rank_refuses_two_collinear_columns():
    t = np.array([[0.0, 1.0], [1.0, 3.0], [2.0, 5.0], [3.0, 7.0]])  # t1 = 2 t0 + 1
    with _raises(
        "the design columns t0, t1 are linearly dependent (one is a linear function of the "
        "others across all runs): the runs lie on a lower-dimensional part of the input box, "
        "so the emulator cannot tell these inputs' effects apart and would extrapolate over "
        "the rest; drop one of them (calibrate their combination) or spread the design"
    ):
        data._check_rank(np.empty((4, 0)), t, (), ("t0", "t1"))
    data._check_rank(np.empty((4, 0)), t[:, :1], (), ("t0",))


_DEPENDENT = (
    "the design columns t0, t1 are linearly dependent (one is a linear function of the "
    "others across all runs): the runs lie on a lower-dimensional part of the input box, so "
    "the emulator cannot tell these inputs' effects apart and would extrapolate over the "
    "rest; drop one of them (calibrate their combination) or spread the design"
)


def test_check_rank_centres_the_unit_columns():
    # t1 = -t0: on the unit scale u1 = 1 - u0, dependent only once centred
    t = np.array([[0.0, 0.0], [1.0, -1.0], [2.0, -2.0], [3.0, -3.0]])
    with _raises(_DEPENDENT):
        data._check_rank(np.empty((4, 0)), t, (), ("t0", "t1"))


def test_check_rank_refuses_a_nearly_dependent_pair():
    t0 = np.array([0.0, 1.0, 2.0, 3.0])
    t = np.column_stack([t0, t0 + np.array([0.0, 1e-10, 0.0, -1e-10])])
    with _raises(_DEPENDENT):
        data._check_rank(np.empty((4, 0)), t, (), ("t0", "t1"))


def test_check_rank_takes_columns_around_zero():
    t = np.array([[-1.0, 1.0], [0.0, -1.0], [1.0, 0.0], [0.5, 0.5]])
    assert data._check_rank(np.empty((4, 0)), t, (), ("t0", "t1")) is None


def test_simdata_refuses_a_dependent_design():
    t = np.array([[0.0, 0.0], [1.0, -1.0], [2.0, -2.0], [3.0, -3.0]])
    with _raises(_DEPENDENT):
        data.SimData(t=t, y=[0.0, 1.0, 4.0, 9.0])


def test_simdata_refuses_index_names_for_a_scalar_output():
    with _raises(
        "index_names labels the output index, but y has one column (a scalar output has no "
        "index); leave index_names out"
    ):
        data.SimData(t=[0.0, 1.0, 2.0], y=[0.0, 1.0, 3.0], index_names="s")


def test_as_float_names_a_value_numpy_cannot_read():
    class Unreadable:
        def __array__(self, *args, **kwargs):
            raise RuntimeError("device lost")

    with _raises("x cannot be converted to numbers: device lost"):
        data.as_float(Unreadable(), "x")


def test_units_hint_for_one_y_unit_only():
    with _raises(
        "y_units must have 3 entries, got 1: ('m',) (one per output value, on a functional "
        "output's grid too: ['m'] * 3)"
    ):
        data._units(["m"], 3, "y_units")
    with _raises("x_units must have 3 entries, got 1: ('m',)"):
        data._units(["m"], 3, "x_units")


def test_index_labels_count_message_gives_the_index_shape():
    with _raises(
        "index_names must have 1 entries, one per column of the output index (5,), got 2: "
        "('a', 'b')"
    ):
        data._index_labels(["a", "b"], 1, 5, "index_names")
    with _raises(
        "index_units must have 2 entries, one per column of the output index (5, 2), got 1: ('s',)"
    ):
        data._index_labels(["s"], 2, 5, "index_units")


def test_named_index_refuses_a_series_of_another_name():
    pd = pytest.importorskip("pandas")
    series = pd.Series([0.0, 1.0, 2.0], name="time")
    with _raises(
        "index is a pandas Series named 'time', but index_names gives ('angle',): leave "
        "index_names out to take the Series' name, or give that name"
    ):
        data._named_index(series, "angle")
    assert data._named_index(series, "time") == (series, "time")


def test_range_table_reads_inputs_by_column_or_row_labels():
    pd = pytest.importorskip("pandas")
    by_columns = pd.DataFrame({"b": [0.0, 2.0], "a": [1.0, 3.0]})  # SEPIA's (2, d) layout
    got = data._range_table(by_columns, ("a", "b"), "x_range")
    assert list(got) == ["b", "a"]
    np.testing.assert_array_equal(got["b"], [0.0, 2.0])
    np.testing.assert_array_equal(got["a"], [1.0, 3.0])
    by_rows = pd.DataFrame([[0.0, 2.0], [1.0, 3.0]], index=["b", "a"], columns=["lo", "hi"])
    got = data._range_table(by_rows, ("a", "b"), "x_range")
    np.testing.assert_array_equal(got["b"], [0.0, 2.0])
    np.testing.assert_array_equal(got["a"], [1.0, 3.0])
    unnamed = pd.DataFrame([[0.0, 2.0], [1.0, 3.0]])
    assert data._range_table(unnamed, ("a", "b"), "x_range") is unnamed
    twice = pd.DataFrame([[0.0, 1.0], [2.0, 3.0]], columns=["a", "a"])
    with _raises("x_range names an input twice: ['a', 'a']"):
        data._range_table(twice, ("a", "b"), "x_range")


def test_obsdata_takes_one_array_of_points_for_every_experiment():
    points = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    obs = data.ObsData(x=[[0.5], [0.7]], y=[[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]], index=points)
    assert len(obs.grids) == 2
    for grid in obs.grids:
        np.testing.assert_array_equal(grid, points)


def test_a_list_holding_itself_is_refused_not_walked_forever():
    looped = [1.0]
    looped.append(looped)
    assert data.tensor_values(looped) is looped
    with _raises(
        "x must be a numeric array, got a ragged list: its entries have lengths [1, 2] (every "
        "row needs the same number of values)"
    ):
        data.as_float(looped, "x")


def test_text_hint_names_a_series_row():
    pd = pytest.importorskip("pandas")
    assert data._text_hint(pd.Series(["1", "n/a"], index=["r1", "r2"])) == (
        "; the first that is not a number: 'n/a' at row 'r2' (a missing-value mark or a unit? "
        "Read the file with pd.read_csv(..., na_values=['n/a']) and drop or fill those rows)"
    )


def test_columns_hint_select_only_for_a_strict_superset():
    assert (
        data._columns_hint(["a", "b", "c"], ["a", "b"])
        == " (select the columns: table[['a', 'b']])"
    )
    assert data._columns_hint(["a", "b", "b"], ["a", "b"]) == ""


def test_run_seed_draws_from_a_generator():
    expected = int(np.random.default_rng(0).integers(2**63))
    assert data.run_seed(np.random.default_rng(0)) == expected
    assert data.run_seed(7) == 7


def test_span_writes_zero_without_sign_and_four_digits():
    assert data._span(np.array([-0.0, 1.0])) == "[0, 1]"
    assert data._span(np.array([1.23456, 2.0])) == "[1.235, 2]"


def test_columns_text_none_and_more():
    assert data._columns_text(np.empty((3, 0)), ()) == "none"
    assert data._columns_text(np.arange(21.0).reshape(3, 7), tuple("abcdefg")) == (
        "a [0, 14], b [1, 15], c [2, 16], d [3, 17], e [4, 18], f [5, 19], ... (1 more)"
    )
    assert data._columns_text(np.arange(18.0).reshape(3, 6), tuple("abcdef")) == (
        "a [0, 12], b [1, 13], c [2, 14], d [3, 15], e [4, 16], f [5, 17]"
    )


def test_by_index_names_orders_named_columns_and_keeps_unnamed():
    pd = pytest.importorskip("pandas")
    named = pd.DataFrame({"angle": [1.0, 2.0], "time": [0.0, 3.0]})
    got = data.by_index_names(named, ("time", "angle"), "grid")
    assert list(got.columns) == ["time", "angle"]
    unnamed = pd.DataFrame([[1.0, 2.0], [0.0, 3.0]])
    assert data.by_index_names(unnamed, ("time", "angle"), "grid") is unnamed


def test_index_tables_labels_only_where_a_table_names_columns():
    pd = pytest.importorskip("pandas")
    arr = np.arange(3.0)
    assert data._index_tables(arr, 2) == (arr, None)
    frame = pd.DataFrame({"time": [0.0, 1.0], "angle": [1.0, 2.0]})
    index, labels = data._index_tables([np.arange(2.0), frame], 2)
    assert labels == (None, ("time", "angle"))
    np.testing.assert_array_equal(index[1], [[0.0, 1.0], [1.0, 2.0]])


def test_multi_column_index_sepia_hint_only_for_d_by_l():
    assert data.multi_column_index("index", (3, 4), 5) == (
        "index must be one output grid (5,) or one point per output value (5, d), got shape (3, 4)"
    )
    assert data.multi_column_index("index", (2, 5), 5) == (
        "index must be one output grid (5,) or one point per output value (5, d), got shape "
        "(2, 5); SEPIA's (d, l) layout: pass its transpose"
    )
    assert data.multi_column_index("index", (2, 5, 3), 5).endswith("got shape (2, 5, 3)")


def test_ranges_hints_at_sepias_mins_then_maxs_layout():
    arr = np.array([[0.0, -6.0], [1.0, -5.0], [0.5, -5.5]])  # a in [0, 1], b in [-6, -5]
    with _raises(
        "x_range[a] = (0.0, -6.0) must be finite numbers with min < max (SEPIA's (2, 2) "
        "layout, mins then maxs? transpose it)"
    ):
        data._ranges(np.array([[0.0, -6.0], [1.0, -5.0]]), arr, ("a", "b"), (), "x_range")


def test_arrays_digest_hashes_each_arrays_number_and_shape():
    arr = np.array([[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]])
    expected = hashlib.sha256(b"0:(2, 3)" + arr.astype("<f8").tobytes() + b"tail").hexdigest()
    assert data._arrays_digest([arr], "tail") == expected
    assert data._arrays_digest([arr]) != data._arrays_digest([arr.reshape(3, 2)])


def test_obsdata_digest_covers_the_precisions():
    plain = data.ObsData(x=[[0.5]], y=[[1.0, 2.0]])
    weighted = data.ObsData(x=[[0.5]], y=[[1.0, 2.0]], precision=4.0)
    assert plain.digest() != weighted.digest()


def test_obsdata_output_grids_reads_named_point_columns_by_the_simulation_names():
    pd = pytest.importorskip("pandas")
    frame = pd.DataFrame({"angle": [0.0, 0.0, 1.0], "time": [0.0, 1.0, 0.0]})
    obs = data.ObsData(x=[[0.5]], y=[[1.0, 2.0, 3.0]], index=frame)
    np.testing.assert_array_equal(obs.output_grids()[0], frame.to_numpy())
    got = obs.output_grids(("time", "angle"))[0]
    np.testing.assert_array_equal(got, [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])


def test_obsdata_repr_gives_one_length_or_a_span_of_lengths():
    even = data.ObsData(x=[[0.5], [0.7]], y=[[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]])
    assert repr(even) == (
        "ObsData(2 experiments; x: x_obs[:, 0] [0.5, 0.7]; y: 3 value(s) each [1, 6])"
    )
    ragged = data.ObsData(x=[[0.5], [0.7]], y=[np.array([1.0, 2.0, 3.0]), np.array([4.0, 5.0])])
    assert repr(ragged) == (
        "ObsData(2 experiments; x: x_obs[:, 0] [0.5, 0.7]; y: 2 to 3 value(s) each [1, 5])"
    )


def test_obsdata_precision_vector_must_be_positive():
    with _raises("precision[0] must be positive, got [1.0, 0.0]"):
        data.ObsData(x=[[0.5]], y=[[1.0, 2.0]], precision=[np.array([1.0, 0.0])])
    obs = data.ObsData(x=[[0.5]], y=[[1.0, 2.0]], precision=[np.array([0.5, 2.0])])
    np.testing.assert_array_equal(obs.precisions[0], [[0.5, 0.0], [0.0, 2.0]])


def test_obsdata_output_grids_keeps_an_unlabelled_experiments_points():
    pd = pytest.importorskip("pandas")
    points = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    frame = pd.DataFrame({"angle": [0.0, 0.0, 1.0], "time": [0.0, 1.0, 0.0]})
    obs = data.ObsData(
        x=[[0.5], [0.7]], y=[[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]], index=[points, frame]
    )
    first, second = obs.output_grids(("time", "angle"))
    np.testing.assert_array_equal(first, points)
    np.testing.assert_array_equal(second, [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])


@pytest.mark.parametrize("level", ["0.5", True, None])
def test_check_level_refuses_what_is_no_number(level):
    with _raises(f"level must be a number in (0, 1), got {level!r}"):
        data.check_level(level)


def test_check_rank_names_only_the_dependent_columns():
    a, b = np.array([0.0, 1.0, 2.0, 3.0, 4.0]), np.array([1.0, 0.0, 3.0, 2.0, 4.0])
    with _raises(_DEPENDENT.replace("t0, t1", "a, c")):
        data._check_rank(np.empty((5, 0)), np.column_stack([a, b, -a]), (), ("a", "b", "c"))


def test_obsdata_precision_of_another_length_is_refused():
    with _raises("precision[0] must be a scalar, (2,) or (2, 2), got (3,)"):
        data.ObsData(x=[[0.5]], y=[[1.0, 2.0]], precision=[np.ones(3)])


def test_as_float_refuses_an_empty_bool_array():
    with _raises(
        "x must be a numeric array, got bool values (text, bools, dates and None are not converted)"
    ):
        data.as_float(np.array([], dtype=bool), "x")


class _Device:
    type = "cuda"

    def __str__(self) -> str:
        return "cuda:0"


class _Tensor:  # what _device_hint reads of a torch tensor: requires_grad and device
    requires_grad = False
    device = _Device()


class _NotATensor:
    device = _Device()


def test_device_hint_for_a_nested_tensor_on_another_device_only():
    assert data._device_hint([[_Tensor()]]) == (
        " (a torch tensor on device 'cuda:0': numpy reads tensors on the CPU only; bring its "
        "values there, e.g. a GPU's by tensor.cpu(), or tensor.detach().cpu() where it records "
        "gradients)"
    )
    assert data._device_hint(_NotATensor()) == ""
    assert data._device_hint([]) == ""


def test_kind_of_names_ragged_lists_with_at_most_eight_lengths():
    assert data._kind_of([[1, 2], [3, 4]]) == "list"
    head = "a ragged list: its entries have lengths [1, 2, 1, 1, 1, 1, 1, 1"
    tail = "] (every row needs the same number of values)"
    assert data._kind_of([[1], [1, 2]] + [[1]] * 6) == head + tail
    assert data._kind_of([[1], [1, 2]] + [[1]] * 7) == head + ", ..." + tail


def test_array_text_uses_numpys_own_defaults():
    with np.printoptions(precision=2, suppress=True):
        assert data.array_text(np.array([1 / 3])) == "[0.33333333]"
        assert data.array_text(np.array([1e-9, 1.0])) == "[1.e-09 1.e+00]"


def test_repr_names_cuts_long_names_and_counts_the_rest():
    assert data.repr_names(["a" * 41, "b", "c"], 2) == f"['{'a' * 37}...', 'b', +1 more]"
    assert data.repr_names(["a", "b"], 2) == "['a', 'b']"


def test_label_text_refuses_a_bool_and_reads_a_multiindex_tuple():
    with _raises("x_names[0] must be a name (a string), got bool True"):
        data._label_text(True, 0, "x_names", "name")
    assert data._label_text(("a", 1), 0, "y_names", "name") == "('a', 1)"


def test_index_tables_one_labelled_column_names_nothing():
    pd = pytest.importorskip("pandas")
    index, labels = data._index_tables(pd.DataFrame({"time": [0.0, 1.0]}), 1)
    assert labels is None
    np.testing.assert_array_equal(index, [[0.0], [1.0]])


def test_ranges_no_sepia_hint_for_a_row_layout_range():
    arr = np.array([[0.0, 0.0], [1.0, 1.0], [0.5, 0.5]])
    with _raises(
        "design column a spans [0, 1], outside its x_range [0, 0.5]: the range must hold every run"
    ):
        data._ranges(np.array([[0.0, 0.5], [0.0, 1.0]]), arr, ("a", "b"), (), "x_range")
