"""``gpmsa.calibrate`` records the versions of what ran its chains in the Posterior's
``info["versions"]``, as ``fit`` records them in ``settings["versions"]`` (before: none, so a
posterior kept beside a seeded result could not say which numpy, BLAS or plug-in made it)."""

import types

import numpy as np
import pytest
from _calib_cases import road_emulator, road_obs

import gpmsa
from gpmsa import backends
from gpmsa.backends import numpy_backend

pytestmark = pytest.mark.filterwarnings("ignore::gpmsa.ConvergenceWarning")

TUNING = {"tune_rounds": 1, "tune_levels": 3}


@pytest.fixture
def registry(monkeypatch):
    """The registry restored after the test (a plug-in registered in it forgotten)."""
    monkeypatch.setattr(backends, "_REGISTRY", dict(backends._REGISTRY))


@pytest.mark.parametrize("fast", [True, False])
def test_calibrate_records_the_versions_that_ran_it(fast):
    post = gpmsa.calibrate(road_emulator(), *road_obs(), n_samples=30, n_burn=5, seed=1,
                           fast=fast, **TUNING)  # fmt: skip
    versions = post.info["versions"]
    assert versions["gpmsa"] == gpmsa.__version__
    assert versions["numpy"] == np.__version__
    assert {"python", "scipy", "machine", "blas"} <= set(versions)
    assert not any(k.startswith("backend") for k in versions)


def test_calibrate_on_a_plugin_records_its_module_and_version(registry):
    module = types.ModuleType("calibrate_versions_s88")
    module.__version__ = "3.1"

    def sample(problem, *, n_iter, n_chains=1, tune=True, step_widths=None, seed=None,
               progress=False, **options):  # fmt: skip
        return numpy_backend.sample(problem, n_iter=n_iter, n_chains=n_chains, tune=tune,
                                    step_widths=step_widths, seed=seed, **options)  # fmt: skip

    module.sample = sample
    backends.register("mine", module)
    post = gpmsa.calibrate(road_emulator(), *road_obs(), n_samples=30, n_burn=5, seed=1,
                           backend="mine", fast=False, **TUNING)  # fmt: skip
    assert post.info["backend"] == "mine"
    assert post.info["versions"]["backend mine"] == "calibrate_versions_s88 3.1"
