"""Options accepted and then without effect (session 79 sweep), each confirmed bit for bit
before the fix and now refused by name: ``fit(..., init=emulator, theta_init=)`` (the chains
continue from their last draws; calibrate already refused it), ``ridge_moves`` above 0 where
the nugget-ridge move does not apply (a joint fit, a calibration, a held lamWOs),
``n_emulator_draws`` with ``emulator_params="point"`` (calibrate, Calibrator), a Calibrator's
``n_grid`` / ``n_draws`` on its MCMC path and ``mcmc_options`` with ``method="grid"``, and a
Simplex's ``latch_p`` with ``after_fault="resume"``. The calls that take them with effect, and
the defaults, run as before."""

import sys
import warnings
from functools import cache
from pathlib import Path

import numpy as np
import pytest

import control
import gpmsa
from gpmsa import GPMSAError

sys.path.insert(0, str(Path(__file__).parent / "gpmsa"))
from _calib_cases import road_emulator, road_obs  # noqa: E402
from _continue_cases import continue_data  # noqa: E402

FIT = {"n_iter": 40, "n_keep": 20, "seed": 0, "tune": False}


def _fit(*args, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        return gpmsa.fit(*args, **{**FIT, **kw})


def _calibrate(*args, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        return gpmsa.calibrate(*args, n_samples=20, n_burn=5, tune=False, seed=1, **kw)


@cache
def _sim_emulator():
    """A simulation-only fit of the continuation problem (retained draws, one component)."""
    return _fit(continue_data()[0], n_iter=100, n_keep=40)


@cache
def _three_param_emulator():
    """An emulator of three calibration parameters (the Calibrator's "auto" chooses MCMC)."""
    rng = np.random.default_rng(2)
    x, t = rng.random((30, 1)), rng.random((30, 3))
    sim = gpmsa.SimData(x=x, t=t, y=(x[:, 0] + t.sum(axis=1))[:, None])
    return gpmsa.Emulator.from_params(sim, {"betaU": [[1.0]] * 4, "lamUz": [1.0],
                                            "lamWs": [1e3], "lamWOs": [1e3]})  # fmt: skip


def test_a_continued_fit_refuses_theta_init():
    data, obs = continue_data()
    src = _fit(data, obs)
    with pytest.raises(GPMSAError, match=r"theta_init= sets a fresh chain's start; init=emu"):
        _fit(data, obs, init=src, theta_init=[0.9])
    assert _fit(data, obs, init=src).settings["continued_from"] == src.model_sha256
    fresh = _fit(data, obs, theta_init=[0.9])  # a fresh chain starts there
    assert not np.array_equal(fresh.log_post, _fit(data, obs).log_post)


def test_ridge_moves_are_refused_where_the_move_does_not_apply():
    data, obs = continue_data()
    with pytest.raises(GPMSAError, match=r"ridge_moves=3: .* model has observations .* leave"):
        _fit(data, obs, ridge_moves=3)
    with pytest.raises(GPMSAError, match=r"ridge_moves=2: .* lamWs or lamWOs is held"):
        _fit(data, fixed={"lamWOs": 1e4}, ridge_moves=2)
    emu, (x, y) = road_emulator(), road_obs()
    with pytest.raises(GPMSAError, match=r"ridge_moves=1: .* a calibration"):
        _calibrate(emu, x, y, fast=False, ridge_moves=1)
    # 0 (the move off) is no surprise anywhere; where it applies the moves change the draws
    assert _fit(data, obs, ridge_moves=0).settings["backend_options"] == {"ridge_moves": 0}
    assert not np.array_equal(_fit(data, ridge_moves=9).log_post, _fit(data).log_post)


def test_n_emulator_draws_with_the_point_estimate_is_refused():
    emu, (x, y) = road_emulator(), road_obs()
    with pytest.raises(GPMSAError, match=r"calibrate: n_emulator_draws=7 .* emulator_params="):
        _calibrate(emu, x, y, n_emulator_draws=7)
    with pytest.raises(GPMSAError, match=r"Calibrator: n_emulator_draws=5 .*'draws' as well"):
        gpmsa.Calibrator(emu, n_emulator_draws=5)
    with pytest.raises(GPMSAError, match=r"Calibrator: n_emulator_draws=5"):
        gpmsa.Calibrator(emu, method="mcmc", n_emulator_draws=5)
    # the default (also given) and the draws mode take it
    same = _calibrate(emu, x, y, n_emulator_draws=20)
    assert np.array_equal(same.samples["GD"], _calibrate(emu, x, y).samples["GD"])
    sim = _sim_emulator()
    post = _calibrate(sim, [[0.2]], [[0.7]], emulator_params="draws", n_emulator_draws=3)
    assert set(post.info["emulator_draws"]) <= set(range(sim.n_draws))
    assert gpmsa.Calibrator(sim, emulator_params="draws", n_emulator_draws=3).method == "grid"
    on_mcmc = gpmsa.Calibrator(sim, method="mcmc", n_emulator_draws=3,
                               mcmc_options={"emulator_params": "draws"})  # fmt: skip
    assert on_mcmc.method == "mcmc"


def test_a_calibrator_refuses_the_other_paths_arguments():
    emu = road_emulator()
    for kw in ({"method": "mcmc"}, {}):
        target = emu if kw else _three_param_emulator()
        with pytest.raises(GPMSAError, match=r"n_grid=33 sets the nodes .* runs MCMC"):
            gpmsa.Calibrator(target, n_grid=33, **kw)
        with pytest.raises(GPMSAError, match=r"n_draws=100 sets .* runs MCMC.*n_samples"):
            gpmsa.Calibrator(target, n_draws=100, **kw)
    with pytest.raises(GPMSAError, match=r"method='auto' chooses MCMC here"):
        gpmsa.Calibrator(_three_param_emulator(), n_grid=33)
    with pytest.raises(GPMSAError, match=r"mcmc_options \['n_chains', 'n_samples'\] apply on"):
        gpmsa.Calibrator(emu, method="grid", mcmc_options={"n_samples": 50, "n_chains": 2})
    # as before: "auto" keeps them for an emulator that needs MCMC; the grid's own arguments
    assert gpmsa.Calibrator(emu, mcmc_options={"n_samples": 50}).method == "grid"
    grid = gpmsa.Calibrator(
        emu,
        method="grid",
        n_grid=33,
        n_draws=100,
        mcmc_options={"backend": "numpy"},
        constraint=lambda t: t[0] > 300,
    )
    assert grid.n_grid == 33 and grid.n_draws == 100
    assert gpmsa.Calibrator(_three_param_emulator(), n_draws=4000).method == "mcmc"


def test_latch_p_with_after_fault_resume_is_refused():
    with pytest.raises(control.ControlError, match=r"latch_p = 1e-06 has no effect with after"):
        control.Simplex(after_fault="resume", latch_p=1e-6)
    assert control.Simplex(after_fault="resume").latch_p == 1e-12
    assert control.Simplex(latch_p=1e-6).latch_p == 1e-6
