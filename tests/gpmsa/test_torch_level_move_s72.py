"""The torch backend's joint level move of a categorical theta (session 72, as the numpy
samplers', ``gpmsa.mcmc.level_moves``).

The case of tests/gpmsa/test_categorical_theta_move_s72.py: y = sin(3x) + k + 0.5 kind, where
(k = 0.4, kind = 1) and (k = 0.9, kind = 0) explain the data alike; brute-force P(kind) =
0.717 / 0.283 / 0. Before, the torch sweep moved the level alone: every joint-fit chain stayed at
its start's level (P(kind 0) per chain 0 or 1, R-hat of kind 6e15) and ``calibrate(...,
backend="torch")`` refused the categorical theta.
"""

import warnings

import numpy as np
import pytest
from _level_cases import level_case

import gpmsa
from gpmsa.calibration.calibrate import calibration_problem
from gpmsa.mcmc.diagnostics import rhat
from gpmsa.mcmc.sampler import ChainState
from gpmsa.model.problem import prepare

torch = pytest.importorskip("torch")
tb = pytest.importorskip("gpmsa.backends.torch_backend")


@pytest.fixture(scope="module")
def case():
    return level_case()


def _p_kind0(draws: np.ndarray) -> float:
    return float(np.mean(draws == 0))


def test_torch_offsets_are_the_numpy_samplers(case):
    """The same coordinate search on the same log posterior (torch's likelihood is numpy's
    within 1e-10): the shifts between the conditional modes of k at each level agree."""
    _, emu, xo, yo = case
    problem = calibration_problem(emu, xo, yo)
    params = {k: v.copy() for k, v in problem.init.items()}
    ref = ChainState(problem, params, np.random.default_rng(0))
    ref.learn_level_shifts()
    (_, table, cont, _), = ref.level_shifts.values()  # fmt: skip
    with tb.torch_threads(1), torch.no_grad():  # as sample runs it
        state = tb.BatchState(problem, 2, torch.float64, "cpu")
        state.learn_level_shifts()
    assert state.shift_elements == cont == [0] and set(state.level_shifts) == {1}
    off = state.level_shifts[1].numpy()  # (chains, levels, continuous elements)
    for r in range(3):
        for s in range(3):
            np.testing.assert_allclose(off[:, s] - off[:, r], [table[r][s]] * 2, atol=1e-12)
    assert abs(off[0, 1, 0] - off[0, 0, 0] + 0.5) < 0.02  # kind 0 -> 1: k down by 0.5


def test_torch_calibrate_matches_the_grid(case):
    """calibrate(backend="torch") samples a categorical theta (before: refused); every chain at
    both levels, P(kind) within Monte-Carlo error of the brute-force grid (measured 0.720 +-
    0.008 over 8 seeds of 4 x 3,000, numpy's fast=False 0.715 +- 0.009)."""
    _, emu, xo, yo = case
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        post = gpmsa.calibrate(emu, xo, yo, seed=1, n_samples=1200, n_burn=200, n_chains=2,
                               backend="torch", warmup=50, tune_rounds=10)  # fmt: skip
    kind = post.chains["kind"]
    for chain in kind:
        assert 0.5 < _p_kind0(chain) < 0.9
    assert rhat(kind) < 1.05 and rhat(post.chains["k"]) < 1.05
    levels = [np.mean(kind == lv) for lv in (0, 1, 2)]
    np.testing.assert_allclose(levels, [0.717, 0.283, 0.0], atol=0.06)
    assert 0.7 < post.mean("k") < 0.8  # grid 0.759


def test_torch_joint_fit_chains_move_between_levels(case):
    """The joint fit's chains, started at kind 0 and kind 1, each visit both levels, in chain
    groups too (the offsets go to each group); before, both ended at kind 1 (P(kind 0) = 0)."""
    sim, _, xo, yo = case
    problem = prepare(sim, gpmsa.ObsData(xo, yo)).problem
    ch = tb.sample(problem, n_iter=150, n_chains=2, seed=0, warmup=30, tune_rounds=2,
                   tune_levels=3, tune_stages=1, chain_groups=2, n_jobs=1)  # fmt: skip
    kind = ch.draws["theta"][..., 1]  # unit scale: levels 0, 0.5, 1
    assert set(ch.info["starts"]["theta"][:, 1]) == {0.0, 0.5}
    for chain in kind:
        assert 0.45 < _p_kind0(chain) < 0.95
    assert not np.any(kind == 1.0)
