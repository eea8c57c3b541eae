"""Parallel tempering on the torch backend (session 73: ``fit``/``calibrate(..., backend="torch",
temperatures=, swap_every=)``; ``torch_backend._tempered_tuning`` and ``_tempered_draws``
(one ``_tempered_sweeps`` before session 74), ``_swap_rows``, ``BatchState.exchange``).

The batch holds n_chains x K rows (chain c's copy k at row c K + k), each row's likelihood
tempered by its 1/T_k; neighbours swap rows' states with the exact acceptance; only the T = 1
rows' draws are kept. Cases: the symmetric two-mode joint fit of test_tempering_s72 (P(t >
0.5) = 1/2 exactly) and a calibration with unequal modes (y = 10 (t - 0.5)^2 + 6 (t - 0.5)^3
observed near 0.9, lamOs held: P(t > 0.5) = 0.402 on an exact grid), where plain torch chains
each stay in one mode.
"""

import warnings

import numpy as np
import pytest
from _level_cases import three_theta_case
from _tempering_cases import two_mode_case as _sym_case

import gpmsa
from gpmsa.errors import GPMSAError, ResourceLimitError
from gpmsa.model.problem import prepare

torch = pytest.importorskip("torch")
tb = pytest.importorskip("gpmsa.backends.torch_backend")

LADDER = [1.0, 4.0, 16.0, 64.0]
SD = 0.15
Y = 0.9 + SD * np.array([[0.3], [-0.5], [0.8], [-0.2]])


def _f(t):
    return 10 * (t - 0.5) ** 2 + 6 * (t - 0.5) ** 3


def _emulator():
    t = np.linspace(0.0, 1.0, 25)[:, None]
    prm = {"betaU": [[0.5]], "lamUz": [1.0], "lamWs": [1e6], "lamWOs": [1e6]}
    return gpmsa.Emulator.from_params(gpmsa.SimData(t=t, y=_f(t), t_names=["t"]), prm)


def _calibrate(**kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # unconverged plain chains
        return gpmsa.calibrate(_emulator(), gpmsa.ObsData(y=Y, precision=SD**-2),
                               backend="torch", fixed={"lamOs": 1.0},
                               **{"tune_rounds": 5, **kw})  # fmt: skip


def _grid_upper() -> float:
    e = np.linspace(0.0, 1.0, 200_001)
    lp = -0.5 * ((Y - _f(e)) ** 2).sum(0) / SD**2 - 0.5 * ((e - 0.5) / 10) ** 2
    w = np.exp(lp - lp.max())
    return float(w[e > 0.5].sum() / w.sum())


def _fit(**kw):
    sim, obs = _sym_case()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        return gpmsa.fit(sim, obs, backend="torch", theta_init=[0.2], **kw)


def test_plain_torch_chains_stick_in_their_modes():
    post = _calibrate(n_samples=400, n_burn=50, n_chains=2, seed=3)
    assert set((post.chains["t"] > 0.5).mean(1).tolist()) == {0.0, 1.0}


def test_tempered_calibrate_weighs_unequal_modes_as_the_grid():
    post = _calibrate(n_samples=1000, n_burn=100, n_chains=4, seed=3, temperatures=LADDER)
    up = (post.chains["t"] > 0.5).mean(1)
    assert np.all((up > 0.15) & (up < 0.75)), up  # each chain visits both modes
    # pooled 0.376 here; 3 seeds of 8 chains x 5,000: 0.384-0.412, the grid 0.402
    assert abs(up.mean() - _grid_upper()) < 0.1, (up.mean(), _grid_upper())
    info = post.info
    assert info["temperatures"] == LADDER and info["swap_every"] == 1
    rates = np.array(info["swap_rate"])
    assert rates.shape == (4, 3) and np.all((rates > 0.3) & (rates < 0.9))


def test_tempered_fit_visits_both_symmetric_modes():
    # (plain torch chains of this fit stay in their modes: 4 chains x 800 sweeps, per-chain
    # P(t > 0.5) 1, 1, 1, 0)
    emu = _fit(n_iter=400, n_burn=50, n_keep=700, n_chains=2, seed=1, tune_rounds=3,
               tune_levels=5, tune_stages=1, warmup=10, temperatures=LADDER,
               swap_every=2)  # fmt: skip
    up = (emu.calibration["theta_native"][:, 0] > 0.5).reshape(2, -1).mean(1)
    assert np.all((up > 0.02) & (up < 0.98)), up  # each chain visits both modes (0.96, 0.21)
    assert 0.25 < up.mean() < 0.75  # 1/2 in the limit (symmetry)
    s = emu.settings
    assert s["temperatures"] == LADDER and s["swap_every"] == 2 and s["backend"] == "torch"
    rates = np.array(s["swap_rate"])
    assert rates.shape == (2, 3) and np.all((rates > 0.05) & (rates < 1))


def test_seeded_and_plain_untouched():
    kw = {"n_samples": 30, "n_burn": 5, "n_chains": 2, "seed": 5, "tune_rounds": 2,
          "tune_levels": 4}  # fmt: skip
    a = _calibrate(temperatures=3, swap_every=2, **kw)
    b = _calibrate(temperatures=3, swap_every=2, **kw)
    np.testing.assert_array_equal(a.chains["t"], b.chains["t"])
    assert a.info["temperatures"] == [1.0, 2.0, 4.0] and a.info["swap_every"] == 2
    assert np.array(a.info["swap_rate"]).shape == (2, 2)
    plain = _calibrate(**kw)
    none = _calibrate(temperatures=None, **kw)
    np.testing.assert_array_equal(plain.chains["t"], none.chains["t"])
    assert not {"temperatures", "swap_every", "swap_rate"} & set(plain.info)


def _two_rows():
    """A batch of one chain's two copies (T = 1, 4) at t = 0.2 (a mode) and 0.5 (between)."""
    sim, obs = _sym_case()
    problem = prepare(sim, obs).problem
    start = {k: np.stack([v, v]) for k, v in problem.init.items()}
    start["theta"] = np.array([[0.2], [0.5]])
    state = tb.BatchState(problem, 2, torch.float64, "cpu", start)
    state.beta = torch.tensor([1.0, 0.25], dtype=torch.float64)
    return problem, start, state


def test_swap_is_exact_and_keeps_each_row_consistent():
    problem, start, state = _two_rows()
    la, lb = state.loglik.tolist()
    assert lb < la
    r = np.exp((1.0 - 0.25) * (lb - la))
    acc = torch.zeros((1, 1), dtype=torch.long)
    tb._swap_rows(state, (1.0, 0.25), torch.tensor([[r * 1.01]], dtype=torch.float64), acc)
    assert acc.item() == 0 and state.loglik.tolist() == [la, lb]
    tb._swap_rows(state, (1.0, 0.25), torch.tensor([[r * 0.99]], dtype=torch.float64), acc)
    assert acc.item() == 1 and state.loglik.tolist() == [lb, la]
    assert state.params["theta"][:, 0].tolist() == [0.5, 0.2]
    fresh = tb.BatchState(problem, 2, torch.float64, "cpu",
                          {**start, "theta": np.array([[0.5], [0.2]])})  # fmt: skip
    for name in ("ll_w", "ll_obs", "alpha", "corr"):  # (ll_obs: to rounding)
        torch.testing.assert_close(getattr(state, name), getattr(fresh, name), rtol=1e-12, atol=0)
    torch.testing.assert_close(state.chol.tril(), fresh.chol.tril())  # (the factor's triangle)
    assert state.beta.tolist() == [1.0, 0.25]  # the temperatures stay with the rows


def test_categorical_and_constraint_with_copies():
    sim, obs = three_theta_case(np.random.default_rng(2))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = gpmsa.fit(sim, obs, n_iter=30, n_chains=2, seed=0, backend="torch",
                        temperatures=3, tune_rounds=2, tune_levels=3, tune_stages=1, warmup=2,
                        constraint=lambda th: th[0] + th[1] < 1.2,
                        theta_init=[0.3, 0.3, 1])  # fmt: skip
    th = emu.calibration["theta_native"]
    assert np.all(th[:, 0] + th[:, 1] < 1.2)
    assert set(np.unique(th[:, 2])) <= {0.0, 1.0}
    modes = emu.settings["level_offsets"]["kind"]["modes"]
    assert np.array(modes).shape[0] == 2  # per chain (the T = 1 row's), not per copy


def test_refused_by_name():
    sim, obs = _sym_case()
    # (chain_groups > 1 with temperatures: taken since session 74, test_torch_tempering_groups_s74)
    with pytest.raises(GPMSAError, match="swap_every=20 exceeds n_iter=10"):
        gpmsa.fit(sim, obs, n_iter=10, backend="torch", temperatures=2, swap_every=20)
    with pytest.raises(GPMSAError, match="swap_every=3 needs temperatures"):
        gpmsa.fit(sim, obs, n_iter=10, backend="torch", swap_every=3)
    with pytest.raises(GPMSAError, match="start at exactly 1"):
        _calibrate(n_samples=10, n_burn=1, temperatures=[2.0, 4.0])
    with pytest.raises(GPMSAError, match="swap_every: parallel tempering runs on the numpy and"):
        gpmsa.fit(sim, obs, n_iter=10, backend="pyro", swap_every=2)


def test_memory_counts_every_copy(monkeypatch):
    sim, obs = _sym_case()
    problem = prepare(sim, obs).problem
    seen = []
    monkeypatch.setattr(tb, "check_memory", lambda n, what: seen.append((n, what)))
    tb.check_batch_memory(problem, 100, 2, torch.float64)
    tb.check_batch_memory(problem, 100, 2, torch.float64, copies=4)
    plain, hot = seen
    assert "temperatures" not in plain[1] and "at 4 temperatures" in hot[1]
    draws = gpmsa.mcmc.sampler.draws_nbytes(problem, 100, 2)
    assert hot[0] - draws == pytest.approx(4 * (plain[0] - draws))
    monkeypatch.undo()
    monkeypatch.setattr(gpmsa.limits, "MAX_MEMORY_BYTES", (plain[0] + hot[0]) / 2)
    with pytest.raises(ResourceLimitError, match="at 4 temperatures"):
        gpmsa.fit(sim, obs, n_iter=100, n_chains=2, backend="torch", temperatures=4)
