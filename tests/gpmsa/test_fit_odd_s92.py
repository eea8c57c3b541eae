"""Mutation testing of gpmsa.fitting.fit, the odd half of its sites (session 92; session 90 did
the even half): what ``fit`` checks of a plug-in's chains, and the helpers' figures and words
against hand-computed values, on tiny fits of 5 runs and tens of sweeps."""

from __future__ import annotations

import types
import warnings

import numpy as np
import pytest
from _fit_cases import five_run_data

import gpmsa
from gpmsa import backends
from gpmsa.backends import numpy_backend
from gpmsa.errors import ChainError, GPMSAError
from gpmsa.fitting import fit as fit_module


@pytest.fixture(scope="module")
def data() -> gpmsa.SimData:
    return five_run_data()


@pytest.fixture
def registry(monkeypatch):
    """The backend registry restored after the test (a plug-in registered in it forgotten)."""
    monkeypatch.setattr(backends, "_REGISTRY", dict(backends._REGISTRY))


def test_a_plugins_non_finite_draw_is_a_chain_error(registry, data):
    """numpy's sampler checks its own chains; a plug-in's are checked by fit."""
    module = types.ModuleType("nan_backend_s92")

    def sample(problem, *, n_iter, n_chains=1, tune=True, step_widths=None, seed=None,
               progress=False, **options):  # fmt: skip
        chains = numpy_backend.sample(problem, n_iter=n_iter, n_chains=n_chains, tune=tune,
                                      step_widths=step_widths, seed=seed, **options)  # fmt: skip
        chains.draws["lamUz"][1, 7, 0] = np.nan
        return chains

    module.sample = sample
    backends.register("nan_s92", module)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        with pytest.raises(ChainError, match=r"^1 of 2 chains .*: chain 1 \(from draw 7\)$"):
            gpmsa.fit(data, n_iter=20, n_chains=2, tune=False, seed=0, backend="nan_s92")


def _fit(data, **kw) -> gpmsa.Emulator:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # short chains: convergence warnings
        return gpmsa.fit(data, **({"n_iter": 20, "tune": False, "seed": 0} | kw))


def test_theta_init_with_a_continuation_is_refused_first(data):
    """Refused as theta_init (before the want of obs= that a simulator-only fit would say)."""
    emu = _fit(data)
    with pytest.raises(GPMSAError, match=r"^theta_init= sets a fresh chain's start; init=emulat"):
        gpmsa.fit(data, n_iter=20, tune=False, seed=0, init=emu, theta_init=[0.5])


def test_point_estimate_mean_and_map_by_hand():
    draws = {k: np.array([[0.0, 4.0], [3.0, 1.0], [6.0, 1.0]]) for k in fit_module.EMULATOR_PARAMS}
    mean = fit_module.point_estimate(draws, np.array([0.0, 2.0, 1.0]), "mean")
    best = fit_module.point_estimate(draws, np.array([0.0, 2.0, 1.0]), "map")
    for k in fit_module.EMULATOR_PARAMS:
        np.testing.assert_array_equal(mean[k], [3.0, 2.0])
        np.testing.assert_array_equal(best[k], [3.0, 1.0])


def test_thinning_by_hand():
    assert fit_module.thinning(1, 1000, 1000) == 1
    assert fit_module.thinning(2, 7, 1000) == 1
    assert fit_module.thinning(1, 1001, 1000) == 2  # ceil(1001 / 2) = 501 kept
    assert fit_module.thinning(3, 10, 4) == 10  # 8, 9 keep 3 x 2 = 6 > 4; 10 keeps 3 x 1


def test_memory_figures_by_hand():
    # (p + q + 4 p_u + 2) m^2 floats: (2 + 3 + 16 + 2) x 100 x 8 bytes
    assert fit_module._factor_nbytes(10, 2, 3, 4) == 18400.0
    # (p + q + 2) p_u + 1 = 29 elements: 16 x n_chains x n_iter x (elements + 1) bytes
    assert fit_module.simulation_fit_nbytes(10, 2, 3, 4, 50, 2) == 16.0 * 2 * 50 * 30 + 18400.0


def test_a_continuation_burns_nothing_by_default(data):
    emu = _fit(data, n_iter=20)
    assert emu.settings["n_burn"] == 4  # n_iter // 5
    more = _fit(data, n_iter=20, init=emu)
    assert more.settings["n_burn"] == 0
    assert more.n_draws == 20


def test_an_untuned_tempered_continuation_resumes_its_hot_copies(data):
    """numpy at the source's ladder: every copy resumes where it stopped, so tune=False runs."""
    emu = _fit(data, temperatures=2)
    more = _fit(data, init=emu)
    assert more.settings["tune"] is False
    assert more.settings["temperatures"] == [1.0, 2.0]


def test_a_continuation_runs_at_the_step_widths_given(data):
    emu = _fit(data)
    given = {k: [2.0 * w for w in np.ravel(v)] for k, v in emu.settings["step_widths"].items()}
    given = {k: np.reshape(v, np.shape(emu.settings["step_widths"][k])) for k, v in given.items()}
    more = _fit(data, init=emu, step_widths=given)
    for k, v in given.items():
        np.testing.assert_array_equal(more.settings["step_widths"][k], v)
    assert more.settings["joint_obs"] is False


def test_an_appended_numpy_fit_refuses_tuning(data):
    emu = _fit(data)
    with pytest.raises(GPMSAError, match=r"^append=True pools the chains' draws evenly spaced"):
        gpmsa.fit(data, n_iter=20, tune=True, seed=0, init=emu, append=True)
