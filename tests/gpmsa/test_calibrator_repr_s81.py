"""``repr(Calibrator)`` is one short line in the style of the package's other reprs (method,
backend, parameter names, grid size, updates so far), never the default ``<... object at
0x...>``, and never raises."""

import warnings

import numpy as np
from _calib_cases import sine_sum_emulator

import gpmsa


def _emulator(q: int, name: str = "t"):
    """20 runs of one scalar output, q calibration parameters."""
    return sine_sum_emulator(q, runs=20, n_iter=20, prefix=name)


def test_a_grid_calibrator_names_its_method_parameters_grid_and_updates():
    cal = gpmsa.Calibrator(_emulator(1), n_grid=33)
    text = repr(cal)
    assert text == "Calibrator(method=grid, backend=numpy, t=['t0'], grid=33 nodes, updates=0)"
    assert str(cal) == text
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        cal.update(np.array([[0.5]]), np.array([[1.5]]))
    assert repr(cal).endswith("updates=1)"), repr(cal)


def test_two_parameters_show_the_nodes_per_axis():
    text = repr(gpmsa.Calibrator(_emulator(2), n_grid=9))
    assert "t=['t0', 't1']" in text and "grid=9x9 nodes" in text, text


def test_an_mcmc_calibrator_has_no_grid_and_names_its_emulator_draws():
    cal = gpmsa.Calibrator(_emulator(1), method="mcmc", emulator_params="draws")
    text = repr(cal)
    assert text.startswith("Calibrator(method=mcmc, backend=numpy, t=['t0'],"), text
    assert "grid" not in text and "emulator_params=draws" in text and "updates=0" in text


def test_long_parameter_names_are_cut():
    text = repr(gpmsa.Calibrator(_emulator(1, "n" * 200), method="mcmc"))
    assert len(text) < 120 and "\n" not in text and "..." in text, text


def test_the_repr_never_raises():
    cal = gpmsa.Calibrator.__new__(gpmsa.Calibrator)  # no attribute at all
    assert repr(cal) == "Calibrator(?)"
