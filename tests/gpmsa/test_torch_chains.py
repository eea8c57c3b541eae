"""Batched torch chains: CPU and GPU code paths agree, 64 chains converge, CUDA where present."""

import numpy as np
import pytest
from threadpoolctl import threadpool_limits

import gpmsa
from gpmsa import backends
from gpmsa.mcmc.diagnostics import rhat
from gpmsa.model.likelihood import log_posterior

torch = pytest.importorskip("torch")
tb = pytest.importorskip("gpmsa.backends.torch_backend")


@pytest.fixture(autouse=True)
def one_blas_thread():
    """BatchState and ChainState used directly: LAPACK on one thread, as the samplers run it."""
    with threadpool_limits(1):
        yield


def _cases():
    from _backend_cases import multi_problem, road_problem

    return {
        "road-sim": road_problem(False).problem,
        "road-joint": road_problem(True).problem,
        "multi-discrepancy": multi_problem("constant").problem,
    }


@pytest.mark.parametrize("case", ["road-sim", "road-joint", "multi-discrepancy"])
def test_batched_path_for_gpus_equals_the_lapack_path(case, monkeypatch):
    """The batched torch ops that a GPU runs (forced here on the CPU) and the per-chain LAPACK
    path give the same cached state after the same sweeps, and both the numpy log posterior."""
    problem = _cases()[case]
    widths = np.array([0.1] * len(gpmsa.mcmc.sampler.elements(problem)))
    states = {}
    for path in ("lapack", "batched"):
        if path == "batched":
            monkeypatch.setattr(tb, "_on_lapack", lambda t: False)
        state = tb.BatchState(problem, 3, torch.float64, "cpu", ridge_moves=2)
        gen = torch.Generator().manual_seed(0)
        for _ in range(6):
            state.sweep(widths, True, gen)
        states[path] = state
    a, b = states["lapack"], states["batched"]
    for name, val in a.params.items():
        np.testing.assert_allclose(b.params[name].numpy(), val.numpy(), rtol=1e-9, err_msg=name)
    want = [log_posterior(problem, {k: v[c].numpy() for k, v in a.params.items()})
            for c in range(3)]  # fmt: skip
    np.testing.assert_allclose(a.log_post().numpy(), want, rtol=1e-9, atol=1e-7)
    np.testing.assert_allclose(b.log_post().numpy(), want, rtol=1e-9, atol=1e-7)


def test_same_starts_as_the_numpy_chains_and_nan_starts_named():
    from _backend_cases import multi_data

    problem = gpmsa.prepare(multi_data()[0]).problem
    got = backends.get("torch").sample(problem, n_iter=3, n_chains=4, seed=9, tune=False)
    ref = backends.get("numpy").sample(problem, n_iter=3, n_chains=4, seed=9, tune=False)
    assert got.info["init"] == "jitter" and got.info["tune_stages"] == 1
    for name, val in ref.info["starts"].items():
        np.testing.assert_allclose(got.info["starts"][name], val, rtol=1e-15)
    w = problem.w.copy()
    w[0, 1] = np.nan
    import dataclasses

    bad = dataclasses.replace(problem, w=w)
    with pytest.raises(gpmsa.ChainError, match=r"chain\(s\) \[0, 1\] give a log-likelihood"):
        backends.get("torch").sample(bad, n_iter=3, n_chains=2, seed=1)


def _max_rhat(chains, burn: float = 0.2) -> tuple[float, str]:
    worst = (0.0, "")
    for name, d in chains.draws.items():
        if np.ptp(d) == 0:
            continue
        d = d[:, int(burn * d.shape[1]) :]
        flat = d.reshape(d.shape[0], d.shape[1], -1)
        for i in range(flat.shape[2]):
            worst = max(worst, (rhat(flat[:, :, i]), f"{name}[{i}]"))
    return worst


@pytest.mark.slow
def test_64_chains_converge_on_a_multivariate_case_with_the_defaults():
    """64 chains from dispersed starts, default warm-up and tuning: R-hat < 1.01 everywhere."""
    from _backend_cases import multi_data

    problem = gpmsa.prepare(multi_data()[0]).problem
    chains = backends.get("torch").sample(problem, n_iter=2500, n_chains=64, seed=11)
    r, where = _max_rhat(chains)
    assert r < 1.01, f"max R-hat {r:.4f} at {where}"


@pytest.mark.slow
def test_64_chains_converge_on_the_road_case_with_the_defaults():
    from _backend_cases import road_problem

    problem = road_problem(False).problem
    chains = backends.get("torch").sample(problem, n_iter=2000, n_chains=64, seed=12)
    r, where = _max_rhat(chains)
    assert r < 1.01, f"max R-hat {r:.4f} at {where}"


@pytest.mark.skipif(not torch.cuda.is_available(), reason="no CUDA device")
def test_cuda_chains_agree_with_the_cpu_and_numpy():
    """The GPU path: float64 chains on CUDA give the posterior of the numpy backend."""
    from _backend_cases import multi_data
    from test_backend_agreement import _elements, assert_agree

    problem = gpmsa.prepare(multi_data()[0]).problem
    got = backends.get("torch").sample(problem, n_iter=600, n_chains=64, seed=4, device="cuda")
    assert got.info["device"].startswith("cuda")
    ref = backends.get("numpy").sample(problem, n_iter=4000, seed=3)
    for name in ("betaU", "lamUz", "lamWs", "lamWOs"):
        for k, (a, b) in enumerate(zip(_elements(got, name), _elements(ref, name), strict=True)):
            assert_agree(a, b, f"cuda {name}[{k}]")


def test_cuda_request_without_a_device_is_refused():
    if torch.cuda.is_available():
        pytest.skip("a CUDA device exists")
    from _backend_cases import multi_data

    problem = gpmsa.prepare(multi_data()[0]).problem
    with pytest.raises(gpmsa.GPMSAError, match="torch sees no CUDA device"):
        backends.get("torch").sample(problem, n_iter=2, device="cuda")


# --- chain groups: the sampling phase in worker processes -----------------------------------
def _grouped(problem, **kw):
    return backends.get("torch").sample(problem, n_iter=12, n_chains=6, seed=21, warmup=4,
                                        tune_stages=1, tune_rounds=1, chain_groups=3,
                                        **kw)  # fmt: skip


def test_chain_groups_give_the_same_draws_with_any_number_of_workers():
    """Groups of consecutive chains, each in a worker process with its own stream: the draws
    depend on chain_groups and seed only; every chain's draws and log posterior stay together."""
    from concurrent.futures import ThreadPoolExecutor

    from _backend_cases import multi_data

    problem = gpmsa.prepare(multi_data()[0]).problem
    runs = [_grouped(problem, n_jobs=1)]
    if gpmsa.mcmc.parallel.available_cpus() >= 2:
        runs.append(_grouped(problem, n_jobs=2))
    with ThreadPoolExecutor(2) as ex:
        runs.append(_grouped(problem, executor=ex))
    first = runs[0]
    assert first.info["chain_groups"] == 3 and first.draws["betaU"].shape[:2] == (6, 12)
    for other in runs[1:]:
        for name, val in first.draws.items():
            assert np.array_equal(other.draws[name], val), name
        assert np.array_equal(other.log_post, first.log_post)
    for c in range(6):  # each group's state (caches included) is its chains' own
        params = {k: v[c, -1] for k, v in first.draws.items()}
        assert np.isclose(first.log_post[c, -1], log_posterior(problem, params), rtol=1e-9)
    assert np.isfinite(first.accept_rate["betaU"]).all()
    one_batch = backends.get("torch").sample(problem, n_iter=12, n_chains=6, seed=21, warmup=4,
                                             tune_stages=1, tune_rounds=1)  # fmt: skip
    assert one_batch.info["chain_groups"] == 1
    assert not np.array_equal(one_batch.log_post, first.log_post)  # other streams


@pytest.mark.filterwarnings("ignore::gpmsa.ConvergenceWarning")  # 4 chains x 8 draws
def test_fit_takes_chain_groups_and_n_jobs_for_torch(tmp_path, capsys):
    """gpmsa.fit passes n_jobs and the torch options on, and records the options it used."""
    from _backend_cases import multi_data

    emu = gpmsa.fit(multi_data()[0], n_iter=10, n_chains=4, backend="torch", seed=2, n_jobs=2,
                    chain_groups=2, warmup=2, tune_stages=1, tune_rounds=1)  # fmt: skip
    assert emu.settings["backend_options"] == {"chain_groups": 2, "tune_rounds": 1,
                                               "tune_stages": 1, "warmup": 2}  # fmt: skip
    from gpmsa.cli.main import main

    path = emu.save(tmp_path / "torch.gpmsa")
    assert gpmsa.load(path).settings["backend_options"] == emu.settings["backend_options"]
    assert main(["info", str(path)]) == 0
    assert "backend options: chain_groups=2, tune_rounds=1" in capsys.readouterr().out


def test_bad_chain_groups_are_named():
    from concurrent.futures import ThreadPoolExecutor

    from _backend_cases import multi_data
    from test_chains import RefusingExecutor

    problem = gpmsa.prepare(multi_data()[0]).problem
    for bad in (0, 7, True, 2.0):
        with pytest.raises(gpmsa.GPMSAError, match=r"chain_groups must be an integer in \[1, "):
            backends.get("torch").sample(problem, n_iter=2, n_chains=6, chain_groups=bad)
    with pytest.raises(gpmsa.GPMSAError, match="run CPU worker processes; device='cuda'"):
        _grouped(problem, device="cuda")
    with pytest.raises(gpmsa.GPMSAError, match="runs one thread: give num_threads=1"):
        _grouped(problem, num_threads=2)
    with pytest.raises(gpmsa.GPMSAError, match="n_jobs=4096 is more than"):
        _grouped(problem, n_jobs=4096)
    with ThreadPoolExecutor(1) as ex, pytest.raises(gpmsa.GPMSAError, match="not both"):
        _grouped(problem, n_jobs=1, executor=ex)
    with RefusingExecutor(1) as ex, pytest.warns(RuntimeWarning, match="running it again"):
        with pytest.raises(gpmsa.ChainError, match=r"chains 0-1: chain group 0 of 3 failed "
                                                   r"after 2 attempts") as info:  # fmt: skip
            _grouped(problem, executor=ex)
    assert info.value.chains == (0, 1)


@pytest.mark.parametrize("changes", [{"garbage": (None,)}, {"n_iter": 5}], ids=["tuple", "short"])
def test_a_group_executor_that_returns_wrong_results_names_the_group_s_chains(changes):
    """Not a TypeError while the groups' draws are joined, nor a silent run with other draws."""
    from _backend_cases import multi_data
    from test_chains import ReturnsOther

    problem = gpmsa.prepare(multi_data()[0]).problem
    with ReturnsOther(**changes) as ex, pytest.raises(gpmsa.ChainError) as exc:
        _grouped(problem, executor=ex)
    assert exc.value.chains == (0, 1)
    assert "chain group 0 of 3 returned a tuple that is not its draws (2 chains x 12" in str(
        exc.value
    )
