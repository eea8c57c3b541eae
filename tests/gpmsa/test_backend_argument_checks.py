"""Backend arguments and imports: a clear GPMSAError / BackendUnavailableError, never a silent
misreading or a crash inside torch; torch's global state left as it was."""

import sys
import types

import numpy as np
import pytest

from gpmsa import backends
from gpmsa.errors import BackendUnavailableError, GPMSAError

torch = pytest.importorskip("torch")
tb = pytest.importorskip("gpmsa.backends.torch_backend")


@pytest.fixture(scope="module")
def problem():
    from _backend_cases import multi_problem

    return multi_problem().problem


def _forget_backends(monkeypatch) -> None:
    """Make the next ``backends.get`` import the torch/pyro backend modules afresh."""
    for mod in list(sys.modules):
        if mod.startswith("gpmsa.backends.") and mod != "gpmsa.backends.numpy_backend":
            monkeypatch.delitem(sys.modules, mod)


def test_an_incompatible_package_version_is_an_unavailable_backend(monkeypatch):
    """A pyro-ppl whose API does not match (an ImportError, not ModuleNotFoundError): the
    backend is unavailable with a hint, and ``available()`` still lists the others."""
    pytest.importorskip("pyro.distributions")  # the real modules the backend imports first
    _forget_backends(monkeypatch)
    monkeypatch.setitem(sys.modules, "pyro.infer", types.ModuleType("pyro.infer"))  # no MCMC
    with pytest.raises(BackendUnavailableError, match=r"'pyro'.*fail to import.*MCMC.*pip install"):
        backends.get("pyro")
    assert backends.available() == ("numpy", "torch")


def test_a_library_that_fails_to_load_is_an_unavailable_backend(monkeypatch):
    """torch installed but its shared libraries missing (an OSError on import)."""

    def import_module(path):
        raise OSError("libtorch_cuda.so: cannot open shared object file")

    monkeypatch.setattr(backends, "importlib", types.SimpleNamespace(import_module=import_module))
    with pytest.raises(BackendUnavailableError, match=r"'torch'.*OSError: libtorch_cuda\.so"):
        backends.get("torch")
    assert "torch" not in backends.available()


def test_a_gpmsa_import_error_is_not_hidden_as_a_missing_package(monkeypatch):
    def import_module(path):
        raise ImportError("cannot import name 'x' from 'gpmsa.mcmc.sampler'",
                          name="gpmsa.mcmc.sampler")  # fmt: skip

    monkeypatch.setattr(backends, "importlib", types.SimpleNamespace(import_module=import_module))
    with pytest.raises(ImportError, match="gpmsa.mcmc.sampler") as info:
        backends.get("torch")
    assert not isinstance(info.value, BackendUnavailableError)


@pytest.mark.parametrize(
    ("option", "message"),
    [
        ({"tune": "no"}, "tune must be True or False, got 'no'"),
        ({"progress": "yes"}, "progress must be True or False, got 'yes'"),
        ({"warmup": True}, "warmup must be an integer >= 0, got True"),
        ({"tune_stages": True}, "tune_stages must be an integer >= 1, got True"),
        ({"tune_stages": 0, "tune": False}, "tune_stages must be an integer >= 1, got 0"),
        ({"dtype": np.dtype("float32")}, r"dtype must be 'float64' or 'float32', got dtype"),
        ({"dtype": np.float64}, r"dtype must be 'float64' or 'float32', got <class"),
    ],
)
def test_torch_options_are_checked_not_read_loosely(problem, option, message):
    """tune="no" used to tune (a truthy string), a numpy dtype to crash in getattr."""
    kw = {"n_iter": 4, "tune": False, "seed": 1, **option}
    with pytest.raises(GPMSAError, match=message):
        tb.sample(problem, **kw)


def test_pyro_progress_is_checked(problem):
    pb = backends.get("pyro")
    with pytest.raises(GPMSAError, match="progress must be True or False, got 'no'"):
        pb.sample(problem, n_iter=4, progress="no")


def test_a_cuda_index_beyond_the_devices_is_refused(problem, monkeypatch):
    """cuda:1 on a one-GPU machine: a GPMSAError naming the devices torch sees, before any
    tensor is placed (simulated: torch is told one CUDA device exists)."""
    monkeypatch.setattr(torch.cuda, "is_available", lambda: True)
    monkeypatch.setattr(torch.cuda, "device_count", lambda: 1)
    with pytest.raises(GPMSAError, match=r"device='cuda:1'.*sees 1 CUDA device\(s\): cuda:0"):
        tb.sample(problem, n_iter=4, tune=False, device="cuda:1")


def test_torch_global_state_is_restored_after_sampling(problem):
    """Thread count and default dtype as before, after a run and after a refused run."""
    threads, dtype = torch.get_num_threads(), torch.get_default_dtype()
    other = 2 if threads == 1 else 1
    torch.set_num_threads(other)
    try:
        chains = tb.sample(problem, n_iter=4, tune=False, seed=1, num_threads=1)
        assert chains.draws["theta"].dtype == np.float64
        assert torch.get_num_threads() == other
        with pytest.raises(GPMSAError, match="device must be"):
            tb.sample(problem, n_iter=4, tune=False, device="tpu", num_threads=1)
        assert torch.get_num_threads() == other
        assert torch.get_default_dtype() == dtype
    finally:
        torch.set_num_threads(threads)
