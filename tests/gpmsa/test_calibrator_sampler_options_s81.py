"""A Calibrator refuses, when it is made, the ``mcmc_options`` that its MCMC update would refuse
as ``gpmsa.calibrate`` does (options without effect on that backend or engine): before, pyro's
``tune_rounds`` / ``tune_levels`` / ``step_widths``, the numpy backend's sampler options under
the fast numpy sampler, and ``fast=True`` with another backend were accepted here and refused
only at the first ``update()``."""

import numpy as np
import pytest
from _calib_cases import road_emulator, road_obs

import gpmsa
from gpmsa import Calibrator, GPMSAError, calibrate

SHORT = {"n_samples": 40, "n_burn": 5}
needs_pyro = pytest.mark.skipif("pyro" not in gpmsa.backends.available(), reason="no pyro")
needs_torch = pytest.mark.skipif("torch" not in gpmsa.backends.available(), reason="no torch")


@needs_pyro
@pytest.mark.parametrize(
    "options",
    [{"tune_rounds": 5}, {"tune_levels": 5}, {"step_widths": {"theta": 0.1}},
     {"tune_rounds": 5, "step_widths": {"theta": 0.1}}],
)  # fmt: skip
def test_pyro_refuses_gpmsa_tuning_when_made(options):
    with pytest.raises(GPMSAError) as err:
        Calibrator(road_emulator(), backend="pyro", mcmc_options={**SHORT, **options})
    msg = str(err.value)
    for key in options:  # the option, the backend, and what to do instead
        assert f"'{key}'" in msg
    assert "backend 'pyro' (NUTS)" in msg and "n_warmup" in msg and "leave" in msg


@needs_pyro
def test_pyro_still_takes_its_own_options_and_empty_widths():
    cal = Calibrator(road_emulator(), backend="pyro",
                     mcmc_options={"n_warmup": 20, "step_widths": None, **SHORT})  # fmt: skip
    assert (cal.method, cal.backend) == ("mcmc", "pyro")


@pytest.mark.parametrize(
    "options", [{"step_widths": {"theta": 0.1}}, {"init": "gpmsa"}, {"temperatures": [1.0, 2.0]}]
)
def test_the_fast_sampler_refuses_the_numpy_samplers_options_when_made(options):
    with pytest.raises(GPMSAError) as err:
        Calibrator(road_emulator(), method="mcmc", mcmc_options={**SHORT, **options})
    msg = str(err.value)
    assert str(sorted(options)) in msg and "fast numpy sampler" in msg
    assert "mcmc_options['fast'] = False" in msg  # the remedy, in the Calibrator's terms
    with pytest.raises(GPMSAError, match="fast numpy sampler"):  # explicitly fast: the same
        Calibrator(road_emulator(), method="mcmc", mcmc_options={"fast": True, **options})
    with pytest.raises(GPMSAError, match=r"mcmc_options\['fast'\] must be True or False"):
        Calibrator(road_emulator(), method="mcmc", mcmc_options={"fast": "no"})


@needs_torch
def test_fast_true_is_refused_with_another_backend_when_made():
    with pytest.raises(GPMSAError, match=r"mcmc_options\['fast'\]=True needs backend='numpy'.*"
                                         r"got backend='torch'"):  # fmt: skip
        Calibrator(road_emulator(), backend="torch", mcmc_options={"fast": True})
    # torch's own tuning is taken (and checked now, as calibrate checks it)
    assert Calibrator(road_emulator(), backend="torch", mcmc_options={"tune_rounds": 3}).backend
    with pytest.raises(GPMSAError, match=r"tune_rounds must be an integer in \[1, 1000000\]"):
        Calibrator(road_emulator(), backend="torch", mcmc_options={"tune_rounds": 0})


@pytest.mark.filterwarnings("ignore::gpmsa.ConvergenceWarning")  # 20 draws
def test_fast_false_takes_the_samplers_options_and_its_update_is_calibrates():
    """Accepted where they have effect: the update's draws are calibrate's own."""
    opts = {"fast": False, "step_widths": {"theta": 0.05}, "tune_rounds": 2, "tune_levels": 2,
            "seed": 7, "n_samples": 20, "n_burn": 2}  # fmt: skip
    x, y = road_obs()
    post = Calibrator(road_emulator(), method="mcmc", mcmc_options=opts).update(x, y)
    ref = calibrate(road_emulator(), x, y, **opts)
    assert np.array_equal(post.samples["GD"], ref.samples["GD"])
