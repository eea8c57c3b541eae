"""What fit's inputs mean: pandas rows are paired as labelled, a pandas column keeps its name,
an emulator's data-corrected priors are not reused for other data, and a number too large for
float64 is named."""

import numpy as np
import pandas as pd
import pytest

import gpmsa
from gpmsa.errors import GPMSAError


def frame(m: int = 14, seed: int = 0) -> pd.DataFrame:
    rng = np.random.default_rng(seed)
    df = pd.DataFrame({"a": rng.uniform(0, 1, m), "b": rng.uniform(0, 1, m)})
    df["out"] = np.sin(3 * df["a"]) + df["b"] ** 2
    return df


def functional(m: int = 16, seed: int = 0) -> gpmsa.SimData:
    rng = np.random.default_rng(seed)
    grid = np.linspace(0, 1, 12)
    x, t = rng.uniform(0, 1, (m, 1)), rng.uniform(0, 1, (m, 1))
    y = np.sin(2 * np.pi * grid * (1 + 0.5 * x)) * (1 + t)
    return gpmsa.SimData(x, t, y, index=grid)


PARAMS = {"betaU": [[2.0], [1.0]], "lamUz": [1.0], "lamWs": [1e4], "lamWOs": [1e4]}
THREE = {"betaU": np.ones((2, 3)), "lamUz": np.ones(3), "lamWs": np.full(3, 1e4), "lamWOs": [1e4]}


# --- pandas rows --------------------------------------------------------------------------------
def test_sim_outputs_in_another_row_order_are_refused_not_mispaired():
    df = frame()
    shuffled = df.sort_values("out")  # the same runs, rows in another order
    for y in (shuffled["out"], shuffled[["out"]]):
        with pytest.raises(GPMSAError, match=r"x and y are pandas objects whose row labels differ"):
            gpmsa.SimData(df[["a"]], df[["b"]], y)
    with pytest.raises(GPMSAError, match=r"x and t are pandas .*t\.loc\[x\.index\]"):
        gpmsa.SimData(df["a"], shuffled["b"], df["out"])
    aligned = gpmsa.SimData(df[["a"]], df[["b"]], shuffled["out"].loc[df.index])
    assert np.array_equal(aligned.y[:, 0], df["out"].to_numpy())


def test_pandas_inputs_with_the_same_rows_or_with_numpy_are_taken_by_position():
    df = frame()
    data = gpmsa.SimData(df[["a"]], df[["b"]].to_numpy(), df["out"])
    assert np.array_equal(data.y[:, 0], df["out"].to_numpy())
    one = df.iloc[[3]]  # a single row pairs with anything
    assert gpmsa.ObsData(one[["a"]], pd.DataFrame({"out": [1.0]}, index=[9])).n == 1


def test_obs_outputs_in_another_row_order_are_refused():
    df = frame()
    with pytest.raises(GPMSAError, match=r"x_obs and y_obs are pandas objects whose row labels"):
        gpmsa.ObsData(df[["a"]], df.sort_values("out")[["out"]])


def test_predict_refuses_x_and_t_tables_in_different_row_orders():
    df = frame()
    emu = gpmsa.Emulator.from_params(gpmsa.SimData(df[["a"]], df[["b"]], df["out"]), PARAMS)
    test = df.iloc[2:8]
    with pytest.raises(GPMSAError, match=r"x and t are pandas objects whose row labels differ"):
        emu.predict(test[["a"]], test[["b"]].iloc[::-1])
    mean, _ = emu.predict(test[["a"]], test[["b"]])
    ref, _ = emu.predict(test[["a"]].to_numpy(), test[["b"]].to_numpy())
    assert np.array_equal(mean, ref)


def test_emulator_prediction_refuses_x_and_t_tables_in_different_row_orders():
    df = frame()
    emu = gpmsa.Emulator.from_params(gpmsa.SimData(df[["a"]], df[["b"]], df["out"]), PARAMS)
    test = df.iloc[2:8]
    with pytest.raises(GPMSAError, match=r"x and t are pandas objects whose row labels differ"):
        gpmsa.emulator_prediction(emu, test[["a"]], test[["b"]].iloc[::-1], draws=False, seed=1)
    pred = gpmsa.emulator_prediction(emu, test[["a"]], test[["b"]], draws=False, seed=1)
    ref = gpmsa.emulator_prediction(
        emu, test[["a"]].to_numpy(), test[["b"]].to_numpy(), draws=False, seed=1
    )
    assert np.array_equal(pred.y, ref.y)


# --- a pandas column's name ---------------------------------------------------------------------
def test_a_pandas_column_names_its_input_and_predict_takes_that_column():
    df = frame()
    data = gpmsa.SimData(df["a"], df["b"], df["out"])
    assert (data.x_names, data.t_names, data.y_names) == (("a",), ("b",), ("out",))
    emu = gpmsa.Emulator.from_params(data, PARAMS)
    test = df.iloc[2:8]
    by_column, _ = emu.predict(test["a"], test["b"])  # refused before: named 'a', not 'x0'
    by_array, _ = emu.predict(test[["a"]].to_numpy(), test[["b"]].to_numpy())
    assert np.array_equal(by_column, by_array)
    given = gpmsa.SimData(df["a"], df["b"], df["out"], x_names=["speed"])
    assert given.x_names == ("speed",)  # an explicit name wins over the column's


# --- priors of an earlier fit -------------------------------------------------------------------
def test_an_emulators_corrected_priors_are_refused_for_a_new_fit():
    emu = gpmsa.Emulator.from_params(functional(), THREE, n_pc=3)
    assert emu.priors.corrected and emu.priors.lamWOs.a > 5.0  # (l_sim - p_u) m / 2 added
    more = functional(m=24, seed=1)
    with pytest.raises(GPMSAError, match=r"priors are already data-corrected .*corrected=False"):
        gpmsa.fit(more, n_iter=5, tune=False, n_pc=3, priors=emu.priors)
    fresh = gpmsa.Emulator.from_params(more, THREE, n_pc=3)
    # the base prior plus this data's correction: a = 5 + (12 - 3) * 24 / 2
    assert fresh.priors.lamWOs.a == pytest.approx(5.0 + 9 * 24 / 2, rel=1e-12)


# --- numbers too large for float64 --------------------------------------------------------------
def test_an_integer_beyond_float64_is_named():
    df = frame()
    x = df[["a"]].to_numpy().tolist()
    x[0][0] = 10**400
    with pytest.raises(GPMSAError, match=r"x holds a number too large for float64"):
        gpmsa.SimData(x, df[["b"]], df["out"])


def test_a_table_with_integer_column_labels_is_read_by_those_labels():
    """pd.DataFrame(array) labels its columns 0, 1, ...: they name the inputs "0", "1", and a
    table labelled so is read by them again (not a KeyError from pandas)."""
    df = frame()
    x, t = pd.DataFrame(df[["a"]].to_numpy()), pd.DataFrame({1: df["b"].to_numpy()})
    data = gpmsa.SimData(x, t, df["out"])
    assert data.x_names == ("0",) and data.t_names == ("1",)
    again = gpmsa.SimData(x, t, df["out"], x_names=["0"], t_names=["1"])
    assert again.t_names == ("1",) and np.array_equal(again.t, t.to_numpy())
    emu = gpmsa.Emulator.from_params(data, PARAMS)
    mean, _ = emu.predict(x.iloc[:3], t.iloc[:3])
    assert np.allclose(mean, emu.predict(x.to_numpy()[:3], t.to_numpy()[:3])[0])
