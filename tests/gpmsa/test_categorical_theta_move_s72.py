"""A categorical theta's joint level move (session 72, ``gpmsa.mcmc.level_moves``).

y = sin(3x) + k + 0.5 kind: (k = 0.4, kind = 1) and (k = 0.9, kind = 0) explain the data
equally well (both inside the design), kind = 2 would need k = -0.1. A move of the level alone
shifts the output by 0.5 against a noise sd of 0.05 and was never accepted: every sampler stayed
at its start's level (the fast sampler, whose chains all start at kind = 1, gave P(kind = 1) =
1 with R-hat 1.00; the generic and joint-fit chains started elsewhere disagreed, R-hat of k
1.5-2.4). The brute-force posterior over (kind, k, lamOs) gives P(kind) = 0.717 / 0.283 / 0.
"""

import warnings

import numpy as np
import pytest
from _level_cases import level_case

import gpmsa
from gpmsa.calibration.observations import fixed_gp, reduce, theta_levels
from gpmsa.calibration.sampler import ThetaPredictive
from gpmsa.mcmc import level_moves
from gpmsa.mcmc.diagnostics import rhat
from gpmsa.model.likelihood import IncrementalLikelihood, log_likelihood
from gpmsa.model.problem import prepare


@pytest.fixture(scope="module")
def case():
    return level_case()


def _grid_level_probabilities(emu, xo, yo) -> np.ndarray:
    """P(kind) by brute force: a grid over unit k (200 nodes) and log lamOs (300), per level."""
    data = reduce(emu, xo, yo, False)
    pred = ThetaPredictive(fixed_gp(emu), data, expand=False)
    lo, pri = data.lamos, emu.priors
    lams = np.exp(np.linspace(-5.0, np.log(min(lo.upper, 1e7)), 300))
    power = lo.shape - 1.0 - 0.5 * data.obs.n_null
    out = []
    for level in theta_levels(emu)[1]:
        per_k = []
        for k in (np.arange(200) + 0.5) / 200:
            e, y2 = pred.at([k, level])
            v = np.asarray(e)[None, :] + 1.0 / lams[:, None]
            ll = -0.5 * np.sum(np.log(v) + np.asarray(y2)[None, :] / v, axis=1)
            ll += (power + 1.0) * np.log(lams) - lo.rate * lams  # d lamOs = lamOs d log lamOs
            top = ll.max()
            per_k.append(top + np.log(np.exp(ll - top).sum())
                         - 0.5 * ((k - pri.theta_mean) / pri.theta_sd) ** 2)  # fmt: skip
        out.append(per_k)
    out = np.array(out)
    p = np.exp(out - out.max())
    return p.sum(1) / p.sum()


def _levels(draws: np.ndarray) -> np.ndarray:
    return np.array([np.mean(draws == lv) for lv in (0, 1, 2)])


def test_the_grid_reference(case):
    _, emu, xo, yo = case
    np.testing.assert_allclose(_grid_level_probabilities(emu, xo, yo), [0.717, 0.283, 0.0],
                               atol=0.01)  # fmt: skip


@pytest.mark.parametrize("kw", [{}, {"fast": False}, {"fast": False, "discrepancy": "constant"}])
def test_calibrate_moves_between_levels_and_matches_the_grid(case, kw):
    """Every chain visits both levels and the pooled P(kind) is the brute-force one (within
    Monte-Carlo error): before the move the fast sampler gave [0, 1, 0], fast=False was
    refused (with the refusal lifted, R-hat of kind 1e15 or 3-11 with a discrepancy)."""
    _, emu, xo, yo = case
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        post = gpmsa.calibrate(emu, xo, yo, seed=1, n_samples=1500, n_burn=300, n_chains=2,
                               n_jobs=1, **kw)  # fmt: skip
    kind = post.chains["kind"]
    for chain in kind:
        assert 0.5 < np.mean(chain == 0) < 0.9, _levels(chain)
    assert rhat(kind) < 1.05 and rhat(post.chains["k"]) < 1.05
    target = [0.717, 0.283, 0.0] if "discrepancy" not in kw else [0.69, 0.30, 0.01]
    np.testing.assert_allclose(_levels(kind), target, atol=0.06)
    assert 0.7 < post.mean("k") < 0.8  # grid 0.759: E[k | kind 0] 0.90, E[k | kind 1] 0.41


def test_joint_fit_moves_between_levels(case):
    """gpmsa.fit(sim, obs) with the categorical theta: every chain at both levels (before: each
    chain at one, P(kind 0) per chain 0 or 1, R-hat of k 1.5-2.4)."""
    sim, _, xo, yo = case
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        emu = gpmsa.fit(sim, gpmsa.ObsData(xo, yo), n_iter=500, n_chains=2, seed=0, n_jobs=1)
    th = emu.calibration["theta_native"].reshape(2, -1, 2)
    for chain in th[..., 1]:
        assert 0.45 < np.mean(chain == 0) < 0.95, _levels(chain)
    assert abs(np.mean(th[..., 1] == 0) - 0.72) < 0.12  # measured 0.72-0.74 (4 x 1,500)


def test_the_move_is_its_own_reverse_and_propose_theta_is_propose(case):
    """The shift r -> s is exactly minus s -> r (a volume-preserving involution pair), and the
    incremental likelihood's whole-theta proposal gives ``propose``'s bits for one element and
    the reference likelihood for several."""
    sim, _, xo, yo = case
    table = level_moves.shift_table(np.array([[0.9], [0.4], [0.05]]) + 1e-3 * np.pi)
    for r in range(3):
        for s in range(3):
            assert table[r][s] == tuple(-v for v in table[s][r])
    problem = prepare(sim, gpmsa.ObsData(xo, yo)).problem
    params = {k: v.copy() for k, v in problem.init.items()}
    inc = IncrementalLikelihood(problem, params)
    one = inc.propose("theta", (0,), 0.3)
    theta = params["theta"].copy()
    theta[0] = 0.3
    assert inc.propose_theta(theta) == one
    theta[:] = [0.7, 0.0]
    ll = inc.propose_theta(theta)
    inc.accept()
    assert ll == pytest.approx(log_likelihood(problem, {**params, "theta": theta}), rel=1e-10)


def test_the_studies_refuse_a_hierarchical_categorical_theta(case):
    """The studies make the joint level move too (``tests/gpmsa/test_study_categorical_s72.py``)
    for a shared or a model's own categorical theta; a hierarchical one is refused by name."""
    _, emu, xo, yo = case
    with pytest.raises(gpmsa.GPMSAError, match=r"hierarchical parameter 'kind' is categorical"):
        gpmsa.calibrate_study([emu, emu], [xo, xo], [yo, yo], hierarchical=["kind"],
                              n_samples=10, n_burn=2)  # fmt: skip
