"""A UQ engineer's walk through parallel chains (numpy processes, dask, the torch backend's
device): the refusals name the argument, why, and the remedy."""

from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import gpmsa
from gpmsa.mcmc import parallel


@pytest.fixture(scope="module")
def problem():
    from _backend_cases import multi_data

    return gpmsa.prepare(multi_data()[0]).problem


def test_cuda_without_a_gpu_says_why_and_names_the_cpu_device(problem):
    torch = pytest.importorskip("torch")
    if torch.cuda.is_available():
        pytest.skip("a CUDA device exists")
    from gpmsa import backends

    # before: "device='cuda' was asked for but torch sees no CUDA device" (no cause, no remedy)
    with pytest.raises(gpmsa.GPMSAError) as err:
        backends.get("torch").sample(problem, n_iter=2, device="cuda")
    msg = str(err.value)
    assert "device='cuda'" in msg and "torch sees no CUDA device" in msg
    assert "device='cpu' (the default)" in msg
    cause = "CPU build" if torch.version.cuda is None else "finds no GPU"
    assert cause in msg and torch.__version__ in msg


def test_one_callable_for_an_executor_is_named_in_the_singular_with_the_remedy():
    with ThreadPoolExecutor(1) as pool:
        # before: "constraint are callables of this process: they cannot go to executor= (the
        # chains run here)", a plural for one callable and no remedy
        with pytest.raises(gpmsa.GPMSAError) as one:
            parallel.in_this_process(["constraint"], None, pool, 2)
        with pytest.raises(gpmsa.GPMSAError) as two:
            parallel.in_this_process(["constraint", "mean_basis"], None, pool, 2)
    assert str(one.value).startswith("constraint is a callable of this process: it cannot go")
    assert str(two.value).startswith("constraint and mean_basis are callables of this process")
    for err in (one, two):
        assert "leave executor= out" in str(err.value) and "one after another" in str(err.value)
    assert parallel.in_this_process(["constraint"], 2, None, 2) == (1, None)
    assert parallel.in_this_process([], 2, None, 2) == (2, None)


def test_a_constrained_fit_refuses_a_dask_like_executor_by_its_callable():
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(12, 1)), rng.uniform(size=(12, 2))
    sim = gpmsa.SimData(x=x, t=t, y=x + t[:, :1] + t[:, 1:])
    obs = gpmsa.ObsData(x=[[0.2]], y=[[0.9]])
    with ThreadPoolExecutor(1) as pool, pytest.raises(gpmsa.GPMSAError) as err:
        gpmsa.fit(sim, obs, n_iter=10, n_chains=2, seed=0, executor=pool,
                  constraint=lambda th: bool(th[0] + th[1] < 1.2))  # fmt: skip
    assert "constraint is a callable of this process" in str(err.value)
    assert "leave executor= out" in str(err.value)
