"""The adaptive ladder on the torch backend (session 74: ``adapt_ladder=True`` with
``temperatures``; ``torch_backend._adapt_ladders``, the numpy backend's rule
``tempering.adapt_gaps``).

After the first stage's warm-up each chain's interior temperatures move towards equal swap
rates from its own swaps (its rows c K + k at its own ladder), then the ladder is frozen for
the widths' tuning and the draws, and chain groups receive their chains' ladders. The case: the
symmetric two-mode joint fit of test_tempering_s72, whose ladder (1, 4, 16, 64) swaps
unevenly (rates about 0.15, 0.33, 0.45; numpy's adapted ladder about (1, 2.3, 9.2, 64),
docs/internals.md "Adaptive ladder").
"""

import warnings

import numpy as np
import pytest
from _tempering_cases import two_mode_case as _sym_case
from tqdm.auto import tqdm

import gpmsa
from gpmsa import backends
from gpmsa.errors import GPMSAError
from gpmsa.mcmc import tempering

torch = pytest.importorskip("torch")
tb = backends.get("torch")

LADDER = [1.0, 4.0, 16.0, 64.0]
KW = {"n_iter": 10, "n_chains": 4, "seed": 5, "warmup": 5, "tune_stages": 1, "tune_rounds": 8,
      "tune_levels": 5, "temperatures": LADDER}  # fmt: skip


def _problem():
    return gpmsa.prepare(*_sym_case()).problem


def _is_ladder(ad, n_chains, start):
    assert ad.shape == (n_chains, len(start))
    assert np.all(ad[:, 0] == 1.0) and np.all(ad[:, -1] == start[-1])
    assert np.all(np.diff(ad, axis=1) > 0) and not np.any(np.all(ad == start, axis=1))


class _GaussRows:
    """A tempered batch (rows c K + k) whose sweep draws each row's x ~ N(0, I / beta) exactly,
    log L = -|x|^2 / 2: scale-free energies, so the geometric ladder swaps evenly (as the numpy
    test's copies, test_adaptive_ladder_s73)."""

    def __init__(self, n_rows, d=4, seed=0):
        self.gen = torch.Generator().manual_seed(seed)
        self.x = torch.randn((n_rows, d), generator=self.gen, dtype=torch.float64)
        self.n_chains, self.els, self.beta = n_rows, [("theta", (0,))], None
        self.ll_w = self.x[:, :1]  # (the batch's dtype and device)

    @property
    def loglik(self):
        return -0.5 * (self.x**2).sum(-1)

    def sweep(self, widths, prop_mh, gen):
        noise = torch.randn(self.x.shape, generator=self.gen, dtype=torch.float64)
        self.x = noise / self.beta.sqrt()[:, None]

    def exchange(self, a, b):
        self.x[a], self.x[b] = self.x[b], self.x[a]


def _rates(state, temps, n_rounds=400):
    """Each pair's swap rate (K - 1,) over the chains at the ladders ``temps`` (K,) or (C, K)."""
    n_temps = np.shape(temps)[-1]
    betas = tb._temper(state, temps)
    swaps = torch.zeros((n_temps - 1, state.n_chains // n_temps), dtype=torch.long)
    gen = torch.Generator().manual_seed(1)
    for _ in range(n_rounds):
        state.sweep(None, False, gen)
        tb._swap_round(state, betas, gen, swaps)
    return swaps.numpy().mean(1) / n_rounds


def test_bad_ladder_adapted_per_chain_towards_equal_swap_rates():
    """(1, 1.5, 2, 64): swap rates 0.73, 0.80, 0.01; each chain's ladder carried near the
    geometric (1, 4, 16, 64) (median 4.00, 16.1; numpy's `tempering.adapt_ladder` 4.01,
    15.9), where the rates are even (0.21, 0.19, 0.21)."""
    start, n_chains = (1.0, 1.5, 2.0, 64.0), 6
    state = _GaussRows(4 * n_chains)
    gen = torch.Generator().manual_seed(0)
    ad = tb._adapt_ladders(state, np.array([0.1]), start, gen, tqdm(disable=True), 50, 20)
    _is_ladder(ad, n_chains, start)
    assert torch.equal(state.beta, torch.as_tensor(1.0 / ad).flatten())  # the rows' ladders
    assert len({tuple(row) for row in ad}) == n_chains  # each chain its own
    np.testing.assert_allclose(np.log(ad[:, 1:3]), np.log([[4.0, 16.0]] * n_chains), atol=0.3)
    from tests.gpmsa.test_adaptive_ladder_s73 import _copies

    states, rng = _copies(start, d=4)
    numpy = tempering.adapt_ladder(states, start, rng, ["theta"], np.array([0.1]), 50, 20,
                                   lambda n: None)  # fmt: skip
    np.testing.assert_allclose(np.log(np.median(ad, 0)), np.log(numpy), atol=0.2)
    before, after = _rates(state, start), _rates(state, ad)
    assert before.min() < 0.02 and np.ptp(before) > 0.6
    assert np.ptp(after) < 0.1 and after.min() > 0.1


def test_adapted_ladders_on_a_two_mode_fit():
    problem = _problem()
    adapted = tb.sample(problem, adapt_ladder=True, **KW)
    ad = adapted.info["adapted_temperatures"]
    _is_ladder(ad, 4, LADDER)
    assert adapted.info["adapt_ladder"] is True and adapted.info["temperatures"] == LADDER
    assert np.median(ad[:, 1]) < 4.0  # (2.9; numpy's, 1,000 rounds: 2.3)
    assert np.shape(adapted.info["swap_rate"]) == (4, 3)
    fixed = {**KW, "n_iter": 2, "warmup": 0, "tune_rounds": 1, "tune_levels": 2}
    assert "adapted_temperatures" not in tb.sample(problem, **fixed).info


def test_chain_groups_receive_each_chains_ladder(monkeypatch):
    problem = _problem()
    kw = {**KW, "n_iter": 8, "n_chains": 4, "tune_rounds": 4, "tune_levels": 3,
          "temperatures": 3, "adapt_ladder": True}  # fmt: skip
    seen, draws = [], tb._tempered_draws

    def spy(state, ws, temps, *args):
        out = draws(state, ws, temps, *args)
        seen.append((np.array(temps), state.beta.view(-1, 3).cpu().numpy()))
        return out

    monkeypatch.setattr(tb, "_tempered_draws", spy)
    one = tb.sample(problem, **kw)
    grouped = tb.sample(problem, chain_groups=2, n_jobs=1, **kw)
    ad = grouped.info["adapted_temperatures"]
    _is_ladder(ad, 4, [1.0, 2.0, 4.0])
    np.testing.assert_array_equal(ad, one.info["adapted_temperatures"])  # tuned in one batch
    assert np.shape(grouped.info["swap_rate"]) == (4, 2) and grouped.info["chain_groups"] == 2
    (t_one, b_one), *groups = seen
    assert len(groups) == 2
    np.testing.assert_array_equal(np.concatenate([t for t, _ in groups]), ad)
    for temps, betas in seen:  # every row swept and swapped at its chain's ladder
        np.testing.assert_array_equal(betas, 1.0 / temps)


def test_swaps_use_each_chains_betas():
    """Two chains of two copies, the same states; chain 0 at (1, 0.25), chain 1 at (1, 0.9):
    the same uniform accepts the swap in chain 1 alone, and probs are min(1, r) per chain."""
    problem = _problem()
    start = {k: np.stack([v] * 4) for k, v in problem.init.items()}
    start["theta"] = np.array([[0.2], [0.5], [0.2], [0.5]])
    state = tb.BatchState(problem, 4, torch.float64, "cpu", start)
    betas = torch.tensor([[1.0, 0.25], [1.0, 0.9]], dtype=torch.float64)
    state.beta = betas.flatten()
    la, lb = state.loglik.tolist()[:2]
    assert lb < la
    r = np.exp(np.array([0.75, 0.1]) * (lb - la))  # chain 0's ratio the smaller
    u = torch.tensor([[np.sqrt(r[0] * r[1])] * 2], dtype=torch.float64)
    acc, probs = torch.zeros((1, 2), dtype=torch.long), torch.empty((1, 2), dtype=torch.float64)
    tb._swap_rows(state, betas, u, acc, probs)
    assert acc.tolist() == [[0, 1]] and state.loglik.tolist() == [la, lb, lb, la]
    np.testing.assert_allclose(probs[0].numpy(), r, rtol=1e-12)
    shared = torch.zeros((1, 2), dtype=torch.long)  # one ladder as a tuple: as before
    tb._swap_rows(state, (1.0, 0.25), u, shared)  # (chain 1 now from lb up to la: taken)
    assert shared.tolist() == [[0, 1]] and state.loglik.tolist() == [la, lb, la, lb]


def test_fit_and_calibrate_record_it_and_refusals():
    sim, obs = _sym_case()
    opts = {"tune_rounds": 2, "tune_levels": 3, "tune_stages": 1, "warmup": 2}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = gpmsa.fit(sim, obs, n_iter=12, n_burn=2, n_chains=2, seed=1, backend="torch",
                        temperatures=3, adapt_ladder=True, **opts)  # fmt: skip
        post = gpmsa.calibrate(emu, obs, n_samples=12, n_burn=2, n_chains=2, seed=2,
                               backend="torch", fast=False, temperatures=[1.0, 2.0, 8.0],
                               adapt_ladder=True, **opts)  # fmt: skip
    s = emu.settings
    assert s["backend_options"]["adapt_ladder"] is True and s["temperatures"] == [1.0, 2.0, 4.0]
    _is_ladder(np.array(s["adapted_temperatures"]), 2, [1.0, 2.0, 4.0])
    _is_ladder(np.array(post.info["adapted_temperatures"]), 2, [1.0, 2.0, 8.0])
    problem = _problem()
    for kw, words in [
        ({}, "adapt_ladder=True needs temperatures="),
        ({"temperatures": 2}, "at least 3 temperatures"),
        ({"temperatures": 3, "tune": False}, "adapt_ladder=True with tune=False"),
        ({"temperatures": 3, "adapt_ladder": 1}, "adapt_ladder must be True"),
    ]:
        with pytest.raises(GPMSAError, match=words):
            tb.sample(problem, n_iter=5, **{"adapt_ladder": True, **kw})
    with pytest.raises(GPMSAError, match="runs on the numpy and torch backends only"):
        gpmsa.fit(sim, obs, n_iter=10, backend="pyro", adapt_ladder=True)
