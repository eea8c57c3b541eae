"""Backend parity sweep (session 80): the checks, warnings and records of ``fit``,
``calibrate`` and ``Calibrator`` compared across numpy, torch and pyro. Two gaps mended:

- an emulator fitted with a callable mean basis (a lambda) took its chains to worker processes
  in ``calibrate`` (the fast sampler and ``fast=False``) and ``calibrate_study`` whenever
  ``n_chains`` > 1: a ChainError (PicklingError) with the defaults, where ``fit`` and the torch
  backend keep such chains in this process and refuse an ``executor=`` by name (as the docs
  say of every MCMC);
- continuing a fast-sampler Posterior with ``backend='torch'`` (or pyro) advised "leave fast=
  out", an argument the caller never gave: it now names the backend."""

import warnings
from concurrent.futures import ThreadPoolExecutor
from functools import cache

import numpy as np
import pytest
from _calib_cases import road_emulator, road_obs
from _continue_cases import continue_data

import gpmsa
from gpmsa import GPMSAError

SHORT = {"n_samples": 30, "n_burn": 5, "tune_rounds": 2, "tune_levels": 5, "seed": 1}
X_OBS, Y_OBS = [[0.2]], [[float(np.sin(0.6) + 0.16)]]
EXECUTOR = "mean_basis is a callable of this process: it cannot go to executor="


def _quiet(call, *args, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        return call(*args, **kw)


@cache
def _callable_mean_emulator() -> gpmsa.Emulator:
    """A simulation-only fit whose mean basis is a lambda (no pickle)."""
    return _quiet(gpmsa.fit, continue_data()[0], n_iter=40, n_keep=20, tune=False, seed=0,
                  mean_basis=lambda z: z[:, :1])  # fmt: skip


@pytest.mark.parametrize("fast", [None, False])
def test_calibrate_keeps_a_callable_mean_basis_s_chains_in_this_process(fast):
    emu = _callable_mean_emulator()
    kw = {**SHORT, "n_chains": 2, **({} if fast is None else {"fast": fast})}
    # before: ChainError "chain 0 of 2 failed after 2 attempts: PicklingError"
    post = _quiet(gpmsa.calibrate, emu, X_OBS, Y_OBS, **kw)
    here = _quiet(gpmsa.calibrate, emu, X_OBS, Y_OBS, n_jobs=1, **kw)
    assert post.info["engine"] == ("fast" if fast is None else "backend")
    np.testing.assert_array_equal(post.samples["t"], here.samples["t"])
    assert post.samples["t"].shape == (50,)
    with ThreadPoolExecutor(1) as pool, pytest.raises(GPMSAError, match=EXECUTOR):
        gpmsa.calibrate(emu, X_OBS, Y_OBS, executor=pool, **kw)


def test_torch_refuses_the_executor_as_numpy_now_does():
    pytest.importorskip("torch")
    with ThreadPoolExecutor(1) as pool, pytest.raises(GPMSAError, match=EXECUTOR):
        gpmsa.calibrate(_callable_mean_emulator(), X_OBS, Y_OBS, backend="torch", n_chains=2,
                        executor=pool, **SHORT)  # fmt: skip


def test_calibrate_study_keeps_a_callable_mean_basis_s_chains_in_this_process():
    emu = _callable_mean_emulator()
    kw = {**SHORT, "n_chains": 2, "shared": ["t"]}
    study = _quiet(gpmsa.calibrate_study, [emu, emu], [X_OBS, X_OBS], [Y_OBS, Y_OBS], **kw)
    here = _quiet(gpmsa.calibrate_study, [emu, emu], [X_OBS, X_OBS], [Y_OBS, Y_OBS], n_jobs=1,
                  **kw)  # fmt: skip
    first, second = study.posterior.samples, here.posterior.samples
    assert set(first) == set(second) and first
    for name in first:
        np.testing.assert_array_equal(first[name], second[name])
    with ThreadPoolExecutor(1) as pool, pytest.raises(GPMSAError, match=EXECUTOR):
        gpmsa.calibrate_study([emu, emu], [X_OBS, X_OBS], [Y_OBS, Y_OBS], executor=pool, **kw)


@pytest.mark.parametrize("backend", ["torch", "pyro"])
def test_a_fast_posterior_continued_on_another_backend_names_the_backend(backend):
    pytest.importorskip("torch" if backend == "torch" else "pyro")
    x, y = road_obs()
    source = _quiet(gpmsa.calibrate, road_emulator(), x, y, **SHORT)
    assert source.info["engine"] == "fast"
    # before: "...its continuation runs there too: leave fast= out" (fast= was never given)
    with pytest.raises(GPMSAError, match=rf"ran on the fast numpy sampler .* leave "
                       rf"backend='{backend}' out \(and fast=\): the fast sampler is the numpy "
                       "backend's"):  # fmt: skip
        gpmsa.calibrate(road_emulator(), x, y, init=source, backend=backend, n_samples=10)
    with pytest.raises(GPMSAError, match=r"continuation runs there too: leave fast= out$"):
        gpmsa.calibrate(road_emulator(), x, y, init=source, fast=False, n_samples=10)
