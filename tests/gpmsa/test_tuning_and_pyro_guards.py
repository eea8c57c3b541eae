"""Tuned widths stay within the candidates tried; the torch and pyro backends check the draws'
memory before sampling; pyro's chains start dispersed, as the numpy backend's."""

import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa import backends
from gpmsa.mcmc import starts
from gpmsa.mcmc.sampler import Chains
from gpmsa.mcmc.tuning import TARGET, choose_widths, fit_logistic, level_widths


def _road_calibration_problem():
    from _backend_cases import road_problem

    prob = road_problem(True).problem
    fixed = {"betaU": [[0.92], [0.35]], "lamUz": [0.45], "lamWs": [165.0], "lamWOs": [837.0]}
    return prob.with_init(fixed, fixed=frozenset(fixed))


# --- choose_widths: the fit is only informed inside the tested widths -----------------------------
CANDS = level_widths(["betaU"], np.array([0.1]), 20)  # 0.1 * 2^-9.5 .. 0.1 * 10 = 1


@pytest.mark.parametrize(
    ("accepted", "unclamped", "chosen"),
    [
        (np.full(20, 50), 153.0, CANDS[-1, 0]),  # every proposal accepted at every width
        (np.r_[np.full(19, 45), 44], 1.2e239, CANDS[-1, 0]),  # acceptance ~0.9 throughout
        (np.linspace(50, 40, 20).round(), 627.0, CANDS[-1, 0]),  # falls, never near 1/e
        (np.r_[1, np.zeros(19)], 9.8e-5, CANDS[0, 0]),  # below 1/e even at the narrowest
    ],
)
def test_a_saturated_fit_takes_the_widest_or_narrowest_candidate(accepted, unclamped, chosen):
    b = fit_logistic(np.log(CANDS[:, 0]), accepted, 50)
    logit = np.log(TARGET / (1 - TARGET))
    assert np.exp((logit - b[0]) / b[1]) == pytest.approx(unclamped, rel=0.05)  # the old choice
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no overflow warning either
        got = choose_widths(np.array([0.1]), CANDS, accepted[:, None], 50)
    assert got[0] == chosen


def test_a_width_inside_the_candidates_is_the_fit_s_and_a_rising_fit_keeps_the_width():
    b0, b1 = -2.0, -1.3  # acceptance 1/e near width 0.33
    acc = np.round(50 / (1 + np.exp(-(b0 + b1 * np.log(CANDS[:, 0])))))
    b = fit_logistic(np.log(CANDS[:, 0]), acc, 50)
    fitted = np.exp((np.log(TARGET / (1 - TARGET)) - b[0]) / b[1])
    assert CANDS[0, 0] < fitted < CANDS[-1, 0]
    assert choose_widths(np.array([0.1]), CANDS, acc[:, None], 50)[0] == fitted
    # acceptance rising with width keeps the width
    rising = np.round(np.linspace(5, 45, 20))
    assert choose_widths(np.array([0.1]), CANDS, rising[:, None], 50)[0] == 0.1


@pytest.mark.parametrize("name", ["theta", "betaU", "lamUz", "lamWs", "lamWOs"])
@pytest.mark.parametrize("width", [0.1, 5.0, 100.0])
def test_none_or_every_proposal_accepted_gives_the_narrowest_or_widest_whatever_the_widths(
    name, width
):
    """With no acceptance (or every proposal accepted) at every candidate the logistic fit's slope
    was the ridge's, whose sign followed that of the candidates' log widths: a precision (default
    width 5 or 100) that accepted nothing got the narrowest width, a theta or betaU (0.2, 0.1)
    kept its width; every proposal accepted: theta the widest, lamUz kept its width."""
    cands = level_widths([name], np.array([width]), 20)
    none = choose_widths(np.array([width]), cands, np.zeros((20, 1)), 50)
    every = choose_widths(np.array([width]), cands, np.full((20, 1), 50.0), 50)
    assert none[0] == cands[:, 0].min()
    assert every[0] == cands[:, 0].max()


# --- torch and pyro: the draws' memory is checked before any chain runs ---------------------------
@pytest.mark.parametrize(("backend", "runner"), [("torch", "BatchState"), ("pyro", "PyroModel")])
def test_torch_and_pyro_refuse_draws_beyond_the_memory_limit(backend, runner, monkeypatch):
    pytest.importorskip(backend)
    module = backends.get(backend)

    def no_chain(*args, **kwargs):
        raise AssertionError("a chain was set up before the memory check")

    monkeypatch.setattr(module, runner, no_chain)
    monkeypatch.setattr(gpmsa.limits, "MAX_MEMORY_BYTES", 100_000)
    with pytest.raises(
        gpmsa.ResourceLimitError,
        match=r"^sample\(n_iter=1000, n_chains=2\) of 7 parameter elements needs about 256000 "
        r"bytes of memory, above the limit gpmsa.limits.MAX_MEMORY_BYTES = 100000 bytes",
    ):
        module.sample(_road_calibration_problem(), n_iter=1000, n_chains=2, tune=False)


def test_torch_refuses_a_batch_whose_cached_factors_exceed_the_memory_limit(monkeypatch):
    """Each chain of a batch caches its correlations and Sigma_W factors (m x m per component):
    many chains of few draws pass the draws' check but not the memory limit."""
    pytest.importorskip("torch")
    from _backend_cases import road_problem

    module = backends.get("torch")
    problem = road_problem().problem  # m = 198, with observations

    def no_chain(*args, **kwargs):
        raise AssertionError("a chain was set up before the memory check")

    monkeypatch.setattr(module, "BatchState", no_chain)
    monkeypatch.setattr(gpmsa.limits, "MAX_MEMORY_BYTES", 400 * 1024**2)
    why = (
        r"^torch sample\(n_iter=2, n_chains=500\), which caches 1 Sigma_W of 198 x 198 "
        r"\(float64\) per chain, needs about 4\d\d MiB of memory, above the limit"
    )
    with pytest.raises(gpmsa.ResourceLimitError, match=why):
        module.sample(problem, n_iter=2, n_chains=500, tune=False)
    with pytest.raises(AssertionError, match="before the memory check"):  # float32: half
        module.sample(problem, n_iter=2, n_chains=250, tune=False, dtype="float32")


# --- pyro: several chains start dispersed, each where the numpy chain c starts --------------------
def _captured_starts(monkeypatch, **kw) -> tuple[list[dict], Chains]:
    pytest.importorskip("pyro")
    pb = backends.get("pyro")
    seen = []
    real = pb.init_to_value

    def spy(*, values):
        seen.append({k: v.clone() for k, v in values.items()})
        return real(values=values)

    monkeypatch.setattr(pb, "init_to_value", spy)
    chains = pb.sample(_road_calibration_problem(), n_iter=4, n_warmup=4, jit=False, **kw)
    return seen, chains


def test_pyro_chains_start_dispersed_as_the_numpy_chains(monkeypatch):
    pb = pytest.importorskip("gpmsa.backends.pyro_backend")
    prob = _road_calibration_problem()
    seen, chains = _captured_starts(monkeypatch, n_chains=2, seed=4)
    assert len(seen) == 2 and chains.info["init"] == "jitter"
    model = pb.PyroModel(prob)
    for c, s in enumerate(np.random.SeedSequence(4).spawn(2)):
        want = starts.draw_start(prob, "jitter", starts.start_generator(s))
        for name in prob.sampled:
            np.testing.assert_array_equal(chains.info["starts"][name][c], want[name])
        for site, v in model.init_values(want).items():
            np.testing.assert_array_equal(seen[c][site].numpy(), v.numpy())
    assert seen[0]["theta"].item() != seen[1]["theta"].item()
    assert seen[0]["lamOs"].item() != seen[1]["lamOs"].item()


def test_pyro_one_chain_or_init_gpmsa_starts_at_gpmsa_s_initial_values(monkeypatch):
    prob = _road_calibration_problem()
    for kw in ({"n_chains": 1}, {"n_chains": 2, "init": "gpmsa"}):
        seen, chains = _captured_starts(monkeypatch, seed=4, **kw)
        assert chains.info["init"] == "gpmsa"
        for s in seen:
            assert s["theta"].numpy().tolist() == prob.init["theta"].tolist()
            assert s["lamOs"].numpy().tolist() == prob.init["lamOs"].tolist()
    with pytest.raises(gpmsa.GPMSAError, match="init must be one of .*got 'random'"):
        backends.get("pyro").sample(prob, n_iter=4, init="random")
