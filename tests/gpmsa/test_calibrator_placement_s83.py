"""A Calibrator on the pyro or torch backend refuses, when it is made, an ``n_jobs`` (or, on
pyro, an ``executor``) in ``mcmc_options`` that its MCMC update refuses whatever the data, with
the update's own message. Before: ``Calibrator(emu, backend="pyro", mcmc_options={"n_jobs":
2})`` (and torch's with one chain group) was made, and refused only at its first ``update``."""

from concurrent.futures import ThreadPoolExecutor

import pytest
from _calib_cases import road_emulator, road_obs

import gpmsa
from gpmsa import Calibrator, GPMSAError
from tests._extras import PYRO, TORCH, backend_needs

SHORT = {"n_samples": 8, "n_burn": 2, "seed": 1}
PYRO_JOBS = "n_jobs=2: the pyro backend runs its chains one after another in this process"
TORCH_JOBS = "n_jobs=2 with chain_groups=1: the torch backend samples its chains as one batch"
BAD_JOBS = r"n_jobs must be None or -1 \(every CPU\) or an integer >= 1, got 0"


def _case(backend: str, options: dict, match: str):
    return pytest.param(backend, options, match, marks=backend_needs(backend))


@pytest.mark.parametrize(
    ("backend", "options", "match"),
    [
        _case("pyro", {"n_jobs": 2}, PYRO_JOBS),
        _case("pyro", {"n_jobs": 2, "n_chains": 2}, PYRO_JOBS),
        _case("pyro", {"n_jobs": 0}, BAD_JOBS),
        _case("pyro", {"executor": "pool"}, "backend 'pyro' runs its chains in one "
         "process: it takes no executor="),
        _case("torch", {"n_jobs": 2}, TORCH_JOBS),
        _case("torch", {"n_jobs": 2, "n_chains": 2, "chain_groups": 1}, TORCH_JOBS),
        _case("torch", {"n_jobs": 0}, BAD_JOBS),
    ],
)  # fmt: skip
def test_refused_when_made_with_the_updates_message(backend, options, match):
    with ThreadPoolExecutor(1) as pool:
        options = {k: pool if v == "pool" else v for k, v in options.items()}
        with pytest.raises(GPMSAError, match=match):
            Calibrator(road_emulator(), backend=backend, mcmc_options={**SHORT, **options})
        with pytest.raises(GPMSAError, match=match):  # gpmsa.calibrate's refusal, as the update's
            gpmsa.calibrate(road_emulator(), *road_obs(), backend=backend, **SHORT, **options)


@PYRO
@pytest.mark.filterwarnings("ignore::gpmsa.ConvergenceWarning")
def test_pyro_still_takes_n_jobs_it_runs():
    for n_jobs in (None, 1, -1):
        cal = Calibrator(road_emulator(), backend="pyro", mcmc_options={**SHORT, "n_jobs": n_jobs})
        assert cal.mcmc_options["n_jobs"] == n_jobs


@TORCH
def test_torch_leaves_several_groups_to_the_update():
    """With chain groups the refusal depends on the chains and the CPUs (checked at update)."""
    groups = {"n_jobs": 2, "n_chains": 2, "chain_groups": 2, "num_threads": 1}
    for options in (groups, {"n_jobs": -1}, {"n_jobs": 1}, {"chain_groups": True, "n_jobs": 2}):
        assert Calibrator(road_emulator(), backend="torch", mcmc_options=options).method == "mcmc"
