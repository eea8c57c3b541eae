"""Review of session 73's level quantiles (f4e5b9f): a categorical theta's quantiles from draws
are levels in ``gpmsa.calibrate``'s and ``study.posterior``'s Posterior, but a joint fit's
(``gpmsa.calibration_posterior``, ``Emulator.theta_summary``) and a study member's
(``Study.member_posterior``) still interpolated between levels (0.5 between kinds 0 and 1),
and ``Study.summary`` no longer equalled ``member_posterior(LABEL).summary()`` as documented."""

import warnings

import numpy as np
import pytest
from _level_cases import level_case

import gpmsa


def _between(draws: np.ndarray) -> float:
    """A probability at which linear interpolation falls halfway between levels 0 and 1."""
    return (np.sum(draws == 0.0) - 0.5) / (draws.size - 1)


@pytest.fixture(scope="module")
def joint():
    sim, _, xo, yo = level_case()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gpmsa.fit(sim, gpmsa.ObsData(x=xo, y=yo[:, None]), n_iter=100, seed=0, tune=False)


def test_a_joint_fits_categorical_quantiles_are_levels(joint):
    post = gpmsa.calibration_posterior(joint)
    kind = post.samples["kind"]
    assert set(np.unique(kind)) == {0.0, 1.0}
    assert post.info["levels"] == {"kind": [0.0, 1.0, 2.0]}
    assert post.quantile("kind", _between(kind)) in (0.0, 1.0)  # was 0.5
    state = joint.__getstate__()  # half its draws at each level: linear's median is 0.5
    theta = np.array(state["calibration"]["theta_native"])
    theta[:, 1] = np.arange(theta.shape[0]) % 2
    state["calibration"] = {**state["calibration"], "theta_native": theta}
    state.pop("model_sha256", None)
    even = object.__new__(gpmsa.Emulator)
    even.__setstate__(state)
    summary = even.theta_summary()["kind"]
    assert (summary["q2.5"], summary["q50"], summary["q97.5"]) == (0.0, 0.0, 1.0)  # q50 was 0.5
    assert summary["q50"] == gpmsa.calibration_posterior(even).quantile("kind", 0.5)


def test_a_study_members_categorical_quantiles_are_levels():
    _, emu, xo, yo = level_case()
    obs = [gpmsa.ObsData(x=xo[:3], y=yo[:3, None]), gpmsa.ObsData(x=xo[3:], y=yo[3:, None])]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        study = gpmsa.calibrate_study([emu, emu], obs, shared=["k", "kind"], n_samples=200,
                                      n_burn=50, n_chains=2, seed=4, n_jobs=1)  # fmt: skip
    member = study.member_posterior(0)
    q = _between(member.samples["kind"])
    assert member.quantile("kind", q) == study.posterior.quantile("kind", q) == 1.0  # was 0.5
    assert member.summary()["kind"] == study.summary()["kind"]
