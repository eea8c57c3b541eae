"""gpmsa's public calls under a caller's ``np.seterr(all="raise")``: a rough emulator (betaU
3000: far points' correlations underflow) predicted, its sensitivity, a Calibrator and a
calibration gave FloatingPointError from deep inside; they now give numpy's default state's
numbers, leave the caller's state as it was, and still point their warnings at the caller's
line (`gpmsa._fp_state.underflow_as_zero` is gpmsa's own wrapper: numpy's errstate used as a
decorator adds a numpy frame, where `user_stacklevel`'s walk stopped)."""

import warnings

import numpy as np
import pytest

import gpmsa

pytestmark = pytest.mark.filterwarnings("ignore::gpmsa.GPMSAWarning")


def _rough():
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(30, 1)), rng.uniform(size=(30, 1))
    params = {"betaU": [[3000.0], [3000.0]], "lamUz": [1.0], "lamWs": [2000.0], "lamWOs": [2000.0]}
    sim = gpmsa.SimData(x=x, t=t, y=np.sin(8 * x) + t)
    emu = gpmsa.Emulator.from_params(sim, params)
    return emu, rng.uniform(size=(5, 1)), rng.uniform(size=(5, 1))


def _calls(emu, xs, ts):
    y = np.sin(8 * xs[:2]) + 0.4
    return {
        "predict": lambda: emu.predict(xs, ts),
        "sensitivity": lambda: gpmsa.sensitivity(emu, draws=False, main_effect_grid=5).main,
        "Calibrator": lambda: gpmsa.Calibrator(emu).update(xs[:2], y).grids["t0"].density,
        "calibrate": lambda: gpmsa.calibrate(
            emu, xs[:2], y, n_samples=60, n_burn=20, seed=1, tune=False
        ).samples["t0"],  # fmt: skip
    }


@pytest.mark.parametrize("name", ["predict", "sensitivity", "Calibrator", "calibrate"])
def test_a_rough_emulator_under_raise_gives_the_default_states_numbers(name):
    call = _calls(*_rough())[name]
    default = call()
    with np.errstate(all="raise"):
        raised = call()
        assert np.geterr()["under"] == "raise"  # the caller's state, after the call
    for a, b in zip(np.atleast_1d(default), np.atleast_1d(raised), strict=True):
        np.testing.assert_array_equal(a, b)


def test_a_warning_inside_a_wrapped_call_points_at_the_callers_line():
    emu, xs, ts = _rough()
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        emu.predict(xs + 0.05, ts, extrapolate=True)  # beyond the design: a warning
    assert seen and {w.filename for w in seen} == {__file__}


def test_no_library_function_uses_numpys_errstate_as_a_decorator():
    """(Its frame is numpy's: a warning raised beneath it pointed at numpy's _ufunc_config.py.)"""
    import ast
    from pathlib import Path

    root = Path(gpmsa.__file__).parents[1]
    found = []
    for package in ("gpmsa", "control", "roadgen", "vehicle"):
        for path in sorted((root / package).rglob("*.py")):
            for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
                if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                    found += [f"{path.name}:{node.name}" for d in node.decorator_list
                              if "errstate" in ast.unparse(d)]  # fmt: skip
    assert found == []
