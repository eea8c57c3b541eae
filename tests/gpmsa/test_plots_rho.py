"""plots.rho_boxplots: boxes of rho = exp(-betaU/4) per input and basis component, from the
emulator's retained draws (SEPIA's SepiaPlot.rho_box_plots)."""

import matplotlib
import numpy as np
import pytest
from _calib_cases import two_param_emulator, vector_emulator, with_draws
from matplotlib.figure import Figure

import gpmsa
from gpmsa import GPMSAError, plots
from gpmsa.plots.rho import _rho_panels

matplotlib.use("Agg")


def _box_values(ax, k: int) -> np.ndarray:
    """Every y value the artists of box k (at x = k + 1) draw."""
    lines = [ln for ln in ax.lines if len(ln.get_xdata())
             and abs(np.mean(ln.get_xdata()) - (k + 1)) < 0.4]  # fmt: skip
    return np.concatenate([ln.get_ydata() for ln in lines])


def _check_boxes(fig, emu, n_panels: int) -> None:
    beta = emu.draws["betaU"]
    assert len(fig.axes) == n_panels
    for j, ax in enumerate(fig.axes):
        rho = np.exp(-beta[:, :, j] / 4)
        np.testing.assert_allclose(_rho_panels(emu, 99)[j], rho, rtol=1e-14)
        for k in range(emu.p + emu.q):
            values = _box_values(ax, k)
            assert values.min() == pytest.approx(rho[:, k].min())
            assert values.max() == pytest.approx(rho[:, k].max())
            assert np.isclose(values, np.median(rho[:, k])).any()
        assert ax.get_ylim()[0] <= 0.0 and ax.get_ylim()[1] >= 1.0
        assert ax.get_title() == f"PC {j + 1}"


def test_boxes_are_rho_of_the_draws_labelled_by_input():
    emu = with_draws(two_param_emulator(), n=9)
    fig = plots.rho_boxplots(emu)
    assert isinstance(fig, Figure)
    _check_boxes(fig, emu, 1)
    assert [t.get_text() for t in fig.axes[0].get_xticklabels()] == ["x", "a", "b"]


def test_functional_output_one_panel_per_component_up_to_max_pc():
    emu = with_draws(vector_emulator(), n=11)
    assert emu.p_u == 2
    _check_boxes(plots.rho_boxplots(emu), emu, 2)
    fig = plots.rho_boxplots(emu, max_pc=1)
    assert len(fig.axes) == 1 and _rho_panels(emu, 1).shape == (1, 11, 2)


def _small_emulator(**sim_kw) -> gpmsa.Emulator:
    rng = np.random.default_rng(5)
    t = rng.uniform(size=(16, 2))
    x = sim_kw.pop("x", None)
    y = np.sin(3 * t[:, 0]) + t[:, 1] + (0.0 if x is None else x[:, 0])
    sim = gpmsa.SimData(x=x, t=t, y=y, t_names=["u", "v"], **sim_kw)
    params = {"betaU": np.ones((sim.p + 2, 1)), "lamUz": [1.0], "lamWs": [1e4], "lamWOs": [1e4]}
    emu = gpmsa.Emulator.from_params(sim, params)
    return with_draws(emu, n=6)


def test_no_known_inputs_shows_the_calibration_inputs_only():
    emu = _small_emulator()
    assert emu.p == 0
    fig = plots.rho_boxplots(emu)
    _check_boxes(fig, emu, 1)
    assert [t.get_text() for t in fig.axes[0].get_xticklabels()] == ["u", "v"]


def test_a_categorical_input_is_marked():
    x = np.tile([0.0, 1.0, 2.0, 3.0], 4)[:, None]
    emu = _small_emulator(x=x, x_names=["kind"], x_categorical=["kind"])
    fig = plots.rho_boxplots(emu)
    _check_boxes(fig, emu, 1)
    assert [t.get_text() for t in fig.axes[0].get_xticklabels()] == ["kind (cat.)", "u", "v"]


def test_bad_arguments_are_named():
    emu = with_draws(two_param_emulator())
    with pytest.raises(GPMSAError, match="emulator must be a gpmsa.Emulator, got dict"):
        plots.rho_boxplots({"betaU": np.ones((3, 3, 1))})
    for bad in (0, -1, 2.5, "3", None):
        with pytest.raises(GPMSAError, match="max_pc must be an integer >= 1"):
            plots.rho_boxplots(emu, max_pc=bad)
    with pytest.raises(GPMSAError, match="no posterior draws of betaU.*from_params"):
        plots.rho_boxplots(two_param_emulator())
