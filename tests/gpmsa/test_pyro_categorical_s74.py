"""The pyro backend samples a categorical calibration parameter (session 74; it refused one).

NUTS samples the continuous parameters with the levels marginalised out of its density (the
log-sum-exp over the levels of prior x likelihood), each kept draw's levels drawn from their
conditional given it (exact), and after each draw the joint level move (``level_moves``) carries
the chain between the modes of a level and a continuous parameter that trade off. The
trading-off case (``_level_cases``: y = sin(3x) + k + 0.5 kind) has P(kind) = 0.717 / 0.283 / 0
by a brute-force grid.
"""

import warnings

import numpy as np
import pytest
from _level_cases import level_case, level_function, level_sim
from scipy.optimize import brentq

import gpmsa
from gpmsa.calibration.calibrate import calibration_problem
from gpmsa.model.likelihood import log_posterior
from gpmsa.model.problem import prepare

torch = pytest.importorskip("torch")
pb = pytest.importorskip("gpmsa.backends.pyro_backend")
pyro = pytest.importorskip("pyro")


def _joint_problem():
    """A joint fit's Problem of the case (24 runs, 4 observations at k = 0.4, kind 1), the
    emulator's parameters sampled, a linear mean basis."""
    rng = np.random.default_rng(3)
    sim = level_sim(rng, 24)
    xo = np.linspace(0.2, 0.8, 4)[:, None]
    yo = level_function(xo, np.column_stack([np.full(4, 0.4), np.ones(4)]))
    return prepare(sim, gpmsa.ObsData(x=xo, y=yo[:, None]), mean_basis="linear").problem


def _sites(model, start):
    return {pb._site(k): v.unsqueeze(0) for k, v in model.init_values(start).items()}


def test_the_density_nuts_samples_is_the_posterior_summed_over_the_levels():
    prob = _joint_problem()
    model = pb.PyroModel(prob)
    assert model.cat.tolist() == [1] and model.held["theta"][0].tolist() == [0]
    start = {k: np.array(v) for k, v in prob.init.items()}
    start["theta"] = np.array([0.3, 0.5])
    sites = _sites(model, start)
    cond = pyro.poutine.condition(model, data={k: v[0] for k, v in sites.items()})
    got = float(pyro.poutine.trace(cond).get_trace().log_prob_sum())
    each = [log_posterior(prob, {**start, "theta": np.array([0.3, lv])})
            for lv in (0.0, 0.5, 1.0)]  # fmt: skip
    assert got == pytest.approx(float(np.logaddexp.reduce(each)), rel=1e-10)


def test_the_draws_levels_come_from_their_conditional():
    """Given k where kind 0 and 1 explain the data alike (between their modes), each draw's
    level from its conditional: exactly the levels, with the log posterior there."""
    _, emu, xo, yo = level_case()
    prob = calibration_problem(emu, xo, yo)
    model = pb.PyroModel(prob)

    def each(k):
        return np.array([log_posterior(prob, {**prob.init, "theta": np.array([k, lv])})
                         for lv in (0.0, 0.5, 1.0)])  # fmt: skip

    k = brentq(lambda k: np.subtract(*each(k)[:2]), 0.5, 0.8, xtol=1e-9)
    start = {**prob.init, "theta": np.array([k, 0.5])}
    sites = {a: v.repeat(2000, *([1] * (v.dim() - 1))) for a, v in _sites(model, start).items()}
    out, lp = model.draw_levels(model.params(sites), np.random.default_rng(0))
    level = out["theta"][:, 1].numpy()
    assert set(np.unique(level)) <= {0.0, 0.5, 1.0}
    p = np.exp(each(k) - np.logaddexp.reduce(each(k)))
    assert 0.3 < p[0] < 0.7  # both levels likely
    freq = np.array([np.mean(level == lv) for lv in (0.0, 0.5, 1.0)])
    assert np.all(np.abs(freq - p) <= 4 * np.sqrt(p * (1 - p) / 2000) + 1e-12)
    each = each(k)
    np.testing.assert_allclose(lp, each[np.rint(2 * level).astype(int)], rtol=1e-10)


@pytest.fixture(scope="module")
def post():
    """A short pyro calibration of the case (1 chain of 40 draws)."""
    _, emu, xo, yo = level_case()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.OutsideEmulatorWarning)
        return gpmsa.calibrate(emu, xo, yo, n_samples=40, n_burn=0, backend="pyro", seed=1,
                               n_warmup=20, max_tree_depth=3, jit=False)  # fmt: skip


def test_pyro_calibrate_draws_the_levels_as_the_other_backends(post):
    kind = post.samples["kind"]
    assert set(np.unique(kind)) <= {0.0, 1.0, 2.0}  # exactly the level codes
    assert post.info["levels"] == {"kind": [0.0, 1.0, 2.0]} and post.info["backend"] == "pyro"
    assert set(post.quantile("kind", [0.1, 0.5, 0.9])) <= {0.0, 1.0, 2.0}
    # the level move's record, as numpy's and torch's: k's conditional modes per level
    modes = np.array(post.info["level_offsets"]["kind"]["modes"])[0, :2, 0]
    np.testing.assert_allclose(modes, [0.9, 0.4], atol=0.03)
    assert post.info["level_offsets"]["kind"]["shifted"] == ["k"]
    given = post.samples["k"]
    assert np.all(np.abs(given[kind == 1] - 0.4) < 0.15)
    assert np.all(np.abs(given[kind == 0] - 0.9) < 0.15)


def test_pyro_refuses_what_remains_unsupported(monkeypatch):
    _, emu, xo, yo = level_case()  # (a theta constraint it takes: test_pyro_constraint_s75)
    prob = calibration_problem(emu, xo, yo)
    monkeypatch.setattr(pb, "MAX_LEVEL_COMBINATIONS", 2)
    with pytest.raises(gpmsa.GPMSAError, match=r"theta elements \[1\] have 3 = 3, more than "
                       "MAX_LEVEL_COMBINATIONS = 2"):  # fmt: skip
        pb.sample(prob, n_iter=4)
    monkeypatch.undo()
    held = prob.with_fixed({"theta": {0: 0.4}, "lamOs": prob.init["lamOs"]})
    with pytest.raises(gpmsa.GPMSAError, match="every other parameter is held"):
        pb.sample(held, n_iter=4)


@pytest.mark.slow
def test_pyro_level_probabilities_agree_with_the_grid():
    """Measured: 2 x 1,000 draws (300 warm-up), seed 1: P(kind) 0.749 / 0.251 / 0, R-hat 1.004."""
    _, emu, xo, yo = level_case()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.OutsideEmulatorWarning)
        post = gpmsa.calibrate(emu, xo, yo, n_samples=1000, n_burn=0, n_chains=2,
                               backend="pyro", seed=1, n_warmup=300)  # fmt: skip
    kind = post.samples["kind"]
    got = [np.mean(kind == v) for v in (0, 1, 2)]
    np.testing.assert_allclose(got, [0.717, 0.283, 0.0], atol=0.05)
    assert post.info["convergence"]["converged"]
