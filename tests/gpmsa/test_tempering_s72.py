"""Parallel tempering (session 72, ``gpmsa.mcmc.tempering``, ``fit(..., temperatures=)``).

A joint fit of y = 10 (t - 0.5)^2 on a design symmetric about t = 0.5, observed 8 times near
0.9: t = 0.2 and t = 0.8 fit equally well, and the posterior is exactly symmetric under
t -> 1 - t (the design maps onto itself, theta's prior is symmetric), so P(t > 0.5) = 1/2. A
plain fit started at t = 0.2 ends with every draw in one mode (P 0 or 1: the wide widths of
tuning may jump once, then never back); with the ladder (1, 4, 16, 64) each chain visits both
(8 chains x 8,000 sweeps: pooled P within its Monte-Carlo error of 1/2, docs/internals.md).
"""

import warnings

import numpy as np
import pytest
from _level_cases import three_theta_case
from _tempering_cases import two_mode_case as _case

import gpmsa
from gpmsa.errors import GPMSAError, ResourceLimitError
from gpmsa.mcmc import tempering
from gpmsa.mcmc.sampler import ChainState

LADDER = [1.0, 4.0, 16.0, 64.0]


def _fit(n_iter=1500, **kw):
    sim, obs = _case()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        return gpmsa.fit(sim, obs, n_iter=n_iter, n_burn=100, n_keep=n_iter - 100,
                         theta_init=[0.2], tune_rounds=10, **kw)  # fmt: skip


def _upper(emu) -> float:
    return float(np.mean(emu.calibration["theta_native"][:, 0] > 0.5))


def test_plain_fit_stays_in_its_mode():
    assert _upper(_fit(800, seed=1)) == 0.0


def test_tempered_fit_visits_both_modes(tmp_path):
    emu = _fit(seed=1, temperatures=LADDER)
    assert 0.2 < _upper(emu) < 0.8  # 0.37; exactly 1/2 in the limit (symmetry)
    s = emu.settings
    assert s["temperatures"] == LADDER and s["swap_every"] == 1
    rates = np.array(s["swap_rate"])
    assert rates.shape == (1, 3) and np.all((rates > 0.05) & (rates < 1))
    back = gpmsa.load(emu.save(tmp_path / "t.gpmsa"))
    assert back.settings["swap_rate"] == s["swap_rate"]


def test_seeded_and_placement_free():
    sim, obs = _case()
    kw = {"n_iter": 40, "n_chains": 2, "seed": 5, "temperatures": 3, "tune_rounds": 2,
          "tune_levels": 4, "swap_every": 2}  # fmt: skip
    warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)  # (pytest restores the filters)
    a = gpmsa.fit(sim, obs, n_jobs=1, **kw)
    b = gpmsa.fit(sim, obs, n_jobs=2, **kw)
    for k, v in a.draws.items():
        np.testing.assert_array_equal(b.draws[k], v)
    np.testing.assert_array_equal(b.calibration["theta"], a.calibration["theta"])
    assert a.settings["temperatures"] == [1.0, 2.0, 4.0] and a.settings["swap_every"] == 2
    more = gpmsa.fit(
        sim, obs, n_iter=10, n_chains=2, seed=6, init=a, n_jobs=1, temperatures=None
    )  # untempered (by default tempered: s74)
    assert more.settings["continued_from"] == a.model_sha256 and "temperatures" not in more.settings
    plain = gpmsa.fit(sim, obs, n_jobs=1, **{**kw, "temperatures": None, "swap_every": 1})
    assert "temperatures" not in plain.settings
    assert not np.array_equal(plain.calibration["theta"], a.calibration["theta"])


def test_swap_is_exact_between_two_states():
    """A swap exchanges the states with probability min(1, e^((b0 - b1)(l1 - l0)))."""
    sim, obs = _case()
    from gpmsa.model.problem import prepare

    problem = prepare(sim, obs).problem
    rng = np.random.default_rng(0)
    lo = {**problem.init, "theta": np.array([0.5])}  # far from the data: low likelihood
    a = ChainState(problem, {**problem.init, "theta": np.array([0.2])}, rng)
    b = ChainState(problem, lo, rng)
    b.beta = 0.25
    la, lb = a.lik.loglik, b.lik.loglik
    assert lb < la
    log_r = (1.0 - 0.25) * (lb - la)
    acc = np.zeros(1)
    tempering.swap([a, b], (1.0, 0.25), np.array([np.exp(log_r) * 1.01]), acc)
    assert acc[0] == 0 and a.lik.loglik == la
    tempering.swap([a, b], (1.0, 0.25), np.array([np.exp(log_r) * 0.99]), acc)
    assert acc[0] == 1 and a.lik.loglik == lb and b.lik.loglik == la
    assert a.params["theta"][0] == 0.5 and a.beta == 1.0 and b.beta == 0.25


@pytest.mark.parametrize(
    ("value", "words"),
    [(0, "temperatures"), (True, "temperatures"), ([2.0, 4.0], "start at exactly 1"),
     ([1.0, 1.0], "increase strictly"), ([1.0, np.inf], "finite"), ("hot", "temperatures"),
     ([[1.0, 2.0]], "flat sequence"), (list(range(1, 40)), "2 to 32")],
)  # fmt: skip
def test_ladder_refused(value, words):
    with pytest.raises(GPMSAError, match=words):
        tempering.ladder(value)


def test_ladder_and_swap_every():
    assert tempering.ladder(None) is None
    assert tempering.ladder(np.int64(3)) == (1.0, 2.0, 4.0)
    assert tempering.ladder((1, 3.5)) == (1.0, 3.5)
    with pytest.raises(GPMSAError, match="swap_every=3 needs temperatures"):
        tempering.check_swap_every(3, None)
    with pytest.raises(GPMSAError, match="swap_every"):
        tempering.check_swap_every(0, (1.0, 2.0))


def test_refused_by_name_elsewhere():
    sim, obs = _case()
    with pytest.raises(GPMSAError, match="temperatures: parallel tempering runs on the numpy"):
        gpmsa.fit(sim, obs, n_iter=10, backend="pyro", temperatures=2)  # (torch: s73)
    with pytest.raises(GPMSAError, match="swap_every: parallel tempering runs on the numpy"):
        gpmsa.fit(sim, obs, n_iter=10, backend="pyro", swap_every=2)
    emu = gpmsa.fit(sim, obs, n_iter=10, seed=0, tune=False)
    with pytest.raises(GPMSAError, match="tune=False with a tempered continuation"):
        gpmsa.fit(sim, obs, n_iter=10, init=emu, temperatures=2, append=True, tune=False)


def test_memory_counts_every_copy(monkeypatch):
    from gpmsa.fitting import fit as fit_module

    sim, obs = _case()
    from gpmsa.model.problem import prepare

    problem = prepare(sim, obs).problem
    seen = []
    monkeypatch.setattr(fit_module, "check_memory", lambda n, what: seen.append((n, what)))
    fit_module._check_fit_memory(problem, 100, 2)
    fit_module._check_fit_memory(problem, 100, 2, copies=4)
    factors = fit_module._factor_nbytes(problem.m, problem.p, problem.q, problem.p_u)
    assert seen[1][0] - seen[0][0] == pytest.approx(3 * factors)
    assert "at 4 temperatures" in seen[1][1]
    monkeypatch.undo()
    monkeypatch.setattr(gpmsa.limits, "MAX_MEMORY_BYTES", (seen[0][0] + seen[1][0]) / 2)
    with pytest.raises(ResourceLimitError, match="at 4 temperatures"):
        gpmsa.fit(sim, obs, n_iter=100, n_chains=2, temperatures=4)


def test_constraint_fixed_and_categorical_respected():
    sim, obs = three_theta_case(np.random.default_rng(2))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = gpmsa.fit(sim, obs, n_iter=60, seed=0, temperatures=3, tune_rounds=2,
                        tune_levels=4, constraint=lambda th: th[0] + th[1] < 1.2,
                        fixed={"betaU": {(1, 0): 0.5}}, theta_init=[0.3, 0.3, 1])  # fmt: skip
    th = emu.calibration["theta_native"]
    assert np.all(th[:, 0] + th[:, 1] < 1.2)
    assert set(np.unique(th[:, 2])) <= {0.0, 1.0}
    assert np.all(emu.draws["betaU"][:, 1, 0] == 0.5)


def test_separable_design_as_dense():
    rng = np.random.default_rng(0)
    xs, ts = np.linspace(0.0, 1.0, 5), rng.random((6, 2))
    x, t = np.repeat(xs, 6)[:, None], np.tile(ts, (5, 1))
    y = np.sin(3 * x) * np.linspace(1.0, 2.0, 3) + t[:, :1] ** 2 + 0.3 * t[:, 1:]
    kw = {"n_iter": 20, "seed": 3, "tune_rounds": 2, "tune_levels": 3, "temperatures": 3}
    dense = gpmsa.fit(gpmsa.SimData(x=x, t=t, y=y), **kw)
    kron = gpmsa.fit(gpmsa.SimData(x=x, t=t, y=y, separable=[[0], [1, 2]]), **kw)
    for k, v in dense.draws.items():
        np.testing.assert_allclose(kron.draws[k], v, rtol=1e-9, atol=0)
    np.testing.assert_allclose(kron.settings["swap_rate"], dense.settings["swap_rate"])
