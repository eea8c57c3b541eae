"""Bad arguments to the public API after a fit, found by a systematic fuzz: each is refused by
a GPMSAError naming the argument and the problem, never a numpy error from deep inside or a
silent figure of nothing."""

from functools import cache

import numpy as np
import pytest
from _calib_cases import two_param_emulator, vector_emulator
from _study_cases import observations, sim_data

import gpmsa
from gpmsa import GPMSAError, ResourceLimitError

RAGGED = [[0.5], [0.5, 0.6]]  # two rows of different lengths: numpy cannot shape them


@cache
def _joint():
    """A joint fit of a functional output (8 outputs) and its observations (2 experiments)."""
    rng = np.random.default_rng(0)
    grid = np.linspace(0.0, 1.0, 8)
    x, t = rng.uniform(size=(30, 1)), rng.uniform(size=(30, 1))
    sim = gpmsa.SimData(x=x, t=t, y=np.outer(x[:, 0] + t[:, 0], 1 + grid), index=grid,
                        x_names=["x"], t_names=["t"])  # fmt: skip
    xo = np.array([[0.3], [0.7]])
    obs = gpmsa.ObsData(x=xo, y=np.outer(xo[:, 0] + 0.4, 1 + grid), index=grid)
    with pytest.warns(gpmsa.ConvergenceWarning):
        emu = gpmsa.fit(sim, obs, n_iter=60, seed=0, tune_rounds=2)
    return emu, obs


@pytest.mark.parametrize("where", ["x", "t"])
def test_emulator_prediction_names_a_ragged_input(where):
    emu = vector_emulator()
    args = {"x": [[0.5], [0.6]], "t": [[0.2], [0.4]], where: RAGGED}
    with pytest.raises(GPMSAError, match=rf"^{where} must be a numeric array.* ragged list"):
        gpmsa.emulator_prediction(emu, args["x"], args["t"], draws=False)


def test_a_ragged_input_is_named_ragged_by_every_prediction_and_calibration():
    emu, obs = _joint()
    post = gpmsa.calibration_posterior(emu)
    calls = {
        "x": lambda v: gpmsa.full_prediction(emu, obs, v, n_draws=2, seed=0),
        "x_new": lambda v: gpmsa.calibrated_predict(emu, post, v, n_theta=2),
        "x_obs": lambda v: gpmsa.calibrate(emu, v, obs.y, n_samples=20, n_burn=5, seed=0),
    }
    for name, call in calls.items():
        with pytest.raises(GPMSAError, match=rf"^{name} must be .*ragged list: its entries "
                                             r"have lengths \[1, 2\]"):  # fmt: skip
            call(RAGGED)
    with pytest.raises(GPMSAError, match=r"^x must be .*ragged list"):
        emu.predict(RAGGED, [[0.2], [0.4]])


def test_calibrator_refuses_a_huge_grid_by_its_memory_before_allocating_an_axis():
    # 10**12 nodes of one axis: the ResourceLimitError, not numpy's MemoryError of linspace
    with pytest.raises(ResourceLimitError, match=r"Calibrator\(n_grid=1000000000000\)"):
        gpmsa.Calibrator(two_param_emulator(), method="grid", n_grid=10**12)


@pytest.mark.parametrize("bad", [3, None])
def test_fit_study_names_a_model_that_is_no_simdata(bad):
    sim = sim_data()
    x, y = observations(0.4, 3, 0.03, np.random.default_rng(0))
    obs = gpmsa.ObsData(x=x, y=y)
    for sims in ([sim, bad], [sim, obs]):
        got = type(sims[1]).__name__
        with pytest.raises(GPMSAError, match=rf"^sims must hold one gpmsa.SimData per model, "
                                             rf"got {got} \(model 1\)"):  # fmt: skip
            gpmsa.fit_study(sims, [obs, obs], shared=["t"], n_iter=20, seed=0)


@pytest.mark.parametrize("value", [np.nan, np.inf])
def test_prediction_bands_refuses_observed_values_that_are_not_finite(value):
    from gpmsa.plots import prediction_bands

    emu, obs = _joint()
    pred = gpmsa.full_prediction(emu, obs, [[0.3], [0.6]], seed=0)  # 48 draws
    observed = np.ones((2, 8))
    observed[1, 3] = value
    with pytest.raises(GPMSAError, match=rf"^observed must be finite, got {value} at index "
                                         r"\(1, 3\)"):  # fmt: skip
        prediction_bands(pred, observed)
    assert prediction_bands(pred, np.ones((2, 8))) is not None  # finite: drawn, as before


@pytest.mark.parametrize("unit", [3, ["m"], b"m"])
def test_posterior_plot_refuses_a_unit_that_is_no_text(unit):
    post = gpmsa.Posterior({"t": np.linspace(0.0, 1.0, 20)})
    with pytest.raises(GPMSAError, match=r"^unit must be a text label \(str\) or None, got "):
        post.plot("t", unit=unit)
    fig = post.plot("t", unit="m")  # text: the axis label, as before
    assert fig.axes[0].get_xlabel() == "t (m)"
