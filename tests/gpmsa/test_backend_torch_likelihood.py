"""The batched torch GPM/SA log-likelihood against a direct dense numpy formula."""

import functools

import numpy as np
import pytest

torch = pytest.importorskip("torch")
tb = pytest.importorskip("gpmsa.backends.torch_backend")


@pytest.fixture(autouse=True)
def _one_thread():
    """Single-threaded torch, as the backend samples (thread pools stall on a busy machine)."""
    with tb.torch_threads(1):
        yield


def _kernel(a: np.ndarray, b: np.ndarray, beta: np.ndarray) -> np.ndarray:
    """exp(-sum_k beta_k (a_k - b_k)^2) by explicit loops."""
    out = np.empty((len(a), len(b)))
    for i in range(len(a)):
        for j in range(len(b)):
            out[i, j] = np.exp(-np.sum(beta * (a[i] - b[j]) ** 2))
    return out


def _dense_loglik(case: dict, prm: dict, with_obs: bool) -> float:
    """log N(z; 0, Sigma) without constants, z = [v; u; w] with the joint GPM/SA covariance."""
    x_sim, t_sim, w, lam_sim = case["x_sim"], case["t_sim"], case["w"], case["lam_sim"]
    m, p_u = w.shape
    xt_sim = np.hstack([x_sim, t_sim])
    blocks_w = []
    for j in range(p_u):
        nug = 1 / (lam_sim[j] * prm["lamWOs"][0]) + 1 / prm["lamWs"][j]
        blocks_w.append(
            _kernel(xt_sim, xt_sim, prm["betaU"][:, j]) / prm["lamUz"][j] + nug * np.eye(m)
        )
    if not with_obs:
        sig = np.zeros((m * p_u, m * p_u))
        for j, blk in enumerate(blocks_w):
            sig[j * m : (j + 1) * m, j * m : (j + 1) * m] = blk
        z = w.T.ravel()
    else:
        x_obs = case["x_obs"]
        n = len(x_obs)
        xt_obs = np.hstack([x_obs, np.tile(prm["theta"], (n, 1))])
        p_v = case["p_v"]
        nv, nu = n * p_v, n * p_u
        size = nv + nu + m * p_u
        sig = np.zeros((size, size))
        for k in range(p_v):
            sl = slice(k * n, (k + 1) * n)
            sig[sl, sl] = _kernel(x_obs, x_obs, prm["betaV"][:, 0]) / prm["lamVz"][0]
        for j in range(p_u):
            su = slice(nv + j * n, nv + (j + 1) * n)
            sw = slice(nv + nu + j * m, nv + nu + (j + 1) * m)
            beta = prm["betaU"][:, j]
            sig[su, su] = (
                _kernel(xt_obs, xt_obs, beta) / prm["lamUz"][j] + np.eye(n) / prm["lamWs"][j]
            )
            sig[su, sw] = _kernel(xt_obs, xt_sim, beta) / prm["lamUz"][j]
            sig[sw, su] = sig[su, sw].T
            sig[sw, sw] = blocks_w[j]
        sig[: nv + nu, : nv + nu] += case["sigma_obs"] / prm["lamOs"][0]
        z = np.concatenate([case["vu"], w.T.ravel()])
    sign, logdet = np.linalg.slogdet(sig)
    assert sign > 0
    return -0.5 * logdet - 0.5 * z @ np.linalg.solve(sig, z)


def _random_case(rng: np.random.Generator, p: int, q: int, p_u: int, n: int, p_v: int):
    m = 9
    case = {
        "x_sim": rng.random((m, p)),
        "t_sim": rng.random((m, q)),
        "w": rng.normal(size=(m, p_u)),
        "lam_sim": rng.uniform(0.5, 3, p_u),
        "x_obs": rng.random((n, p)),
        "p_v": p_v,
    }
    n_vu = n * (p_v + p_u)
    a = rng.normal(size=(n_vu, n_vu))
    case["sigma_obs"] = a @ a.T / n_vu + 0.1 * np.eye(n_vu)
    case["vu"] = rng.normal(size=n_vu)
    return case


def _random_params(rng: np.random.Generator, p: int, q: int, p_u: int) -> dict:
    return {
        "theta": rng.random(q),
        "betaU": rng.uniform(0.1, 3, (p + q, p_u)),
        "lamUz": rng.uniform(0.5, 3, p_u),
        "lamWs": rng.uniform(100, 1000, p_u),
        "lamWOs": rng.uniform(100, 1000, 1),
        "betaV": rng.uniform(0.1, 3, (p, 1)),
        "lamVz": rng.uniform(1, 30, 1),
        "lamOs": rng.uniform(1, 50, 1),
    }


def _tensors(case: dict, with_obs: bool) -> "tb.ModelTensors":
    t = lambda a: torch.as_tensor(np.asarray(a), dtype=torch.float64)  # noqa: E731
    xt = np.hstack([case["x_sim"], case["t_sim"]])
    obs = {}
    if with_obs:
        obs = {
            "d_obs": t(tb.pairwise_sq(case["x_obs"], case["x_obs"])),
            "d_cross": t(tb.pairwise_sq(case["x_obs"], case["x_sim"])),
            "z": t(case["vu"]),
            "sig_obs": t(case["sigma_obs"]),
            "u_blocks": tuple(case["p_v"] + j for j in range(case["w"].shape[1])),
            "v_blocks": tuple(range(case["p_v"])),
        }
    return tb.ModelTensors(
        p=case["x_sim"].shape[1],
        q=case["t_sim"].shape[1],
        d_sim=t(tb.pairwise_sq(xt, xt)),
        t_sim=t(case["t_sim"]),
        w=t(case["w"].T),
        lam_sim=t(case["lam_sim"]),
        **obs,
    )


@pytest.mark.parametrize(
    ("p", "q", "p_u", "n", "p_v"),
    [(1, 1, 1, 1, 0), (1, 2, 2, 3, 2), (2, 1, 3, 2, 1), (1, 1, 2, 4, 0)],
)
@pytest.mark.parametrize("with_obs", [False, True])
def test_batched_loglik_matches_dense_formula(p, q, p_u, n, p_v, with_obs):
    rng = np.random.default_rng(p * 100 + q * 10 + p_u + n)
    case = _random_case(rng, p, q, p_u, n, p_v)
    chains = [_random_params(rng, p, q, p_u) for _ in range(5)]
    data = _tensors(case, with_obs)
    stacked = {k: torch.as_tensor(np.stack([c[k] for c in chains])) for k in chains[0]}
    chol, alpha, ll_w = tb.sim_factor(
        data.d_sim, data.w, data.lam_sim, *(stacked[k] for k in tb.SIM_PARAMS)
    )
    got = ll_w.sum(-1)
    if with_obs:
        got = got + tb.obs_loglik(data, chol, alpha, stacked)
    want = [_dense_loglik(case, c, with_obs) for c in chains]
    np.testing.assert_allclose(got.numpy(), want, rtol=1e-9, atol=1e-8)


def test_not_positive_definite_gives_minus_inf():
    rng = np.random.default_rng(3)
    case = _random_case(rng, 1, 1, 1, 1, 0)
    case["x_sim"][1] = case["x_sim"][0]
    case["t_sim"][1] = case["t_sim"][0]
    data = _tensors(case, False)
    ones = torch.ones(1, 1, dtype=torch.float64)
    beta = torch.full((1, 2, 1), 1e-3, dtype=torch.float64)
    _, _, ll = tb.sim_factor(data.d_sim, data.w, data.lam_sim, beta, ones, ones * 1e30, ones * 1e30)
    assert torch.isneginf(ll).all()


@functools.cache
def _cases():
    from _backend_cases import multi_problem, road_problem

    return {
        "road-sim": road_problem(False).problem,
        "road-joint": road_problem(True).problem,
        "multi": multi_problem().problem,
        "multi-discrepancy": multi_problem("constant").problem,
    }


def _perturbed(problem, n_chains: int, rng: np.random.Generator) -> dict:
    """Random points near the initial values, name -> (n_chains, *shape) tensors."""
    out = {}
    for name, val in problem.init.items():
        v = val * rng.uniform(0.6, 1.4, (n_chains, *val.shape))
        out[name] = torch.as_tensor(np.clip(v, 0.01, 0.99) if name == "theta" else v)
    return out


def _numpy_log_post(problem, params: dict, c: int) -> float:
    from gpmsa.model.likelihood import log_posterior

    return log_posterior(problem, {k: v[c].numpy() for k, v in params.items()})


@pytest.mark.parametrize("case", ["road-sim", "road-joint", "multi", "multi-discrepancy"])
def test_log_posterior_matches_numpy_reference(case):
    problem = _cases()[case]
    state = tb.BatchState(problem, 4, torch.float64, "cpu")
    params = _perturbed(problem, 4, np.random.default_rng(7))
    state.reset(params)
    want = [_numpy_log_post(problem, params, c) for c in range(4)]
    assert np.all(np.isfinite(want))
    np.testing.assert_allclose(state.log_post().numpy(), want, rtol=1e-9, atol=1e-7)


@pytest.mark.parametrize("case", ["road-joint", "multi-discrepancy"])
def test_cached_state_after_sweeps_equals_fresh_evaluation(case):
    problem = _cases()[case]
    state = tb.BatchState(problem, 3, torch.float64, "cpu")
    gen = torch.Generator().manual_seed(0)
    widths = np.array([0.1] * len(state.els))
    accepted = sum(state.sweep(widths, True, gen).sum() for _ in range(15))
    assert accepted > 0
    cached = state.log_post().numpy()
    want = [_numpy_log_post(problem, state.params, c) for c in range(3)]
    np.testing.assert_allclose(cached, want, rtol=1e-9, atol=1e-7)


def test_correlation_is_gpytorch_ard_rbf_kernel():
    """R(beta) equals GPyTorch's ARD RBFKernel with lengthscale l_k = 1/sqrt(2 beta_k)."""
    gpytorch = pytest.importorskip("gpytorch")
    rng = np.random.default_rng(4)
    x = rng.random((30, 3))
    beta = torch.as_tensor(rng.uniform(0.1, 5.0, (4, 3, 1)))
    lam = torch.as_tensor(rng.uniform(0.5, 2.0, (4, 1)))
    kernel = gpytorch.kernels.RBFKernel(ard_num_dims=3, batch_shape=torch.Size([4])).double()
    kernel.lengthscale = (1.0 / torch.sqrt(2.0 * beta)).transpose(1, 2)
    xt = torch.as_tensor(x)
    with torch.no_grad():
        want = kernel(xt, xt).to_dense() / lam[:, :, None]
        got = tb.scaled_correlation(beta, torch.as_tensor(tb.pairwise_sq(x, x)), lam)[:, 0]
    np.testing.assert_allclose(got.numpy(), want.numpy(), rtol=1e-10, atol=1e-12)
