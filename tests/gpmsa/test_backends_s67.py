"""Backend choices made once and kept (session 67): the Calibrator's MCMC backend."""

import pytest
from _calib_cases import road_emulator, road_obs

from gpmsa import Calibrator, GPMSAError

pytest.importorskip("torch")


def test_calibrator_takes_the_backend_of_its_mcmc_options():
    """mcmc_options={"backend": "torch"} chose the grid (numpy) for one parameter and ran it
    there, the torch backend silently unused; now it is the Calibrator's backend."""
    cal = Calibrator(road_emulator(), mcmc_options={"backend": "torch"})
    assert (cal.method, cal.backend) == ("mcmc", "torch")
    with pytest.raises(GPMSAError, match="method='grid' runs on numpy"):
        Calibrator(road_emulator(), method="grid", mcmc_options={"backend": "torch"})


def test_calibrator_backends_that_disagree_or_are_unknown_are_refused_up_front():
    with pytest.raises(GPMSAError, match=r"backend='torch' and mcmc_options\['backend'\]='pyro'"):
        Calibrator(road_emulator(), backend="torch", mcmc_options={"backend": "pyro"})
    with pytest.raises(GPMSAError, match="unknown backend 'jax'"):
        Calibrator(road_emulator(), method="mcmc", mcmc_options={"backend": "jax"})


@pytest.mark.parametrize(
    ("backend", "options"),
    [("torch", {"dtype": "float32", "num_threads": 1}), ("pyro", {"n_warmup": 50})],
)
def test_calibrator_passes_backend_options_on_as_calibrate_takes_them(backend, options):
    """mcmc_options refused every backend option ("unknown keyword(s) ['dtype']"), though
    gpmsa.calibrate takes them: a Calibrator could not set torch's dtype or pyro's warm-up."""
    cal = Calibrator(road_emulator(), backend=backend, mcmc_options=options)
    assert cal.mcmc_options == options
    if backend == "torch":  # a short run: the options reach the sampler
        run = {"n_samples": 12, "n_burn": 0, "tune": False}
        cal = Calibrator(road_emulator(), backend=backend, mcmc_options={**options, **run})
        post = cal.update(*road_obs())
        assert post.info["backend_options"] == options
    with pytest.raises(GPMSAError, match=r"unknown keyword\(s\) \['options'\]"):
        Calibrator(road_emulator(), backend=backend, mcmc_options={"options": options})


def test_calibrator_refuses_another_backend_s_options_naming_what_it_takes():
    with pytest.raises(GPMSAError, match=r"\['n_warmup'\].*'torch' backend"):
        Calibrator(road_emulator(), backend="torch", mcmc_options={"n_warmup": 50})
    with pytest.raises(GPMSAError, match=r"\['dtype'\].*'pyro' backend"):
        Calibrator(road_emulator(), backend="pyro", mcmc_options={"dtype": "float32"})


def test_an_explicit_numpy_backend_is_not_overridden_by_mcmc_options():
    """(s68) backend="numpy" looked the same as the default, so mcmc_options["backend"] took
    over silently; now the default is None and an explicit backend that disagrees is refused."""
    with pytest.raises(GPMSAError, match=r"backend='numpy' and mcmc_options\['backend'\]='torch'"):
        Calibrator(road_emulator(), backend="numpy", mcmc_options={"backend": "torch"})
    assert Calibrator(road_emulator()).backend == "numpy"  # the default as before
    same = Calibrator(road_emulator(), backend="numpy", mcmc_options={"backend": "numpy"})
    assert same.backend == "numpy"
    assert Calibrator(road_emulator(), backend="torch").backend == "torch"
