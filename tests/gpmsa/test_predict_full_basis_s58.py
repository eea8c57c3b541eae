"""full_prediction refuses a discrepancy basis other than the one its draws were made with.

Before: the joint fit recorded an array basis only as "given", and a Posterior of
gpmsa.calibrate (or of calibration_posterior) recorded nothing, so another array (other
columns, another count of columns), or "constant" for draws of "linear", was taken silently and
gave another delta (e.g. 0.104 flat against 0.287 ... -0.020 along the grid).
"""

import warnings

import numpy as np
import pytest
from _predict_cases import GRID, known_truth_case

import gpmsa
from gpmsa import GPMSAError
from gpmsa.predictive import full_prediction


def _joint_with_array_basis():
    emu, obs, *_ = known_truth_case()
    std = emu.standardizer
    data = gpmsa.SimData(x=std.x_from_unit(emu.x_unit), t=std.t_from_unit(emu.t_unit), y=emu.y,
                         index=emu.index, x_names=["x"], t_names=["t"])  # fmt: skip
    D = np.exp(-0.5 * ((GRID[:, None] - np.linspace(0, 1, 4)[None, :]) / 0.3) ** 2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu_d = gpmsa.fit(data, obs, n_iter=30, tune=False, seed=0, discrepancy=D)
    return emu_d, obs, D


def test_joint_fit_refuses_another_array_basis():
    emu, obs, D = _joint_with_array_basis()
    for other in (D[:, :3], D[:, ::-1], D + 0.1):
        with pytest.raises(GPMSAError, match="discrepancy basis differs from the one the draws"):
            full_prediction(emu, obs, [[0.5]], discrepancy=other, n_draws=2)
    # the same basis (or a multiple: the basis is normalised) is accepted, after a save too
    a = full_prediction(emu, obs, [[0.5]], discrepancy=D, n_draws=2, seed=0)
    b = full_prediction(emu, obs, [[0.5]], discrepancy=2.0 * D, n_draws=2, seed=0)
    np.testing.assert_array_equal(a.y, b.y)
    post = gpmsa.calibration_posterior(emu)
    for other in (D[:, :3], "linear", "constant"):
        with pytest.raises(GPMSAError, match="discrepancy basis differs from the one the draws"):
            full_prediction(emu, obs, [[0.5]], posterior=post, discrepancy=other, n_draws=2)
    full_prediction(emu, obs, [[0.5]], posterior=post, discrepancy=D, n_draws=2)


def test_joint_fit_record_survives_the_file(tmp_path):
    emu, obs, D = _joint_with_array_basis()
    back = gpmsa.load(emu.save(tmp_path / "d.gpmsa"))
    with pytest.raises(GPMSAError, match="discrepancy basis differs from the one the draws"):
        full_prediction(back, obs, [[0.5]], discrepancy=D[:, :2], n_draws=2)
    full_prediction(back, obs, [[0.5]], discrepancy=D, n_draws=2)


def test_calibrate_posterior_refuses_another_basis():
    emu, obs, *_ = known_truth_case()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        post = gpmsa.calibrate(emu, obs.x, obs.y, n_samples=60, n_burn=10, seed=0, tune=False,
                               discrepancy="linear")  # fmt: skip
    for other in ("constant", np.ones((GRID.size, 1)), np.column_stack([np.ones(12), GRID**2])):
        with pytest.raises(GPMSAError, match="discrepancy basis differs from the one the draws"):
            full_prediction(emu, obs, [[0.5]], posterior=post, discrepancy=other, n_draws=2)
    same = np.column_stack([np.ones(GRID.size), GRID])  # "linear" as an array: the same basis
    a = full_prediction(emu, obs, [[0.5]], posterior=post, discrepancy="linear", n_draws=2, seed=0)
    b = full_prediction(emu, obs, [[0.5]], posterior=post, discrepancy=same, n_draws=2, seed=0)
    np.testing.assert_allclose(a.y, b.y, rtol=1e-10)  # D_pred built by another path


def test_fit_study_member_refuses_another_basis():
    emu, obs, *_ = known_truth_case()
    std = emu.standardizer
    data = gpmsa.SimData(x=std.x_from_unit(emu.x_unit), t=std.t_from_unit(emu.t_unit), y=emu.y,
                         index=emu.index, x_names=["x"], t_names=["t"])  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        study = gpmsa.fit_study([data, data], [obs, obs], shared=["t"], n_iter=20, tune=False,
                                seed=0, discrepancy="linear")  # fmt: skip
    member, post = study.members[0], study.member_posterior("model0")
    for kw in ({}, {"posterior": post}):  # (without posterior=: the name already differs)
        with pytest.raises(GPMSAError, match="differs from the (joint fit's|one the draws)"):
            full_prediction(member, obs, [[0.5]], discrepancy="constant", n_draws=2, **kw)
        full_prediction(member, obs, [[0.5]], discrepancy="linear", n_draws=2, **kw)


def test_any_multiple_of_the_basis_is_the_same_basis():
    """docs/prediction.md: a multiple of the basis is the same basis. Only powers of two were:
    3 D or D / 10 normalise to D's basis within an ulp or two, and the exact SHA-256 refused
    them ('differs from the one the draws were made with'), though the prediction is the same
    to 2e-15."""
    emu, obs, D = _joint_with_array_basis()
    a = full_prediction(emu, obs, [[0.5]], discrepancy=D, n_draws=2, seed=0)
    for multiple in (3.0 * D, 0.1 * D, D / 7.0 * 7.0, 1e200 * D):
        b = full_prediction(emu, obs, [[0.5]], discrepancy=multiple, n_draws=2, seed=0)
        np.testing.assert_allclose(b.y, a.y, rtol=0, atol=1e-12)
    with pytest.raises(GPMSAError, match="discrepancy basis differs from the one the draws"):
        full_prediction(emu, obs, [[0.5]], discrepancy=D + 1e-4, n_draws=2)
