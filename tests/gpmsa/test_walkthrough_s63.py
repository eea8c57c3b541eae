"""From a SEPIA-user walkthrough of docs/from-sepia.md (session 63): Posterior.summary's R-hat,
calibrate's advice on options it does not take, ragged observations given as plain lists,
ObsData's messages, SEPIA-style categorical declarations and prediction_bands' observed."""

import functools

import numpy as np
import pytest

import gpmsa
from gpmsa import GPMSAError
from gpmsa.calibration.posterior import Posterior

GRID = np.linspace(0.0, 1.0, 8)


def _simulator(x, t):
    return np.exp(-(0.5 + x) * GRID[None]) * t + GRID[None] * x


@functools.cache
def _emulator():
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(24, 1)), rng.uniform(size=(24, 1))
    data = gpmsa.SimData(x=x, t=t, y=_simulator(x, t), x_names=["x"], t_names=["t"], index=GRID)
    return gpmsa.fit(data, n_iter=60, tune=False, seed=0)


def _ragged():
    grids = [np.linspace(0.0, 1.0, 5), np.array([0.1, 0.4, 0.9])]
    x = np.array([[0.3], [0.7]])
    ys = [np.interp(g, GRID, _simulator(x[j : j + 1], 0.4)[0]) for j, g in enumerate(grids)]
    return x, ys, grids


def test_summary_reports_rhat_beside_ess_for_chains():
    rng = np.random.default_rng(1)
    mixed = rng.normal(size=(2, 200))
    apart = np.vstack([rng.normal(size=200), 5.0 + rng.normal(size=200)])
    post = Posterior({"a": mixed.ravel(), "b": apart.ravel()}, chains={"a": mixed, "b": apart})
    row = post.summary()
    assert row["a"]["rhat"] == pytest.approx(1.0, abs=0.02)
    assert row["b"]["rhat"] > 1.5  # two chains 5 sds apart
    assert "rhat" not in Posterior({"a": mixed.ravel()}).summary()["a"]  # no chains: no R-hat


def test_calibrate_names_an_unknown_option_instead_of_sending_it_to_fast_false():
    emu = _emulator()
    x, y = np.array([[0.5]]), _simulator(np.array([[0.5]]), 0.4)
    with pytest.raises(GPMSAError, match=r"unknown option\(s\) \['tune_round'\]"):
        gpmsa.calibrate(emu, x, y, n_samples=20, n_burn=5, tune_round=3)
    with pytest.raises(GPMSAError, match=r"ObsData\(x, y, index="):
        gpmsa.calibrate(emu, x, y, n_samples=20, n_burn=5, index=GRID)
    with pytest.raises(GPMSAError, match="the fast numpy sampler replaces"):  # a real option
        gpmsa.calibrate(emu, x, y, n_samples=20, n_burn=5, step_widths={"theta": 0.1})


def test_ragged_y_obs_lists_are_pointed_at_obsdata():
    emu = _emulator()
    x, ys, grids = _ragged()
    with pytest.raises(GPMSAError, match=r"lengths \[5, 3\].*gpmsa\.ObsData\(x, y, index="):
        gpmsa.calibrate(emu, x, ys, n_samples=20, n_burn=5)
    with pytest.raises(GPMSAError, match=r"lengths \[5, 3\].*gpmsa\.ObsData"):
        gpmsa.Calibrator(emu).update(x, ys)
    post = gpmsa.calibrate(emu, gpmsa.ObsData(x, ys, index=grids), n_samples=30, n_burn=5, seed=0)
    assert post.samples["t"].shape == (25,)


def test_obsdata_messages_name_its_index_argument():
    x, ys, grids = _ragged()
    with pytest.raises(GPMSAError, match=r"^index has 1 grids for 2 experiment") as err:
        gpmsa.ObsData(x, ys, index=grids[:1])
    assert "index_obs" not in str(err.value)
    with pytest.raises(GPMSAError, match=r"index\[1\] has 2 points, y\[1\] has 3"):
        gpmsa.ObsData(x, ys, index=[grids[0], grids[1][:2]])


def test_sepia_style_categorical_declaration_is_refused_with_the_hint():
    rng = np.random.default_rng(2)
    x = np.column_stack([rng.uniform(size=20), rng.integers(0, 3, 20)])
    t, y = rng.uniform(size=(20, 1)), rng.uniform(size=(20, 3))
    with pytest.raises(GPMSAError, match=r"column 3 out of range.*x_cat_ind"):
        gpmsa.SimData(x, t, y, x_categorical=[0, 3])  # SEPIA: 0 continuous, 3 levels
    x3 = np.column_stack([x, rng.integers(0, 2, 20)])
    with pytest.raises(GPMSAError, match=r"lists column 0 \(x0\) twice.*x_cat_ind"):
        gpmsa.SimData(x3, t, y, x_categorical=[0, 0, 2])  # SEPIA's form, read as columns 0, 2
    with pytest.raises(GPMSAError, match=r"lists column 1 \(x1\) twice"):
        gpmsa.SimData(x, t, y, x_categorical=["x1", 1])
    assert gpmsa.SimData(x, t, y, x_categorical=[1]).x_categorical == (1,)


def test_prediction_bands_refuses_ragged_observations_naming_the_grid():
    x, ys, grids = _ragged()
    rng = np.random.default_rng(3)
    xs, ts = rng.uniform(size=(24, 1)), rng.uniform(size=(24, 1))
    data = gpmsa.SimData(x=xs, t=ts, y=_simulator(xs, ts), x_names=["x"], t_names=["t"],
                         index=GRID)  # fmt: skip
    obs = gpmsa.ObsData(x, ys, index=grids)
    emu = gpmsa.fit(data, obs, n_iter=60, tune=False, seed=0, discrepancy="constant")
    pred = gpmsa.full_prediction(emu, obs, x, n_draws=5, seed=0)
    for observed in (ys, obs):
        with pytest.raises(GPMSAError, match=r"\(2, 8\) on pred\.grid.*grid="):
            gpmsa.plots.prediction_bands(pred, observed=observed)


def test_a_precision_vector_per_experiment_is_its_diagonal():
    x, ys, grids = _ragged()
    vectors = [np.linspace(1e3, 2e3, 5), np.array([5e2, 1e3, 4e3])]
    obs = gpmsa.ObsData(x, ys, index=grids, precision=vectors)
    same = gpmsa.ObsData(x, ys, index=grids, precision=[np.diag(v) for v in vectors])
    assert all(np.array_equal(a, b) for a, b in zip(obs.precisions, same.precisions, strict=True))
    assert obs.digest() == same.digest()
    with pytest.raises(GPMSAError, match=r"precision\[1\] must be positive"):
        gpmsa.ObsData(x, ys, index=grids, precision=[vectors[0], -vectors[1]])
    with pytest.raises(GPMSAError, match=r"precision\[1\] must be a scalar, \(3,\) or \(3, 3\)"):
        gpmsa.ObsData(x, ys, index=grids, precision=[vectors[0], vectors[1][:2]])


def test_one_unit_for_a_functional_output_says_one_per_value():
    rng = np.random.default_rng(5)
    x, t = rng.uniform(size=(12, 1)), rng.uniform(size=(12, 1))
    with pytest.raises(GPMSAError, match=r"y_units must have 8 entries.*\['s'\] \* 8"):
        gpmsa.SimData(x=x, t=t, y=_simulator(x, t), index=GRID, y_units=["s"])


def test_full_prediction_reads_the_discrepancy_kind_a_calibration_recorded():
    emu = _emulator()
    xo = np.array([[0.2], [0.5], [0.8]])
    obs = gpmsa.ObsData(xo, _simulator(xo, 0.4) + 0.05)
    post = gpmsa.calibrate(emu, obs, n_samples=60, n_burn=10, seed=0, discrepancy="linear")
    auto = gpmsa.full_prediction(emu, obs, [[0.4]], posterior=post, n_draws=10, seed=1)
    told = gpmsa.full_prediction(emu, obs, [[0.4]], posterior=post, n_draws=10, seed=1,
                                 discrepancy="linear")  # fmt: skip
    assert auto.p_v == 2 and np.array_equal(auto.y, told.y)
    D = np.column_stack([np.ones(GRID.size), GRID**2])
    given = gpmsa.calibrate(emu, obs, n_samples=60, n_burn=10, seed=0, discrepancy=D)
    assert given.info["discrepancy"] == "given"
    with pytest.raises(GPMSAError, match="given as an array; pass it again"):
        gpmsa.full_prediction(emu, obs, [[0.4]], posterior=given)
    study = gpmsa.calibrate_study([emu, emu], [obs, obs], shared=["t"], n_samples=60,
                                  n_burn=10, seed=0, discrepancy=["constant", None])  # fmt: skip
    first, second = (study.member_posterior(k) for k in study.labels)
    assert first.info["discrepancy"] == "constant" and "discrepancy" not in second.info
    assert gpmsa.full_prediction(emu, obs, [[0.4]], posterior=first, n_draws=5).p_v == 1
    assert gpmsa.full_prediction(emu, obs, [[0.4]], posterior=second, n_draws=5).p_v == 0
