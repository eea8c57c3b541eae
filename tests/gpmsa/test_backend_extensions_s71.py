"""The torch and pyro backends on categorical inputs, a mean basis and a theta constraint
(docs/categorical-and-constraints.md): the same log posterior as the numpy likelihood, the
numpy sampler's moves (a categorical theta to another level, a constraint's proposals
rejected), and pyro's refusals naming what NUTS cannot sample."""

from dataclasses import replace

import numpy as np
import pytest

import gpmsa
from gpmsa.mcmc import starts
from gpmsa.model import constraints
from gpmsa.model.likelihood import log_posterior
from gpmsa.model.problem import prepare

torch = pytest.importorskip("torch")
tb = pytest.importorskip("gpmsa.backends.torch_backend")

RTOL = 1e-10


@pytest.fixture(autouse=True)
def _one_thread():
    with tb.torch_threads(1):
        yield


def _square(z: np.ndarray) -> np.ndarray:
    return np.column_stack([np.ones(len(z)), z[:, 0] ** 2])


MEAN_BASES = [None, "constant", "linear", _square]


def _data(t_categorical: bool = True):
    """24 runs over x = (s, kind in 0..2), t = (k, level in 0..2 or continuous), output on a
    5-point grid; two experiments."""
    rng = np.random.default_rng(0)
    m = 24
    x = np.column_stack([rng.random(m), np.arange(m) % 3])
    t = np.column_stack([rng.random(m), rng.integers(0, 3, m) if t_categorical else rng.random(m)])
    y = np.column_stack([np.sin(3 * x[:, 0] + t[:, 0]) + x[:, 1] + 0.5 * t[:, 1] + 0.1 * k * x[:, 0]
                         for k in range(5)])  # fmt: skip
    sim = gpmsa.SimData(x, t, y, x_categorical=[1], t_categorical=[1] if t_categorical else None,
                        index=np.linspace(0, 1, 5))  # fmt: skip
    obs = gpmsa.ObsData(x=np.array([[0.3, 1], [0.7, 2]]), y=y[:2] + 0.01)
    return sim, obs


def _problem(mean_basis, with_obs: bool, discrepancy=None, t_categorical: bool = True):
    sim, obs = _data(t_categorical)
    prep = prepare(sim, obs if with_obs else None, mean_basis=mean_basis,
                   discrepancy=discrepancy, n_pc=2)  # fmt: skip
    return prep


def _starts(prob, n: int = 4) -> dict[str, np.ndarray]:
    """Dispersed starts (a categorical theta at levels)."""
    _, firsts = starts.chain_starts(prob, "auto", np.random.SeedSequence(1).spawn(n))
    return {k: np.stack([f[k] for f in firsts]) for k in prob.init}


def _numpy_log_post(prob, params: dict[str, np.ndarray]) -> np.ndarray:
    n = next(iter(params.values())).shape[0]
    return np.array([log_posterior(prob, {k: v[c] for k, v in params.items()}) for c in range(n)])


@pytest.mark.parametrize("mean_basis", MEAN_BASES, ids=["zero", "constant", "linear", "callable"])
@pytest.mark.parametrize(("with_obs", "discrepancy"), [(False, None), (True, "linear")])
@pytest.mark.parametrize("lapack", [True, False], ids=["cpu-lapack", "batched"])
def test_torch_log_posterior_equals_numpy_on_the_extensions(mean_basis, with_obs, discrepancy,
                                                            lapack, monkeypatch):  # fmt: skip
    if not lapack:  # the batched path a GPU takes
        monkeypatch.setattr(tb, "_on_lapack", lambda t: False)
    prob = _problem(mean_basis, with_obs, discrepancy).problem
    start = _starts(prob)
    if with_obs:
        assert set(np.unique(start["theta"][:, 1])) <= {0.0, 0.5, 1.0}
    state = tb.BatchState(prob, 4, torch.float64, "cpu", start)
    np.testing.assert_allclose(state.log_post().numpy(), _numpy_log_post(prob, start), rtol=RTOL)


def test_level_move_is_the_numpy_samplers():
    """others[int(u * others.size)] over the other levels, in order."""
    prob = _problem(None, True).problem
    state = tb.BatchState(prob, 1, torch.float64, "cpu")
    lv = np.array([0.0, 0.5, 1.0])
    for x in lv:
        others = lv[lv != x]
        for u in (0.0, 0.3, 0.49, 0.5, 0.99):
            cand, ok = state._level_move(1, torch.tensor([x], dtype=torch.float64),
                                         torch.tensor([u], dtype=torch.float64))  # fmt: skip
            assert bool(ok[0]) and cand.item() == others[int(u * others.size)]


def _constrained(prep):
    std = prep.standardizer
    con = constraints.make(lambda th: th[0] < 0.8, std.t_min, std.t_max, ("k", "level"))
    return replace(prep.problem, constraint=con)


def test_torch_chains_move_on_levels_inside_the_constraint_with_numpy_s_log_posterior():
    prep = _problem("linear", True, "linear")
    prob = _constrained(prep)
    ch = tb.sample(prob, n_iter=40, n_chains=3, seed=3, warmup=4, tune_rounds=1, tune_levels=3,
                   tune_stages=1)  # fmt: skip
    theta = ch.draws["theta"]
    # every level visited (the chains start at 0.5; P(level) 0.77 / 0.17 / 0.06 with the joint
    # level move, session 72: 12 sweeps, enough before it, stay at 0)
    assert set(np.unique(theta[..., 1])) == {0.0, 0.5, 1.0}
    native = prep.standardizer.t_from_unit(theta.reshape(-1, 2))
    assert np.all(native[:, 0] < 0.8)
    draws = {k: v.reshape(-1, *v.shape[2:]) for k, v in ch.draws.items()}
    np.testing.assert_allclose(ch.log_post.reshape(-1), _numpy_log_post(prob, draws), rtol=RTOL)


def test_torch_callables_keep_chain_groups_in_this_process():
    """A lambda constraint cannot go to a worker process: the groups run here (as the numpy
    backend's chains), the same draws as with n_jobs=1; an executor is refused."""
    from concurrent.futures import ThreadPoolExecutor

    prob = _constrained(_problem("constant", True))
    kw = {"n_iter": 4, "n_chains": 4, "seed": 2, "tune": False, "warmup": 2, "chain_groups": 2}
    a = tb.sample(prob, n_jobs=2, **kw)
    b = tb.sample(prob, n_jobs=1, **kw)
    assert np.array_equal(a.log_post, b.log_post)
    refused = pytest.raises(gpmsa.GPMSAError, match="constraint is a callable")
    with ThreadPoolExecutor(1) as pool, refused:
        tb.sample(prob, executor=pool, **kw)


def test_torch_refuses_a_start_outside_the_constraint_as_numpy():
    prep = _problem(None, True)
    std = prep.standardizer
    con = constraints.make(lambda th: th[0] > 2.0, std.t_min, std.t_max, ("k", "level"))
    prob = replace(prep.problem, constraint=con)
    with pytest.raises(gpmsa.GPMSAError, match="theta constraint rejects"):
        tb.sample(prob, n_iter=2, tune=False)


@pytest.mark.parametrize("mean_basis", ["linear", _square], ids=["linear", "callable"])
def test_pyro_log_posterior_equals_numpy_with_categorical_x_and_a_mean_basis(mean_basis):
    pb = pytest.importorskip("gpmsa.backends.pyro_backend")
    prob = _problem(mean_basis, True, "linear", t_categorical=False).problem
    if mean_basis is _square:  # a callable of theta: theta held
        prob = prob.with_fixed({"theta": [0.4, 0.6]})
    model = pb.PyroModel(prob)
    start = _starts(prob)
    sites = {pb._site(k): torch.as_tensor(np.exp(-0.25 * start[k]) if k in ("betaU", "betaV")
                                          else start[k]) for k in model.free}  # fmt: skip
    prm = model.params(sites)
    got = (model.log_likelihood(prm) + model.log_prior(prm)).numpy()
    np.testing.assert_allclose(got, _numpy_log_post(prob, start), rtol=RTOL)


def test_pyro_names_what_nuts_cannot_sample():
    pb = pytest.importorskip("gpmsa.backends.pyro_backend")
    cat = _problem(None, True).problem
    pb.refuse_unsupported(cat)  # a categorical theta: marginalised (session 74, s74 tests)
    pb.refuse_unsupported(cat.with_fixed({"theta": {1: 0.5}}))  # held at a level: fine
    prep = _problem(_square, True, t_categorical=False)
    with pytest.raises(gpmsa.GPMSAError, match="a callable mean_basis with theta sampled"):
        pb.sample(prep.problem, n_iter=4)
    pb.refuse_unsupported(_constrained(_problem(None, True, t_categorical=False)))  # s75: taken
