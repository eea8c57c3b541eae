"""Odd but legitimate data sets: runs that are all the same output, and observations holding
one value far outside every simulation run (a missing-value code such as -999).

A functional observation's values beyond the emulator's basis estimate the observation error
(GPM/SA's lamOs correction), so one value of -999 among 36 inflated that estimate and the
outside-the-emulator check read the data 1.5 predictive sds away: no warning, and theta's
posterior fell from 0.500 +- 0.017 to its prior (0.50 +- 0.29). Such a value is now named in
an ``OutsideEmulatorWarning``; so is the farthest value where the check already warns.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

import gpmsa
from gpmsa import GPMSAError
from gpmsa.fitting.emulator import Emulator
from tests.gpmsa._far_cases import GRID
from tests.gpmsa._far_cases import design as _design
from tests.gpmsa._far_cases import functional as _functional
from tests.gpmsa._far_cases import outside_texts as _outside


@pytest.fixture(scope="module")
def functional_emulator() -> Emulator:
    x, t = _design()
    sim = gpmsa.SimData(x=x, t=t, y=_functional(x, t), index=GRID, x_names=["v"],
                        t_names=["k"], index_names="time", index_units="s")  # fmt: skip
    params = {"betaU": [[1.0, 1.0], [1.5, 1.5]], "lamUz": [1.0, 1.0],
              "lamWs": [2000.0, 2000.0], "lamWOs": [2000.0]}  # fmt: skip
    return Emulator.from_params(sim, params, n_pc=2)


@pytest.fixture(scope="module")
def scalar_emulator() -> Emulator:
    x, t = _design()
    sim = gpmsa.SimData(x=x, t=t, y=np.sin(3 * x) + t**2, x_names=["v"], t_names=["k"])
    params = {"betaU": [[1.0], [1.5]], "lamUz": [1.0], "lamWs": [2000.0], "lamWOs": [2000.0]}
    return Emulator.from_params(sim, params)


def _observed() -> tuple[np.ndarray, np.ndarray]:
    """Three experiments at k = 0.5 with noise of sd 0.02 (the outputs' sd is about 0.7)."""
    x = np.array([[0.2], [0.4], [0.7]])
    noise = 0.02 * np.random.default_rng(0).standard_normal((3, GRID.size))
    return x, _functional(x[:, 0], np.full(3, 0.5)) + noise


# --- runs that are all the same output --------------------------------------------------------


def test_functional_output_the_same_in_every_run_is_refused_by_name():
    """Each output element constant over the runs, the output varying along its index only:
    numpy's "zero-size array to reduction operation maximum" before."""
    x, t = _design(10)
    y = np.tile(np.sin(GRID), (10, 1))  # its mean over the runs rounds: not exactly zero spread
    with pytest.raises(GPMSAError, match=r"y is the same in every run \(10 runs of 12 output"):
        gpmsa.SimData(x=x, t=t, y=y, index=GRID)
    with pytest.raises(GPMSAError, match="y is the same in every run"):
        gpmsa.SimData(x=x, t=t, y=np.tile([1.0, 2.0, 4.0], (10, 1)))  # the mean is exact


def test_one_constant_output_element_is_still_accepted():
    x, t = _design(10)
    y = _functional(x, t)
    y[:, 0] = 2.0
    assert gpmsa.SimData(x=x, t=t, y=y, index=GRID).l_sim == GRID.size


# --- one observed value far outside every run -------------------------------------------------


def test_clean_functional_observations_do_not_warn(functional_emulator):
    x, y = _observed()
    texts, post = _outside(lambda: gpmsa.Calibrator(functional_emulator).update(x, y))
    assert texts == []
    assert abs(post.mean("k") - 0.5) < 0.05 and post.sd("k") < 0.05


@pytest.mark.parametrize("how", ["Calibrator", "calibrate", "ObsData"])
def test_missing_value_code_in_a_functional_observation_is_named(functional_emulator, how):
    x, y = _observed()
    y[1, 5] = -999.0  # a logger's missing-value code
    emu = functional_emulator
    if how == "Calibrator":
        call = lambda: gpmsa.Calibrator(emu).update(x, y)  # noqa: E731
    elif how == "calibrate":
        call = lambda: gpmsa.calibrate(emu, x, y, n_samples=200, n_burn=50, seed=0)  # noqa: E731
    else:  # on its own grid: every other point, the value at time 0.4545 kept
        obs = gpmsa.ObsData(x=x, y=y[:, 1::2], index=GRID[1::2])
        call = lambda: gpmsa.Calibrator(emu).update(obs)  # noqa: E731
    texts, post = _outside(call)
    assert post.info["outside_sds"] < 5  # the predictive check alone reads it inside
    assert len(texts) == 1
    assert re.search(
        r"y_obs\[1\] holds -999 at time 0\.4545\d* s, 1\.\d+e\+03 sds of the simulation "
        r"outputs below every simulation run's value there \(\[-?\d\.\d+, \d\.\d+\]\)",
        texts[0],
    ), texts[0]
    assert "missing-value code" in texts[0] and "lamOs" in texts[0]


def test_a_value_a_little_outside_the_runs_is_not_named(functional_emulator):
    """Noise can put a value beyond every run: only more than 5 of the outputs' sds is named."""
    x, y = _observed()
    emu = functional_emulator
    top = float(emu.y[:, 5].max())
    y[1, 5] = top + 3.0 * emu.standardizer.y_sd  # 3 sds above every run
    texts, _ = _outside(lambda: gpmsa.Calibrator(emu).update(x, y))
    assert texts == []


def test_the_outside_warning_names_the_farthest_scalar_value(scalar_emulator):
    """Ten experiments, one of them 100 (the outputs span about [-1, 2]): the predictive
    check's warning says which."""
    x = np.linspace(0.05, 0.95, 10)[:, None]
    y = np.sin(3 * x) + 0.25
    y[6] = 100.0
    texts, post = _outside(lambda: gpmsa.Calibrator(scalar_emulator).update(x, y))
    assert len(texts) == 1 and post.info["outside_sds"] > 5
    assert texts[0].startswith("y_obs lies ")
    assert re.search(r"The farthest value: y_obs\[6\] = 100, \d+ sds of the simulation outputs "
                     r"above every simulation run's value \(\[", texts[0]), texts[0]  # fmt: skip


def test_study_names_the_model_and_the_value(functional_emulator):
    x, y = _observed()
    y[2, 0] = 999.0
    emulators = [functional_emulator, functional_emulator]
    texts, _ = _outside(
        lambda: gpmsa.calibrate_study(
            emulators, [x, x], [_observed()[1], y], labels=["a", "b"], n_samples=60, n_burn=10
        )
    )
    assert len(texts) == 1
    assert texts[0].startswith("model 'b': y_obs[2] holds 999 at time 0 s"), texts[0]


# --- units, array layouts and the fewest runs (held as they are) ------------------------------


def test_the_fewest_runs_and_one_fewer():
    x, t = _design(4)
    assert gpmsa.SimData(x=x, t=t, y=np.sin(3 * x) + t).m == 4  # p + q + 2
    with pytest.raises(GPMSAError, match=r"p \+ q \+ 2 = 4 simulation runs for 2 inputs, got 3"):
        gpmsa.SimData(x=x[:3], t=t[:3], y=x[:3] + t[:3])
    with pytest.raises(GPMSAError, match=r"= 3 simulation runs for 1 input, got 2"):
        gpmsa.SimData(t=[0.0, 1.0], y=[0.0, 1.0])


def test_extreme_units_scale_predictions_and_the_calibration_exactly():
    """x in [1e-6, 2e-6], t in [1e5, 1e6], y ~ 1e-9: the unit-scaled problem's numbers, scaled,
    to rounding (the inputs map onto [0, 1] and y is standardised)."""
    x, t = _design()
    y = np.sin(3 * x) + t**2
    params = {"betaU": [[1.0], [1.5]], "lamUz": [1.0], "lamWs": [2000.0], "lamWOs": [2000.0]}
    unit = Emulator.from_params(gpmsa.SimData(x=x, t=t, y=y), params)
    odd = Emulator.from_params(gpmsa.SimData(x=1e-6 + 1e-6 * x, t=1e5 + 9e5 * t, y=1e-9 * y),
                               params)  # fmt: skip
    xs, ts = np.array([[0.3], [0.7]]), np.array([[0.2], [0.9]])
    mean, var = unit.predict(xs, ts)
    mean_odd, var_odd = odd.predict(1e-6 + 1e-6 * xs, 1e5 + 9e5 * ts)
    np.testing.assert_allclose(mean_odd / 1e-9, mean, rtol=1e-12)
    np.testing.assert_allclose(var_odd / 1e-18, var, rtol=1e-12)
    xo = np.array([[0.4], [0.6]])
    yo = np.sin(3 * xo) + 0.25
    a = gpmsa.Calibrator(unit).update(xo, yo)
    b = gpmsa.Calibrator(odd).update(1e-6 + 1e-6 * xo, 1e-9 * yo)
    assert b.mean("t0") == pytest.approx(1e5 + 9e5 * a.mean("t0"), rel=1e-12)
    assert b.sd("t0") == pytest.approx(9e5 * a.sd("t0"), rel=1e-12)


def test_integer_fortran_strided_and_pandas_inputs_make_the_same_emulator():
    """The same values as int64, float32 (exact here), Fortran-ordered, strided or as pandas
    objects with a non-default row index give the float64 C-contiguous model to the bit."""
    pd = pytest.importorskip("pandas")
    rng = np.random.default_rng(2)
    xi, ti = rng.integers(0, 10, 20), rng.integers(100, 200, 20)
    xi[:2], ti[:2] = (0, 9), (100, 199)
    y = np.sin(xi / 3.0) + (ti / 100.0) ** 2
    params = {"betaU": [[1.0], [1.5]], "lamUz": [1.0], "lamWs": [2000.0], "lamWOs": [2000.0]}
    names = {"x_names": ["v"], "t_names": ["GD"], "y_names": ["f"]}

    def sha(x, t, yy) -> str:
        return Emulator.from_params(gpmsa.SimData(x=x, t=t, y=yy, **names), params).model_sha256

    reference = sha(xi.astype(float), ti.astype(float), y)
    table = np.asfortranarray(np.column_stack([xi, ti, y]).astype(float))
    wide = np.zeros((40, 3))
    wide[::2] = table
    frame = pd.DataFrame({"v": xi, "GD": ti, "f": y}, index=np.arange(120, 100, -1))
    assert sha(xi, ti, y) == reference
    assert sha(xi.astype(np.float32), ti.astype(np.float32), y) == reference
    assert sha(table[:, 0], table[:, 1], table[:, 2]) == reference
    assert sha(wide[::2, 0], wide[::2, 1], wide[::2, 2]) == reference
    assert sha(frame["v"], frame["GD"], frame["f"]) == reference
    assert sha(frame[["v"]], frame[["GD"]], frame[["f"]]) == reference
