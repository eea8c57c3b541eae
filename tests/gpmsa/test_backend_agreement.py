"""Each backend's posterior agrees with the numpy backend's within Monte-Carlo error.

Tolerances come from the draws themselves: a mean differs by at most Z standard errors
sd * sqrt(1/ESS_a + 1/ESS_b), an sd by at most Z standard errors sd * sqrt((kurtosis - 1)/(4 ESS))
combined over both runs, ESS from arviz (bulk, rank-normalised).
"""

import numpy as np
import pytest

from gpmsa import backends
from gpmsa.mcmc.diagnostics import ess, rhat
from tests._extras import PYRO, TORCH, backend_param

Z = 4.0


def _moments(x: np.ndarray) -> tuple[float, float, float, float]:
    """mean, sd, standard error of the mean, standard error of the sd of draws x (chains, n)."""
    flat = x.reshape(-1)
    mean, sd = flat.mean(), flat.std(ddof=1)
    n_eff = ess(x)
    kurt = np.mean((flat - mean) ** 4) / sd**4
    return mean, sd, sd / np.sqrt(n_eff), sd * np.sqrt(max(kurt - 1.0, 0.5) / (4.0 * n_eff))


def assert_agree(a: np.ndarray, b: np.ndarray, what: str, sd_too: bool = True) -> None:
    """Means (and sds) of draws a and b (chains, n) equal within Z Monte-Carlo standard errors."""
    ma, sa, sem_a, ses_a = _moments(a)
    mb, sb, sem_b, ses_b = _moments(b)
    tol_m = Z * np.hypot(sem_a, sem_b)
    assert abs(ma - mb) <= tol_m, f"{what}: mean {ma:.5g} vs {mb:.5g}, tolerance {tol_m:.3g}"
    if sd_too:
        tol_s = Z * np.hypot(ses_a, ses_b)
        assert abs(sa - sb) <= tol_s, f"{what}: sd {sa:.5g} vs {sb:.5g}, tolerance {tol_s:.3g}"


def _elements(chains, name: str, frac: float = 0.2) -> list[np.ndarray]:
    d = chains.draws[name]
    d = d[:, int(frac * d.shape[1]) :]
    flat = d.reshape(d.shape[0], d.shape[1], -1)
    return [flat[:, :, i] for i in range(flat.shape[2])]


@pytest.fixture(scope="module")
def calibration_problem():
    from _backend_cases import road_problem

    prob = road_problem(True).problem
    fixed = {"betaU": [[0.924], [0.354]], "lamUz": [0.453], "lamWs": [164.6], "lamWOs": [837.1]}
    return prob.with_init(fixed, fixed=frozenset(fixed))


@pytest.fixture(scope="module")
def numpy_calibration(calibration_problem):
    return backends.get("numpy").sample(calibration_problem, n_iter=5000, seed=1)


@pytest.mark.parametrize(
    ("backend", "options"),
    [
        backend_param("torch", {"n_iter": 300, "n_chains": 8}),
        backend_param("pyro", {"n_iter": 150, "n_warmup": 100}),
    ],
)
def test_road_calibration_agrees_with_numpy(
    calibration_problem, numpy_calibration, backend, options
):
    chains = backends.get(backend).sample(calibration_problem, seed=2, **options)
    for name in ("theta", "lamOs"):
        (a,) = _elements(chains, name)
        (b,) = _elements(numpy_calibration, name)
        assert_agree(a, b, f"{backend} {name}", sd_too=name == "theta")


@pytest.fixture(scope="module")
def multi_sim_problem():
    from _backend_cases import multi_data

    from gpmsa.model.problem import prepare

    sim, _ = multi_data()
    return prepare(sim).problem


@TORCH
def test_multivariate_emulator_posterior_agrees_with_numpy(multi_sim_problem):
    prob = multi_sim_problem
    assert prob.p_u >= 2
    ref = backends.get("numpy").sample(prob, n_iter=4000, seed=3)
    # warm-up 30 sweeps a stage (default 100), 4 tuning rounds (default ceil(50 / 8) = 7): 4 s,
    # not 7 s. Over seeds 4-11 the largest of the 18 mean and sd differences was 3.0 standard
    # errors (at the defaults, seeds 4-9: 3.1); a lamUz prior rate 20 % off (4, not 5) failed
    # 6 of 9 seeds (the defaults: 5 of 9)
    got = backends.get("torch").sample(prob, n_iter=400, n_chains=8, warmup=30, tune_rounds=4,
                                       seed=4)  # fmt: skip
    for name in ("betaU", "lamUz", "lamWs", "lamWOs"):
        for k, (a, b) in enumerate(zip(_elements(got, name), _elements(ref, name), strict=True)):
            assert_agree(a, b, f"torch {name}[{k}]")


@pytest.fixture(scope="module")
def numpy_joint():
    from _backend_cases import road_problem

    prob = road_problem(True).problem
    return prob, backends.get("numpy").sample(prob, n_iter=15_000, n_chains=2, seed=5)


def _identified(chains) -> dict[str, np.ndarray]:
    """Draws (chains, kept) of the joint model's identified quantities.

    For a scalar output lamWs and lamWOs enter the likelihood only through the nugget
    1/lamWs + 1/(LamSim lamWOs) (LamSim = 1), so each alone mixes slowly in every Metropolis
    sampler (numpy included: ESS ~ 40 in 2 x 8,000 sweeps); their sum is compared instead.
    """
    out = {"theta": _elements(chains, "theta")[0], "lamUz": _elements(chains, "lamUz")[0]}
    out["lamOs"] = _elements(chains, "lamOs")[0]
    for k, b in enumerate(_elements(chains, "betaU")):
        out[f"betaU[{k}]"] = b
    (ws,), (wos,) = _elements(chains, "lamWs"), _elements(chains, "lamWOs")
    out["nugget"] = 1.0 / ws + 1.0 / wos
    return out


@pytest.mark.slow
@pytest.mark.parametrize(
    ("backend", "options", "max_rhat"),
    [
        # 16 x 2,500 sweeps put theta's R-hat at 1.006-1.019 by seed (7, 8, 6): the bound
        # judged the seed; at 5,000 seed 6 gives 1.008
        backend_param("torch", {"n_iter": 5000, "n_chains": 16}, 1.01),
        backend_param("pyro", {"n_iter": 400, "n_chains": 2, "n_warmup": 200}, 1.05),
    ],
)
def test_road_joint_fit_agrees_with_numpy(numpy_joint, backend, options, max_rhat):
    """The full GPM/SA joint posterior (emulator + theta + lamOs) on the road case."""
    prob, ref = numpy_joint
    got = _identified(backends.get(backend).sample(prob, seed=6, **options))
    want = _identified(ref)
    for name, a in got.items():
        assert rhat(a) < max_rhat, f"{backend} {name} R-hat {rhat(a):.3f}"
        assert_agree(a, want[name], f"{backend} {name}", sd_too=name == "theta")


@pytest.mark.slow
@PYRO
def test_multivariate_pyro_agrees_with_numpy(multi_sim_problem):
    prob = multi_sim_problem
    ref = backends.get("numpy").sample(prob, n_iter=10_000, seed=7)
    got = backends.get("pyro").sample(prob, n_iter=500, n_chains=2, n_warmup=300, seed=8)
    for name in ("betaU", "lamUz", "lamWs", "lamWOs"):
        for k, (a, b) in enumerate(zip(_elements(got, name), _elements(ref, name), strict=True)):
            assert_agree(a, b, f"pyro {name}[{k}]", sd_too=False)
