"""Exact checks of full_prediction found by mutation testing, its last odd sites (session 93).

The functional case of `test_full_prediction_rest_s93` (`_predict`: a one-component emulator
on the grid [0, 1/3, 2/3, 1], a hand-made Posterior, 'constant' discrepancy): one draw, the
progress bar's count, the repr without draws, the experiments' grids that the discrepancy
basis takes or refuses (the same size with other points, one point each, scales apart in the
8th digit, six experiments named whole), the helpers' hints; and a two-component emulator with
a linear mean basis and a discrepancy whose observations say nothing (lamOs 1e-12).
"""

from __future__ import annotations

import dataclasses
import typing

import numpy as np
import pytest
from _calib_cases import one_component_functional
from test_full_prediction_rest_s93 import X_OBS, _predict

import gpmsa
from gpmsa import GPMSAError
from gpmsa.calibration.posterior import Posterior
from gpmsa.fitting.emulator import Emulator
from gpmsa.predictive import full, full_prediction

pytestmark = pytest.mark.filterwarnings("ignore::gpmsa.ConvergenceWarning")


def test_one_draw_is_the_first_draw_bit_for_bit():
    """n_draws=1 takes draw 0 (evenly spaced from the first); each draw's solve is its own."""
    one, every = _predict(n_draws=1), _predict()
    np.testing.assert_array_equal(one.draw_index, [0])
    np.testing.assert_array_equal(one.theta, every.theta[:1])
    np.testing.assert_array_equal(one.mu, every.mu[:1])
    np.testing.assert_array_equal(one.cov, every.cov[:1])


def test_the_progress_bar_counts_every_draw(capfd):
    pytest.importorskip("tqdm")
    _predict(progress=True)
    err = capfd.readouterr().err
    assert "full_prediction: 100%" in err and "3/3" in err, err[-300:]


def test_repr_without_draws_says_zero_realizations():
    pred = _predict()
    empty = dataclasses.replace(pred, theta=pred.theta[:0], eta=pred.eta[:0])
    want = "FullPrediction(1 points x 4 outputs, 0 draws x 0 realizations, p_u=1, p_v=1)"
    assert repr(empty) == want


def test_recorded_discrepancys_hints_resolve():
    hints = typing.get_type_hints(full._recorded_discrepancy)
    assert hints["posterior"] == Posterior | None  # (never Posterior & None)


# --- the experiments' grids and the discrepancy basis ------------------------------------------


def test_list_bases_refuse_a_grid_of_an_experiments_size_with_other_points():
    obs = gpmsa.ObsData(x=X_OBS, y=[[1.5, 2.0], [1.8, 2.4]], index=[[0.0, 0.5], [0.5, 1.0]])
    bases = [np.array([[1.0], [2.0]]), np.array([[3.0], [1.0]])]
    with pytest.raises(GPMSAError, match=r"^per-experiment discrepancy bases \(a list\) are kno"):
        _predict(obs, discrepancy=bases, grid=[0.0, 0.25])  # 2 values, neither grid


def test_experiments_on_one_point_each_take_the_constant_basis():
    """Both experiments observe index 0.5 only: 'constant' is [[1]] there (its row norm 1)."""
    obs = gpmsa.ObsData(x=X_OBS, y=[[2.0], [2.4]], index=[[0.5], [0.5]])
    pred = _predict(obs)
    np.testing.assert_array_equal(pred.grid, [0.5])
    np.testing.assert_array_equal(pred.D, [[1.0]])


def test_linear_scales_apart_in_the_8th_digit_are_refused_by_the_helper():
    """'linear' on [0, g] is [1, index] / sqrt(1 + g^2): g = 0.5 and 0.5 + 1e-7 give scales
    apart by 4e-8 of them (allowed: 1e-12). full_prediction never gets there (the reduction
    refuses grids whose largest |index| differ first); the helper refuses them itself."""
    emu, grid = one_component_functional()
    std = emu.standardizer
    g0 = np.array([0.0, 0.5])
    with pytest.raises(GPMSAError, match=r"^the experiments' grids give the 'linear' discrep"):
        full._pred_discrepancy("linear", [g0, g0 + [0.0, 1e-7]], std, grid, False)
    D = full._pred_discrepancy("linear", [g0, g0 + [0.0, 1e-15]], std, g0, False)
    np.testing.assert_allclose(D, [[1.0, 0.0], [1.0, 0.5]] / np.sqrt(1.25), rtol=1e-14)
    close = gpmsa.ObsData(x=X_OBS, y=[[1.5, 2.0], [1.8, 2.4]],
                          index=[[0.0, 0.5], [0.0, 0.5 + 1e-15]])  # fmt: skip
    want = np.column_stack([np.ones(4), grid]) / np.sqrt(1.25)
    np.testing.assert_allclose(_predict(close, discrepancy="linear").D, want, rtol=1e-14)


def test_six_experiments_off_the_grid_are_named_without_an_ellipsis():
    obs = gpmsa.ObsData(x=[[0.1 * k + 0.1] for k in range(6)], y=[[2.0]] * 6,
                        index=[[0.1 * k + 0.05] for k in range(6)])  # fmt: skip
    with pytest.raises(GPMSAError) as err:
        _predict(obs, discrepancy=[np.array([[1.0]])] * 6)
    sizes = ", ".join(f"{j}: 1 values" for j in range(6))
    assert f"experiments {sizes}), whose basis" in str(err.value)


# --- a mean basis with two components and a discrepancy ----------------------------------------


def test_mean_basis_components_keep_their_own_gls_mean_beside_a_discrepancy():
    """Weights [v; u_0; u_1]: u_j's mean is h c_j + r^T alpha, c_j its own GLS coefficients.
    With lamOs 1e-12 the observations move nothing (by ~1e-12): delta's mean stays its prior
    0, its variance 1 / lamVz, and eta's mean is Emulator.predict's at (x, theta)."""
    x = np.linspace(0.0, 1.0, 10)
    t = np.random.default_rng(1).permutation(np.linspace(0.0, 1.0, 10))
    grid = np.linspace(0.0, 1.0, 4)
    y = (1.0 + x[:, None] + t[:, None]) * (1.0 + grid) + np.outer(x * t, grid**2)
    sim = gpmsa.SimData(x=x[:, None], t=t[:, None], y=y, index=grid, x_names=["x"],
                        t_names=["t"])  # fmt: skip
    params = {"betaU": [[1.0, 2.0], [1.0, 2.0]], "lamUz": [1.0, 2.0], "lamWs": [5e3, 5e3],
              "lamWOs": [5e3]}  # fmt: skip
    emu = Emulator.from_params(sim, params, n_pc=2, mean_basis="linear")
    post = gpmsa.Posterior({"t": np.array([0.4]), "lamOs": np.array([1e-12]),
                            "betaV": np.array([1.0]), "lamVz": np.array([3.0])})  # fmt: skip
    obs = gpmsa.ObsData(x=X_OBS, y=[[1.5, 2.0, 2.5, 3.0], [1.8, 2.4, 3.0, 3.6]])
    x_new = [[0.4], [0.7]]
    pred = full_prediction(emu, obs, x_new, posterior=post, discrepancy="constant", seed=0)
    assert pred.mu.shape == (1, 2, 3)
    np.testing.assert_allclose(pred.mu[0, :, 0], 0.0, atol=1e-9)
    np.testing.assert_allclose(pred.cov[0, :, 0, 0], 1.0 / 3.0, rtol=1e-9)
    mean, _ = emu.predict(x_new, [[0.4], [0.4]])
    np.testing.assert_allclose(pred.mean("eta"), mean, rtol=1e-9)
