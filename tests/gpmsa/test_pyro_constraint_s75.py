"""The pyro backend takes a theta constraint (session 75; it refused one).

A theta the constraint rejects has log density -inf in the density NUTS samples (a constant of
the detached verdict): an infinite energy, which pyro's NUTS treats as a divergence whose
subtree gets zero weight, so the chain stays exact. With a categorical theta each level
combination's term is -inf where the constraint rejects it, and the level draws and moves take
the same -inf. The broad case (``test_constraint_two_params``: one observation, a + b <= 1.1556
through the posterior's mean) cuts off 39 % of the unconstrained posterior's mass.
"""

import warnings

import numpy as np
import pytest
from _calib_cases import two_param_emulator
from _level_cases import level_case

import gpmsa
from gpmsa import backends
from gpmsa.calibration.calibrate import calibration_problem
from gpmsa.mcmc.diagnostics import ess
from gpmsa.model.likelihood import log_posterior

torch = pytest.importorskip("torch")
pyro = pytest.importorskip("pyro")
pb = pytest.importorskip("gpmsa.backends.pyro_backend")

CUT = 1.1556
X_OBS, Y_OBS = [[0.3]], [[np.sin(0.6 + 0.6) + 0.8 * 0.6 * 0.3]]


def below_line(th) -> bool:
    return bool(th[0] + th[1] <= CUT)


def _density(model, start) -> float:
    """The log density of ``model``'s pyro trace at ``start`` (name -> array, model scales)."""
    sites = {pb._site(k): v for k, v in model.init_values(start).items()}
    cond = pyro.poutine.condition(model, data=sites)
    return float(pyro.poutine.trace(cond).get_trace().log_prob_sum())


def _unit(emu, native):
    std = emu.standardizer
    return (np.asarray(native, dtype=float) - std.t_min) / (std.t_max - std.t_min)


def test_the_density_is_minus_infinity_outside_and_unchanged_inside():
    emu = two_param_emulator()
    free = calibration_problem(emu, X_OBS, Y_OBS)
    cut = calibration_problem(emu, X_OBS, Y_OBS, constraint=below_line)
    inside = {**free.init, "theta": _unit(emu, [0.5, 0.5])}
    outside = {**free.init, "theta": _unit(emu, [0.7, 0.6])}
    for start in (inside, outside):
        assert _density(pb.PyroModel(free), start) == pytest.approx(
            log_posterior(free, start), rel=1e-10)  # fmt: skip
    assert _density(pb.PyroModel(cut), inside) == _density(pb.PyroModel(free), inside)
    assert _density(pb.PyroModel(cut), outside) == -np.inf


def test_held_elements_enter_the_constraint_at_their_values():
    """b held at 0.7: a = 0.5 is rejected (0.5 + 0.7 > CUT), a = 0.4 allowed."""
    emu = two_param_emulator()
    prob = calibration_problem(emu, X_OBS, Y_OBS, constraint=below_line, theta_init=[0.4, 0.7])
    prob = prob.with_fixed({"theta": {1: float(_unit(emu, [0.4, 0.7])[1])}})
    model = pb.PyroModel(prob)
    assert model.held["theta"][0].tolist() == [0]
    ok = {**prob.init, "theta": _unit(emu, [0.4, 0.7])}
    bad = {**prob.init, "theta": _unit(emu, [0.5, 0.7])}
    assert np.isfinite(_density(model, ok)) and _density(model, bad) == -np.inf


def test_a_rejected_start_is_numpys_error():
    emu = two_param_emulator()
    prob = calibration_problem(emu, X_OBS, Y_OBS, constraint=lambda th: bool(th.sum() <= 0.2))
    with pytest.raises(gpmsa.GPMSAError) as numpy_error:
        backends.get("numpy").sample(prob, n_iter=4)
    with pytest.raises(gpmsa.GPMSAError) as pyro_error:
        pb.sample(prob, n_iter=4)
    assert str(numpy_error.value) == str(pyro_error.value)  # both before any chain runs
    assert isinstance(pyro_error.value, gpmsa.StartRejectedError)
    assert "the theta constraint rejects the initial value" in str(pyro_error.value)
    assert "pass theta_init=" in str(pyro_error.value)
    with pytest.raises(gpmsa.GPMSAError, match="no 'jitter' start of theta inside"):
        pb.sample(prob, n_iter=4, n_chains=2)  # dispersed starts: redrawn, as numpy's


def test_nuts_on_a_jit_compiled_default_keeps_every_draw_inside():
    """jit=True (the default) with a constraint: the trace would freeze the verdict of the
    start, and the chain would cross the boundary; the potential is not compiled."""
    emu = two_param_emulator()
    post = gpmsa.calibrate(emu, X_OBS, Y_OBS, backend="pyro", constraint=below_line, seed=2,
                           theta_init=[0.5, 0.5], n_samples=30, n_burn=0, n_warmup=15,
                           max_tree_depth=3)  # fmt: skip
    a, b = post.samples["a"], post.samples["b"]
    assert np.ptp(a) > 0.05 and np.all(a + b <= CUT)
    assert post.info["backend"] == "pyro"


@pytest.mark.slow
def test_nuts_with_a_hard_wall_samples_the_truncated_density():
    """pyro's NUTS itself on N(0, 1) cut at x <= 0.3 by a -inf factor of the detached verdict
    (as `PyroModel.log_prior`'s): the truncated normal's mean -phi(0.3) / Phi(0.3) = -0.6174,
    within 4 se."""
    from scipy.stats import norm

    def model():
        x = pyro.sample("x", pyro.distributions.Normal(0.0, 1.0))
        pyro.factor("wall", torch.tensor(0.0 if float(x.detach()) <= 0.3 else -np.inf))

    with torch.random.fork_rng():
        torch.manual_seed(0)
        kernel = pyro.infer.NUTS(model, jit_compile=False, max_tree_depth=4,
                                 init_strategy=pyro.infer.autoguide.init_to_value(
                                     values={"x": torch.tensor(0.0)}))  # fmt: skip
        mcmc = pyro.infer.MCMC(kernel, num_samples=1000, warmup_steps=200, disable_progbar=True)
        mcmc.run()
    x = mcmc.get_samples()["x"].numpy()
    assert x.max() <= 0.3
    truth = -norm.pdf(0.3) / norm.cdf(0.3)
    se = x.std() / np.sqrt(ess(x[None]))
    assert abs(x.mean() - truth) < 4 * se, (x.mean(), truth, se)


def _level_problem(constraint):
    _, emu, xo, yo = level_case()
    return calibration_problem(emu, xo, yo, constraint=constraint)


def no_kind0_above(th) -> bool:
    """The level case's region: kind 0 only with k < 0.7 (its mode, k = 0.9, cut off)."""
    return bool(th[1] != 0 or th[0] < 0.7)


def test_each_level_combination_is_minus_infinity_where_rejected():
    prob = _level_problem(no_kind0_above)
    model = pb.PyroModel(prob)
    for k in (0.5, 0.9):
        start = {**prob.init, "theta": np.array([k, 0.5])}
        each = np.array([log_posterior(prob, {**start, "theta": np.array([k, lv])})
                         for lv in (0.0, 0.5, 1.0)])  # fmt: skip
        rejected = [not prob.constraint(np.array([k, lv])) for lv in (0.0, 0.5, 1.0)]
        assert rejected == [k == 0.9, False, False]
        each[rejected] = -np.inf
        got = _density(model, start)
        assert got == pytest.approx(float(np.logaddexp.reduce(each)), rel=1e-10)
    # the level draws: at k = 0.9 level 0 is the likeliest unconstrained, never drawn with it
    sites = {
        pb._site(a): v.unsqueeze(0).repeat(500, *([1] * v.dim()))
        for a, v in model.init_values({**prob.init, "theta": np.array([0.9, 0.5])}).items()
    }
    out, lp = model.draw_levels(model.params(sites), np.random.default_rng(0))
    assert set(np.unique(out["theta"][:, 1].numpy())) <= {0.5, 1.0} and np.all(np.isfinite(lp))


def test_pyro_calibrate_with_levels_and_a_constraint_draws_inside():
    """The level moves (`LevelJumps`) from kind 1 (k ~ 0.4) to kind 0 shift k to ~0.9, which
    the constraint rejects: never accepted, and no draw lies outside."""
    _, emu, xo, yo = level_case()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.OutsideEmulatorWarning)
        post = gpmsa.calibrate(emu, xo, yo, n_samples=40, n_burn=0, backend="pyro", seed=1,
                               n_warmup=20, max_tree_depth=3, constraint=no_kind0_above,
                               theta_init=[0.4, 1])  # fmt: skip
    k, kind = post.samples["k"], post.samples["kind"]
    assert all(no_kind0_above([a, b]) for a, b in zip(k, kind, strict=True))
    assert set(np.unique(kind)) <= {0.0, 1.0, 2.0} and np.mean(kind == 1) > 0.5


@pytest.mark.slow
def test_pyro_agrees_with_the_grid_under_the_constraint():
    """Each moment within 4 of its Monte-Carlo se (ESS-based) of the grid's (200,000 draws);
    measured (seed 1, 2 x 600 draws after 200 warm-up, 100-260 s): a 0.537 / 0.541, b 0.437 /
    0.444, P(a < 0.5) 0.424 / 0.418 (se 0.011, 0.011, 0.035)."""
    emu = two_param_emulator()
    grid = gpmsa.Calibrator(emu, n_draws=200_000, seed=4, constraint=below_line)
    ref = grid.update(X_OBS, Y_OBS).samples
    post = gpmsa.calibrate(emu, X_OBS, Y_OBS, backend="pyro", constraint=below_line, seed=1,
                           theta_init=[0.4, 0.4], n_samples=600, n_burn=0, n_chains=2,
                           n_warmup=200)  # fmt: skip
    a, b = post.samples["a"].reshape(2, -1), post.samples["b"].reshape(2, -1)
    assert np.all(a + b <= CUT)
    for got, want in ((a, ref["a"]), (b, ref["b"]), (a < 0.5, ref["a"] < 0.5)):
        got = got.astype(float)
        se = got.std() / np.sqrt(ess(got))
        assert abs(got.mean() - want.mean()) < 4 * se, (got.mean(), want.mean(), se)
