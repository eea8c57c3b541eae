"""A categorical calibration parameter in a study (session 72, ``gpmsa.studies.sampler``).

The case of ``test_categorical_theta_move_s72.py`` (y = sin(3x) + k + 0.5 kind; kind = 1 at
k = 0.4 and kind = 0 at k = 0.9 explain the data alike) observed in two experiments, one
model each (one emulator for both, or each its own). ``calibrate_study`` / ``fit_study``
refused a categorical theta; with the refusal lifted and no level move, the study's
continuous walk put the element off its levels, and a level-alone move was never accepted
(each chain at its start's level, R-hat of kind 4e15). The joint level move
(``gpmsa.mcmc.level_moves``) gives the brute-force P(kind) over (kind, k, each model's lamOs):
shared kind and k 0.844 / 0.156 / 0 (one emulator; 0.856 with each its own), shared kind and
each model's own k 0.777 / 0.223 / 0; measured 0.836, 0.862, 0.775 (2 x 1,200), R-hat <= 1.02.
"""

import os
import warnings

import numpy as np
import pytest
from _level_cases import level_function

import gpmsa
from gpmsa.calibration.observations import fixed_gp, reduce, theta_levels
from gpmsa.calibration.sampler import ThetaPredictive
from gpmsa.fitting.emulator import EMULATOR_PARAMS
from gpmsa.mcmc.diagnostics import rhat

N_K = 100
"""Grid nodes over unit k."""


def _sim(rng, m=60, k_range=None):
    x = rng.random((m, 1))
    t = np.column_stack([rng.random(m), np.arange(m) % 3])
    if k_range is not None:  # a shared k needs one range in every model
        lo, hi = k_range
        t[:, 0] = lo + (hi - lo) * t[:, 0]
        t[:2, 0] = lo, hi
    return gpmsa.SimData(x, t, level_function(x, t), x_names=["s"], t_names=["k", "kind"],
                         t_categorical=["kind"])  # fmt: skip


@pytest.fixture(scope="module")
def case():
    rng = np.random.default_rng(2)
    sim = _sim(rng)
    emu = gpmsa.fit(sim, n_iter=600, seed=0)
    xa = np.linspace(0.1, 0.9, 6)[:, None]
    ya = level_function(xa, np.column_stack([np.full(6, 0.4), np.full(6, 1)])) + rng.normal(
        0, 0.05, 6
    )
    xb = np.linspace(0.15, 0.85, 5)[:, None]
    yb = level_function(xb, np.column_stack([np.full(5, 0.4), np.full(5, 1)])) + rng.normal(
        0, 0.05, 5
    )
    k = sim.t[:, 0]
    sim2 = _sim(np.random.default_rng(7), k_range=(k.min(), k.max()))
    emu2 = gpmsa.Emulator.from_params(sim2, {k: emu.params[k] for k in EMULATOR_PARAMS})
    return sim, emu, sim2, emu2, (xa, ya), (xb, yb)


@pytest.fixture(scope="module")
def marginals(case):
    """`_log_marginal` of (emu, a), (emu, b), (emu2, b)."""
    _, emu, _, emu2, a, b = case
    return {(0, "a"): _log_marginal(emu, *a), (0, "b"): _log_marginal(emu, *b),
            (1, "b"): _log_marginal(emu2, *b)}  # fmt: skip


def _log_marginal(emu, xo, yo) -> np.ndarray:
    """(levels, N_K): log of the likelihood integrated over the model's lamOs (a grid over log
    lamOs, its prior as the study's reduction sets it), per level and unit k node."""
    data = reduce(emu, xo, yo, False)
    pred = ThetaPredictive(fixed_gp(emu), data, expand=False)
    lo = data.lamos
    lams = np.exp(np.linspace(-5.0, np.log(min(lo.upper, 1e7)), 300))
    power = lo.shape - 1.0 - 0.5 * data.obs.n_null
    out = np.empty((3, N_K))
    for r, level in enumerate(theta_levels(emu)[1]):
        for j, k in enumerate((np.arange(N_K) + 0.5) / N_K):
            e, y2 = pred.at([k, level])
            v = np.asarray(e)[None, :] + 1.0 / lams[:, None]
            ll = -0.5 * np.sum(np.log(v) + np.asarray(y2)[None, :] / v, axis=1)
            ll += (power + 1.0) * np.log(lams) - lo.rate * lams  # d lamOs = lamOs d log lamOs
            top = ll.max()
            out[r, j] = top + np.log(np.exp(ll - top).sum())
    return out


def _grid(priors, parts: list[np.ndarray], shared_k: bool) -> np.ndarray:
    """P(kind) by brute force over (kind, k or each model's k, each model's lamOs) from the
    models' `_log_marginal`s ``parts``."""
    k = (np.arange(N_K) + 0.5) / N_K
    log_prior = -0.5 * ((k - priors.theta_mean) / priors.theta_sd) ** 2
    if shared_k:
        lp = sum(parts) + log_prior
    else:  # each model's own k: integrated per model
        lp = sum(np.logaddexp.reduce(p + log_prior, axis=1) for p in parts)[:, None]
    p = np.exp(lp - lp.max())
    return p.sum(axis=1) / p.sum()


def _levels(draws: np.ndarray) -> np.ndarray:
    return np.array([np.mean(draws == lv) for lv in (0, 1, 2)])


@pytest.mark.parametrize("own, shared", [(False, ["kind", "k"]), (True, ["kind", "k"]),
                                         (False, ["kind"])])  # fmt: skip
def test_calibrate_study_moves_between_levels_and_matches_the_grid(case, marginals, own, shared):
    """Every chain visits both levels, R-hat of kind and k < 1.05, and the pooled P(kind) is
    the brute-force one within Monte-Carlo error (before: GPMSAError, "kind is
    categorical")."""
    _, emu, _, emu2, a, b = case
    emus = [emu, emu2 if own else emu]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)  # lamOs' heavy tail
        study = gpmsa.calibrate_study(emus, [a[0], b[0]], [a[1], b[1]], shared=shared,
                                      seed=1, n_samples=1200, n_burn=200, n_chains=2,
                                      n_jobs=1, tune_rounds=20)  # fmt: skip
    chains = study.posterior.chains
    kind = chains["kind"]
    assert set(np.unique(kind)) == {0.0, 1.0}  # exactly the level codes
    for chain in kind:
        assert 0.6 < np.mean(chain == 0) < 0.97, _levels(chain)
    ks = [n for n in chains if n.startswith("k")]
    assert all(rhat(chains[n]) < 1.05 for n in ks), {n: rhat(chains[n]) for n in ks}
    parts = [marginals[0, "a"], marginals[int(own), "b"]]
    grid = _grid(emu.priors, parts, "k" in shared)
    np.testing.assert_allclose(_levels(kind), grid, atol=0.04)  # measured within 0.02 (seeds 1-4)


def test_a_study_with_a_categorical_theta_saves_loads_and_continues(case, tmp_path):
    """The draws at levels 0 and 1 (unit scale) pass the study file's range check, load back
    as level codes, and a continuation keeps them on the levels."""
    _, emu, _, _, a, b = case
    study = gpmsa.calibrate_study([emu, emu], [a[0], b[0]], [a[1], b[1]], shared=["kind", "k"],
                                  seed=1, n_samples=200, n_burn=50, tune_rounds=5)  # fmt: skip
    path = os.path.join(tmp_path, "s.gpmsa")
    study.save(path)
    back = gpmsa.load_study(path)
    np.testing.assert_array_equal(back.posterior.chains["kind"], study.posterior.chains["kind"])
    more = gpmsa.calibrate_study([emu, emu], [a[0], b[0]], [a[1], b[1]], shared=["kind", "k"],
                                 seed=2, n_samples=100, init=back)  # fmt: skip
    assert set(np.unique(more.posterior.chains["kind"])) <= {0.0, 1.0, 2.0}


def test_fit_study_moves_between_levels(case):
    """fit_study with a shared categorical theta: both chains at both levels, the draws and
    each member's theta_native exactly level codes."""
    sim, _, sim2, _, a, b = case
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        study = gpmsa.fit_study([sim, sim2], [gpmsa.ObsData(*a), gpmsa.ObsData(*b)],
                                shared=["kind", "k"], seed=0, n_iter=400, n_chains=2,
                                n_jobs=1, tune_rounds=20)  # fmt: skip
    kind = study.posterior.chains["kind"]
    for chain in kind:
        assert 0.6 < np.mean(chain == 0) < 0.98, _levels(chain)
    assert abs(np.mean(kind == 0) - 0.86) < 0.12  # grid 0.856 (each its emulator, known)
    for member in study.members:
        assert set(np.unique(member.calibration["theta_native"][:, 1])) <= {0.0, 1.0, 2.0}


def test_refused_by_name(case):
    """A hierarchical categorical parameter (a normal hierarchy over level codes means
    nothing), and a shared one that is continuous in another model, are refused by name."""
    sim, emu, _, _, a, b = case
    with pytest.raises(gpmsa.GPMSAError, match=r"hierarchical parameter 'kind' is categorical"):
        gpmsa.calibrate_study([emu, emu], [a[0], b[0]], [a[1], b[1]], hierarchical=["kind"],
                              n_samples=10, n_burn=2)  # fmt: skip
    plain = gpmsa.SimData(sim.x, sim.t, sim.y[:, 0], x_names=["s"], t_names=["k", "kind"])
    cont = gpmsa.Emulator.from_params(plain, {k: emu.params[k] for k in EMULATOR_PARAMS})
    with pytest.raises(gpmsa.GPMSAError, match=r"shared parameter 'kind' is categorical with "
                                               r"different levels \(or continuous\)"):  # fmt: skip
        gpmsa.calibrate_study([emu, cont], [a[0], b[0]], [a[1], b[1]], shared=["kind"],
                              n_samples=10, n_burn=2)  # fmt: skip


def test_an_even_number_of_levels_starts_at_a_level(case):
    """GPM/SA's start (theta 0.5) lies between two levels: the study starts the element at its
    nearest level (before: GPMSAError, the start outside the theta prior's support)."""
    sim, emu, _, _, a, b = case
    t = sim.t.copy()
    t[:, 1] = np.arange(t.shape[0]) % 2
    two = gpmsa.SimData(sim.x, t, level_function(sim.x, t), x_names=["s"], t_names=["k", "kind"],
                        t_categorical=["kind"])  # fmt: skip
    emu2 = gpmsa.Emulator.from_params(two, {k: emu.params[k] for k in EMULATOR_PARAMS})
    study = gpmsa.calibrate_study(
        [emu2, emu2],
        [a[0], b[0]],
        [a[1], b[1]],
        shared=["kind"],
        seed=0,
        n_samples=50,
        n_burn=10,
        tune_rounds=2,
        init="gpmsa",
    )
    assert set(np.unique(study.posterior.chains["kind"])) <= {0.0, 1.0}
