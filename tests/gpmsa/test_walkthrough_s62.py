"""A UQ user's walkthrough of session 62's features (studies with a discrepancy, per-group lamVz
priors, the read-only Emulator): what it found wrong.

Before: a study's per-model warnings other than OutsideEmulatorWarning (a vague observation
precision's ReductionWarning, an extrapolated x_obs) did not name the model, so two models'
identical messages showed once, from one model unknown; ``emu.metadata = None`` (or a list) was
taken, and failed only at ``save`` ("it could not be read back") or in the user's own code."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.calibration.calibrate import calibration_problem
from gpmsa.errors import ReductionWarning
from gpmsa.model.likelihood import log_posterior
from tests.gpmsa import _study_cases as sc

S = np.linspace(0.0, 1.0, 8)
"""The output grid of the functional case."""


def _functional_emulator() -> gpmsa.Emulator:
    """y(s; x, t) = x s + t s^2 on 8 points, at fixed parameters."""
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(20, 1)), rng.uniform(size=(20, 1))
    data = gpmsa.SimData(x=x, t=t, y=np.outer(x, S) + np.outer(t, S**2), index=S,
                         x_names=["x"], t_names=["t"])  # fmt: skip
    return gpmsa.Emulator.from_params(data, {"betaU": [[1, 1], [1, 1]], "lamUz": [1, 1],
                                             "lamWs": [1e3, 1e3], "lamWOs": [1e3]})  # fmt: skip


def _caught(run) -> list[warnings.WarningMessage]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        run()
    return caught


def test_a_studys_reduction_warnings_name_their_model():
    """Both models declare a vague precision (sd 10 where the outputs' spread is 0.3): each
    model's ReductionWarning names it, so that the default filter shows both."""
    emu = _functional_emulator()
    x = np.array([[0.3], [0.6]])
    obs = gpmsa.ObsData(x=x, y=np.outer(x, S) + 0.4 * S**2, index=S, precision=1e-2)
    for disc in (None, "constant"):
        caught = _caught(lambda d=disc: gpmsa.calibrate_study(
            [emu, emu], [obs, obs], labels=["a", "b"], shared=["t"], discrepancy=d,
            n_samples=20, n_burn=5, tune=False, seed=0))  # fmt: skip
        msgs = [str(w.message) for w in caught if issubclass(w.category, ReductionWarning)]
        assert len(msgs) == 2
        assert msgs[0].startswith("model 'a': the observation precisions declare")
        assert msgs[1].startswith("model 'b': the observation precisions declare")
        assert all(w.filename == __file__ for w in caught)  # the user's line


def test_fit_studys_per_model_warnings_name_their_model():
    emu = _functional_emulator()
    data = gpmsa.SimData(x=emu.x_unit, t=emu.t_unit, y=np.asarray(emu.y), index=S,
                         x_names=["x"], t_names=["t"])  # fmt: skip
    x = np.array([[0.3], [0.6]])
    obs = gpmsa.ObsData(x=x, y=np.outer(x, S) + 0.4 * S**2, index=S, precision=1e-2)
    caught = _caught(
        lambda: gpmsa.fit_study(
            [data, data], [obs, obs], labels=["a", "b"], shared=["t"], n_iter=20, tune=False, seed=0
        )
    )
    msgs = sorted(str(w.message)[:10] for w in caught if issubclass(w.category, ReductionWarning))
    assert msgs == ["model 'a':", "model 'b':"]


def test_an_extrapolated_observation_is_named_by_its_model():
    emu = sc.emulator()
    caught = _caught(lambda: gpmsa.calibrate_study(
        [emu, emu], [[[0.5]], [[1.05]]], [[1.0], [1.0]], labels=["a", "b"], shared=["t"],
        extrapolate=True, n_samples=20, n_burn=5, tune=False, seed=0))  # fmt: skip
    outside_x = [str(w.message) for w in caught if "x_obs" in str(w.message)
                 and "predictive sds" not in str(w.message)]  # fmt: skip
    assert outside_x and all(m.startswith("model 'b': ") for m in outside_x)


def test_metadata_is_replaced_only_by_a_dict():
    emu = sc.emulator().with_calibration_priors()
    emu.metadata = None  # as the constructor takes it: no metadata
    assert emu.metadata == {}
    given = {"robot": "jackal-2"}
    emu.metadata = given
    assert emu.metadata == given
    for bad in ([1, 2], "notes", 3.0):
        with pytest.raises(gpmsa.GPMSAError, match="metadata must be None or a dict, got"):
            emu.metadata = bad
    assert emu.metadata == given


def test_a_studys_log_posterior_is_the_models_dense_sum():
    """Independent check of the study sampler's cached likelihoods with discrepancies: the
    recorded log posterior of each draw minus the sum of each model's dense GPM/SA log posterior
    (``model.likelihood.log_posterior``, the shared theta's prior once) is one constant, for a
    model with two precision groups under per-group priors, one without a discrepancy and one
    with a constant one (measured spread 5e-10)."""
    emu = _functional_emulator()
    tight = emu.with_calibration_priors(lamVz=[gpmsa.GammaPrior(1, 1e-3),
                                               gpmsa.GammaPrior(50, 0.1)])  # fmt: skip
    rng = np.random.default_rng(1)
    x = np.array([[0.2], [0.5], [0.8]])
    ys = [np.outer(x, S) + 0.4 * S**2 + off + 0.01 * rng.standard_normal((3, S.size))
          for off in (0.05, 0.0, 0.03)]  # fmt: skip
    D = np.column_stack([np.ones_like(S), S])
    kinds = [(tight, D, [0, 1]), (emu, None, None), (emu, "constant", None)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the offsets lie outside the emulator, on purpose
        study = gpmsa.calibrate_study(
            [k[0] for k in kinds], [x, x, x], ys, shared=["t"], discrepancy=[k[1] for k in kinds],
            discrepancy_groups=[k[2] for k in kinds], n_samples=120, n_burn=20, seed=3,
        )  # fmt: skip
        problems = [calibration_problem(e, x, y, discrepancy=d, discrepancy_groups=g)
                    for (e, d, g), y in zip(kinds, ys, strict=True)]  # fmt: skip
    dr = study.draws
    diffs = []
    for i in range(0, 100, 9):
        total = 0.0
        for j, prob in enumerate(problems):
            prm = {k: np.array(v) for k, v in prob.init.items()}
            prm["theta"], prm["lamOs"] = dr["theta"][0, i], dr["lamOs"][0, i, j : j + 1]
            if f"lamVz_{j}" in dr:
                prm["betaV"], prm["lamVz"] = dr[f"betaV_{j}"][0, i], dr[f"lamVz_{j}"][0, i]
            total += log_posterior(prob, prm) - (prob.theta_log_prior(prm["theta"]) if j else 0)
        diffs.append(dr["log_post"][0, i] - total)
    assert np.ptp(diffs) < 1e-6
