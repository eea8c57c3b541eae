"""Review of session 78's torch sweep, emulator_fit arrays and device message (helper rev3).

The torch batch's memory check: with observations each chain of a batch holds its components'
observation terms (``obs_parts``: p_u n x n) and factors the observations' N x N covariance (N =
n (p_u + p_v)) at every proposal; for many observed experiments and components that, not the m x
m Sigma_W caches, is the batch's memory (100 chains, 100 experiments, 10 components, 100 runs:
~1.9 GB measured, the check's estimate 235 MiB; with one Sigma_W shared by the chains, a
calibration's, there was no check at all). emulator_fit's (None, t, y) for an emulator with
known inputs, and device='cuda' on a ROCm build without a GPU, are named.
"""

import numpy as np
import pytest

import gpmsa
from gpmsa import backends

torch = pytest.importorskip("torch")
tb = pytest.importorskip("gpmsa.backends.torch_backend")

HELD = ("betaU", "lamUz", "lamWs", "lamWOs")


def _problem(shared: bool = False, observed: bool = True):
    """40 runs of a 12-point output, 5 components, 40 observed experiments (N = 200)."""
    rng = np.random.default_rng(0)
    grid = np.linspace(0.0, 1.0, 12)

    def f(x, t):
        return sum(np.sin((k + 1) * grid[None] * (1 + t[:, :1] + k * x[:, :1])) for k in range(6))

    x, t = rng.random((40, 1)), rng.random((40, 1))
    xo = np.linspace(0.05, 0.95, 40)[:, None]
    obs = gpmsa.ObsData(x=xo, y=f(xo, np.full((40, 1), 0.4)) + 0.01 * rng.normal(size=(40, 12)))
    sim = gpmsa.SimData(x=x, t=t, y=f(x, t), index=grid)
    problem = gpmsa.prepare(sim, obs if observed else None, n_pc=5).problem
    if shared:
        problem = problem.with_init({k: problem.init[k] for k in HELD}, fixed=frozenset(HELD))
    return problem


def _no_chain(*args, **kwargs):
    raise AssertionError("a chain was set up before the memory check")


def _covariances(problem, n_chains: int) -> float:
    """The bytes of one N x N float64 observation covariance and its factor per chain."""
    big = problem.obs.sig_obs.shape[0]
    return 2.0 * 8 * n_chains * big * big


@pytest.mark.parametrize("shared", [False, True], ids=["joint", "one Sigma_W"])
def test_the_observations_covariance_per_chain_is_counted(monkeypatch, shared):
    problem = _problem(shared)
    assert problem.obs.sig_obs.shape == (200, 200) and problem.p_u == 5
    seen = []
    monkeypatch.setattr(tb, "check_memory", lambda n, what: seen.append((n, what)))
    tb.check_batch_memory(problem, 10, 500, torch.float64)
    ((nbytes, what),) = seen
    assert nbytes >= _covariances(problem, 500)
    assert "factors the observations' 200 x 200 covariance (float64) per chain," in what
    assert ("caches 5 Sigma_W's" in what) is not shared


@pytest.mark.parametrize("shared", [False, True], ids=["joint", "one Sigma_W"])
def test_a_batch_whose_observation_terms_exceed_the_limit_is_refused(monkeypatch, shared):
    problem, module = _problem(shared), backends.get("torch")
    monkeypatch.setattr(module, "BatchState", _no_chain)
    monkeypatch.setattr(gpmsa.limits, "MAX_MEMORY_BYTES", _covariances(problem, 500))
    with pytest.raises(gpmsa.ResourceLimitError, match=r"torch sample\(n_iter=2, n_chains=500\), "
                       r"which .*factors the observations' 200 x 200 covariance"):  # fmt: skip
        module.sample(problem, n_iter=2, n_chains=500, tune=False)
    with pytest.raises(AssertionError, match="before the memory check"):  # a few chains: taken
        module.sample(problem, n_iter=2, n_chains=5, tune=False)


def test_tempered_copies_count_their_observation_terms(monkeypatch):
    problem = _problem()
    seen = []
    monkeypatch.setattr(tb, "check_memory", lambda n, what: seen.append(n))
    tb.check_batch_memory(problem, 10, 20, torch.float64)
    tb.check_batch_memory(problem, 10, 20, torch.float64, copies=3)
    draws = gpmsa.mcmc.sampler.draws_nbytes(problem, 10, 20)
    assert seen[1] - draws == pytest.approx(3 * (seen[0] - draws))
    assert seen[1] - draws >= _covariances(problem, 60)


def test_without_observations_the_estimate_is_unchanged(monkeypatch):
    sim_only = _problem(observed=False)
    seen = []
    monkeypatch.setattr(tb, "check_memory", lambda n, what: seen.append((n, what)))
    tb.check_batch_memory(sim_only, 10, 4, torch.float64)
    ((nbytes, what),) = seen
    packed = sum((b - a) * b for a, b in tb.row_blocks(40))
    draws = gpmsa.mcmc.sampler.draws_nbytes(sim_only, 10, 4)
    assert nbytes == draws + 8.0 * 4 * 5 * 2 * packed
    assert what.endswith("which caches 5 Sigma_W's of 40 x 40 (float64) per chain,")


def test_emulator_fit_names_a_missing_x_of_held_out_arrays():
    """(None, t, y) for an emulator with known inputs named held_out x and the emulator's inputs
    (it read "x must be a numeric array, got None", Emulator.predict's words)."""
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    rng = np.random.default_rng(0)
    x, t = rng.random((20, 1)), rng.random((20, 1))
    sim = gpmsa.SimData(x=x, t=t, y=np.sin(3 * x) + t, x_names=["s"], t_names=["a"])
    prm = {"betaU": [[2.0], [1.0]], "lamUz": [1.0], "lamWs": [1e4], "lamWOs": [1e4]}
    emu = gpmsa.Emulator.from_params(sim, prm)
    with pytest.raises(gpmsa.GPMSAError, match=r"held_out x is None, but the emulator has 1 known "
                       r"input\(s\) \['s'\]: give their values \(runs x 1\)"):  # fmt: skip
        gpmsa.plots.emulator_fit(emu, (None, t[:2], np.sin(3 * x[:2]) + t[:2]))
    fig = gpmsa.plots.emulator_fit(emu, (x[:2], t[:2], np.sin(3 * x[:2]) + t[:2]))
    assert fig.axes[0].get_title().startswith("2 held-out runs: ")


@pytest.mark.parametrize(
    ("cuda", "hip", "why"),
    [
        (None, None, "is a CPU build"),
        ("12.4", None, "is built for CUDA 12.4 but finds no GPU (driver, CUDA_VISIBLE_DEVICES)"),
        (None, "6.2.4", "is built for ROCm (HIP 6.2.4) but finds no GPU (driver, HIP_VISIBLE"),
    ],
)
def test_cuda_without_a_gpu_names_the_build(monkeypatch, cuda, hip, why):
    """A ROCm build (torch.version.cuda None, its GPUs device 'cuda') that finds no GPU was
    called a CPU build."""
    monkeypatch.setattr(torch.version, "cuda", cuda)
    monkeypatch.setattr(torch.version, "hip", hip, raising=False)
    monkeypatch.setattr(torch.cuda, "is_available", lambda: False)
    with pytest.raises(gpmsa.GPMSAError) as err:
        tb._device("cuda")
    msg = str(err.value)
    assert msg.startswith("device='cuda' was asked for but torch sees no CUDA device (")
    assert why in msg and msg.endswith("give device='cpu' (the default), or run where torch "
                                       "sees a GPU")  # fmt: skip
