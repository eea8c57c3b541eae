"""The Calibrator's grid posterior: constraint boundaries, draws, quantiles, modes, zero priors."""

import warnings
from functools import cache

import numpy as np
import pytest
from _calib_cases import road_emulator, road_obs, two_param_emulator

import gpmsa
from gpmsa import Calibrator
from gpmsa.calibration.posterior import GridMarginal
from gpmsa.fitting.emulator import Emulator


def narrow_road_data():
    """40 road observations: a GD posterior of sd ~3.7 that the default grid must refine."""
    rng = np.random.default_rng(0)
    v = np.linspace(0.6, 1.9, 40)[:, None]
    return v, 0.02 * 410 * v**1.6 * (1 + 0.005 * rng.standard_normal(v.shape))


@cache
def symmetric_emulator() -> Emulator:
    """One x, one parameter t, y = (t - 0.5)^2 (1 + x): t and 1 - t give the same output."""
    rng = np.random.default_rng(5)
    x, t = rng.uniform(0, 1, 60), rng.uniform(0, 1, 60)
    y = (t - 0.5) ** 2 * (1 + x)
    sim = gpmsa.SimData(x=x[:, None], t=t[:, None], y=y[:, None], x_names=["x"], t_names=["t"])
    params = {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [5000.0], "lamWOs": [5000.0]}
    return Emulator.from_params(sim, params)


@cache
def symmetric_two_param_emulator() -> Emulator:
    """One x, parameters a and b, y = (a - 0.5)^2 (1 + x) + 0.3 b x: a and 1 - a look alike."""
    rng = np.random.default_rng(5)
    x, t = rng.uniform(0, 1, 80), rng.uniform(0, 1, (80, 2))
    y = (t[:, 0] - 0.5) ** 2 * (1 + x) + 0.3 * t[:, 1] * x
    sim = gpmsa.SimData(x=x[:, None], t=t, y=y[:, None], x_names=["x"], t_names=["a", "b"])
    params = {"betaU": [[1.0], [1.0], [1.0]], "lamUz": [1.0], "lamWs": [5000.0],
              "lamWOs": [5000.0]}  # fmt: skip
    return Emulator.from_params(sim, params)


def peaks_data() -> tuple[np.ndarray, np.ndarray]:
    """12 observations of `symmetric_two_param_emulator` at a = 0.3, b = 0.5: peaks of a near
    0.3 and 0.7."""
    x = np.linspace(0.05, 0.95, 12)[:, None]
    return x, (0.3 - 0.5) ** 2 * (1 + x) + 0.3 * 0.5 * x


@cache
def fine_peaks_posterior():
    """`peaks_data` on a 257 x 257 grid (resolved: no warning, not refined), made once (5 s)
    for the tests that read it; a warning is an error wherever it is made first."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return Calibrator(symmetric_two_param_emulator(), n_grid=257).update(*peaks_data())


CONSTRAINTS = {  # name: (constraint, the allowed region's bounds within the design, GD)
    "upper": (lambda th: th[0] <= 401.3, (None, 401.3)),
    "lower": (lambda th: th[0] >= 447.7, (447.7, None)),
    "interval": (lambda th: 401.3 <= th[0] <= 447.7, (401.3, 447.7)),
}


@pytest.mark.parametrize("narrow", [False, True], ids=["fixed_grid", "refined_grid"])
@pytest.mark.parametrize("kind", sorted(CONSTRAINTS))
def test_a_constrained_grid_posterior_has_no_mass_outside_the_constraint(kind, narrow):
    """The density used to ramp to zero across the cell past the boundary: ~3 % of the mass
    (and as many draws) lay up to one grid cell outside it."""
    constraint, (lo, hi) = CONSTRAINTS[kind]
    x, y = narrow_road_data() if narrow else road_obs()
    if narrow:  # boundaries through the narrow mode (mean 410.8)
        constraint, (lo, hi) = {
            "upper": (lambda th: th[0] <= 409.0, (None, 409.0)),
            "lower": (lambda th: th[0] >= 409.0, (409.0, None)),
            "interval": (lambda th: 405.0 <= th[0] <= 409.0, (405.0, 409.0)),
        }[kind]
    post = Calibrator(road_emulator(), seed=1, constraint=constraint).update(x, y)
    assert post.info["refined"] is narrow
    grid, draws = post.grids["GD"], post.samples["GD"]
    tol = 1e-12 * 600.0  # float precision of GD
    if hi is not None:
        assert draws.max() <= hi + tol
        assert grid.cdf(hi) == pytest.approx(1.0, abs=1e-12)
        assert post.prob_above("GD", hi) == pytest.approx(0.0, abs=1e-12)
        assert post.quantile("GD", 1.0) == pytest.approx(hi, abs=tol)
    if lo is not None:
        assert draws.min() >= lo - tol
        assert grid.cdf(lo) == pytest.approx(0.0, abs=1e-12)
        assert post.quantile("GD", 0.0) == pytest.approx(lo, abs=tol)
    assert (lo or -np.inf) < post.mean("GD") < (hi or np.inf)
    # the calibrated predictive pairs the grid's nodes with their E[1/lamOs]
    assert len(post.info["expected_inv_lamOs"]) == grid.nodes.size
    pred = gpmsa.predictive.calibrated_predict(road_emulator(), post, [[1.0]], noise=True)
    assert np.all(np.isfinite(pred.mean))


def test_a_constrained_posterior_matches_a_fine_grid():
    """Cut at the boundary, the 129-node posterior is within its second-order error (the density
    has a jump there) of the 4097-node one: mean 0.004 sd, sd 0.13 % off (the leak made them
    0.019 sd and 0.43 %)."""
    x, y = road_obs()
    constraint = lambda th: th[0] <= 401.3  # noqa: E731
    post = Calibrator(road_emulator(), constraint=constraint).update(x, y)
    fine = Calibrator(road_emulator(), n_grid=4097, constraint=constraint).update(x, y)
    assert post.mean("GD") == pytest.approx(fine.mean("GD"), abs=0.01 * fine.sd("GD"))
    assert post.sd("GD") == pytest.approx(fine.sd("GD"), rel=3e-3)


def test_quantiles_end_where_the_mass_ends():
    """ppf(1.0) used to land in the last, zero-mass cell of the grid (the design's end)."""
    x, y = road_obs()
    cal = Calibrator(road_emulator())
    gd = cal.theta_grid
    prior = np.where(gd <= 420.0, 0.0, -np.inf)  # zero density from the first node past 420
    post = cal.update(x, y, prior=prior)
    end = gd[gd > 420.0][0]
    grid = post.grids["GD"]
    assert post.quantile("GD", 1.0) == pytest.approx(end, abs=1e-9)
    assert post.quantile("GD", 0.0) == pytest.approx(gd[0], abs=1e-9)
    q = np.linspace(0.0, 1.0, 2001)
    v = grid.ppf(q)
    assert np.all(np.diff(v) >= 0.0)
    np.testing.assert_allclose(grid.cdf(v), q, atol=1e-12)
    assert post.samples["GD"].max() <= end


def test_a_grid_marginals_quantiles_skip_cells_without_mass():
    """GridMarginal.ppf itself (the BCR's trackers build theirs without trimming): zero-mass
    cells at both ends and inside hold no quantile."""
    nodes = np.arange(9.0)
    density = np.array([0.0, 0.0, 1.0, 2.0, 0.0, 0.0, 1.0, 0.0, 0.0])
    with np.errstate(divide="ignore"):
        grid = GridMarginal.from_log_density(nodes, np.log(density))
    assert grid.ppf(0.0) == 1.0 and grid.ppf(1.0) == 7.0
    assert grid.ppf(0.75) == pytest.approx(4.0)  # mass 3/4 ends at 4, the next begins at 5
    q = np.linspace(0.0, 1.0, 1001)
    v = grid.ppf(q)
    assert np.all(np.diff(v) >= 0.0) and not np.any((v > 4.0) & (v < 5.0))
    np.testing.assert_allclose(grid.cdf(v), q, atol=1e-12)


@pytest.mark.parametrize("refined", [False, True])
def test_two_parameter_draws_follow_the_grid_density(refined):
    """The draws used to pick nodes without trapezoid weights and jitter over a whole cell: their
    mean and tail fraction missed the grid's by 7 to 15 Monte-Carlo errors."""
    emu = two_param_emulator()
    if refined:
        x = np.array([0.1, 0.3, 0.5, 0.7, 0.9])[:, None]
        y = np.sin(2 * x + 1.5 * 0.4) + 0.8 * 0.6 * x
    else:  # one observation: a broad, skewed posterior
        x, y = [[0.3]], [[np.sin(0.6 + 0.6) + 0.8 * 0.6 * 0.3]]
    n = 200_000
    post = Calibrator(emu, n_draws=n, seed=3).update(x, y)
    assert post.info["refined"] is refined
    for name in ("a", "b"):
        draws = post.samples[name]
        assert abs(draws.mean() - post.mean(name)) < 4 * post.sd(name) / np.sqrt(n)
        for q in (0.1, 0.8):
            level = post.quantile(name, q)
            p = post.prob_above(name, level)
            assert abs(np.mean(draws > level) - p) < 4 * np.sqrt(p * (1 - p) / n)
        nodes = post.grids[name].nodes
        assert nodes[0] <= draws.min() and draws.max() <= nodes[-1]
    assert np.all(post.samples["lamOs"] > 0)


def mode_summary(post, split: float = 0.5) -> list[tuple[float, float]]:
    """(mass, mean) of the posterior of t below and above ``split`` (the density is negligible
    there: 1e-11 of its peak or less)."""
    g = post.grids["t"]
    below = float(g.cdf(split))
    w = g.weights * g.density
    out = []
    for mass, side in ((below, g.nodes < split), (1.0 - below, g.nodes >= split)):
        out.append((mass, float(w[side] @ g.nodes[side] / w[side].sum())))
    return out


@pytest.mark.parametrize(
    ("t_true", "n_obs"),
    [(0.3, 30), (0.46, 30)],
    ids=["separated", "touching"],  # by a gap below MASS_CUTOFF of the peak, or not
)
def test_narrow_modes_are_each_refined(t_true, n_obs):
    """Two modes of sd 0.0012 at t = 0.3 and 0.7 (0.0039 at 0.446 and 0.554): the global sd
    (0.19; 0.055) looked resolved, so each mode stayed within a cell or two and their masses
    came out 0.719 / 0.281 instead of 0.645 / 0.355 (0.559 / 0.441 instead of 0.564 / 0.436)."""
    emu = symmetric_emulator()
    x = np.linspace(0.05, 0.95, n_obs)[:, None]
    y = (t_true - 0.5) ** 2 * (1 + x)
    post = Calibrator(emu).update(x, y)
    fine = Calibrator(emu, n_grid=8193).update(x, y)
    pairs = zip(mode_summary(post), mode_summary(fine), strict=True)
    for (mass, mean), (ref_mass, ref_mean) in pairs:
        assert 0.3 < ref_mass < 0.7
        assert mass == pytest.approx(ref_mass, abs=1e-6)
        assert mean == pytest.approx(ref_mean, abs=1e-5)
    assert post.mean("t") == pytest.approx(fine.mean("t"), abs=1e-5)
    assert post.sd("t") == pytest.approx(fine.sd("t"), rel=1e-5)
    assert post.info["refined"] and not fine.info["refined"]


def test_two_parameter_peaks_are_each_refined():
    """Two peaks of a near a = 0.3 and 0.7, not separated by a gap: the old refinement re-gridded
    both parameters with 49 nodes over their whole live range (coarser than the grid for b) and
    found P(a < 0.5) = 0.1366 instead of 0.1473."""
    emu = symmetric_two_param_emulator()
    x, y = peaks_data()
    # two peaks too far apart to refine both within the node budget: the moments below are
    # right, the quantiles and cdf of a are not (0.026 off), and a warning says so
    with pytest.warns(
        UserWarning, match=r"does not resolve the posterior of a: its width \(.*\) spans 0\.8"
    ):
        post = Calibrator(emu).update(x, y)
    fine = fine_peaks_posterior()  # resolved: not refined
    assert post.info["refined"] and not fine.info["refined"]
    assert post.prob_above("a", 0.5) == pytest.approx(fine.prob_above("a", 0.5), abs=1e-4)
    for name in ("a", "b"):
        assert post.mean(name) == pytest.approx(fine.mean(name), abs=1e-3 * fine.sd(name))
        assert post.sd(name) == pytest.approx(fine.sd(name), rel=1e-3)


def test_gridded_prior_with_zeros_survives_refinement_in_two_parameters():
    """-inf in a gridded prior used to become NaN (0 * -inf) when interpolated onto a refined
    grid, and the update was refused."""
    emu = two_param_emulator()
    x = np.array([0.1, 0.3, 0.5, 0.7, 0.9])[:, None]
    y = np.sin(2 * x + 1.5 * 0.4) + 0.8 * 0.6 * x  # a = 0.4, b = 0.6
    cal = Calibrator(emu, n_draws=20_000)
    a = cal.theta_grid[:, 0]
    end = a[a > 0.4].min()  # the prior is zero from the first grid line past a = 0.4
    flat = cal.update(x, y)
    with warnings.catch_warnings():  # resolved: the refined grid keeps only the lines at the
        warnings.simplefilter("error")  # prior's zero edge (all of them held the tails: 0.56)
        post = cal.update(x, y, prior=np.where(a <= 0.4, 0.0, -np.inf))
    assert post.info["refined"] and min(post.info["resolution"]) >= 1.5
    assert post.prob_above("a", end) == 0.0
    assert post.samples["a"].max() <= end
    assert post.mean("a") < flat.mean("a")
    as_table = cal.update(x, y, prior=np.where(a <= 0.4, 0.0, -np.inf).reshape(65, 65))
    assert as_table.mean("a") == post.mean("a")


def test_gridded_prior_with_zeros_survives_refinement_in_one_parameter():
    """The prior between its last positive grid line and its first zero one: the fixed grid's
    linear density ramps to zero across that cell, but a refined grid used to cut it at the last
    positive line (log-linear interpolation to -inf). Both now end at the first zero line, and
    nothing lies past it."""
    cal = Calibrator(road_emulator(), n_draws=20_000)
    gd = cal.theta_grid
    end = gd[gd > 409.0].min()
    post = cal.update(*narrow_road_data(), prior=np.where(gd <= 409.0, 0.0, -np.inf))
    assert post.info["refined"]
    assert post.prob_above("GD", end) == 0.0
    assert post.samples["GD"].max() <= end
    assert post.quantile("GD", 1.0) == pytest.approx(end, abs=1e-6)  # mass ends there


@pytest.mark.parametrize(
    "prior",
    [gpmsa.GammaPrior(1e-30, 1e-3), gpmsa.GammaPrior(1.0, 1e-3, lower=1e300)],
    ids=["shape-near-0", "lower-beyond-the-mass"],
)
def test_a_lamos_prior_beyond_float64s_reach_is_named_by_the_grid(prior):
    """Legal priors whose mass the grid's integral over lamOs cannot reach: ValueError from
    int(NaN) or a negative sample count inside numpy before."""
    from _study_cases import emulator

    emu = emulator(gpmsa.Priors(lamOs=prior))
    with pytest.raises(gpmsa.GPMSAError, match=r"the lamOs prior Gamma\(a=.* has no mass"):
        Calibrator(emu, method="grid").update([[0.5]], [[0.6]])
    ok = emulator(gpmsa.Priors(lamOs=gpmsa.GammaPrior(1.0, 1e-3, lower=10.0)))
    assert 0.0 <= Calibrator(ok, method="grid").update([[0.5]], [[0.6]]).mean("t") <= 1.0


@cache
def sum_only_emulator() -> Emulator:
    """One x, parameters a and b that act only through a + b: precise data make the posterior a
    diagonal ridge far narrower than the grid's node spacing."""
    rng = np.random.default_rng(7)
    x, t = rng.uniform(0, 1, 80), rng.uniform(0, 1, (80, 2))
    y = np.sin(2.0 * x + 1.5 * (t[:, 0] + t[:, 1]))
    sim = gpmsa.SimData(x=x[:, None], t=t, y=y[:, None], x_names=["x"], t_names=["a", "b"])
    params = {"betaU": [[1.0], [1.5], [1.5]], "lamUz": [1.0], "lamWs": [1e6], "lamWOs": [1e6]}
    return Emulator.from_params(sim, params)


def test_calib_a_ridge_narrower_than_the_grid_is_named_not_summarised_silently():
    """A diagonal ridge 0.01 node spacings wide has wide marginals, so refinement left it
    unresolved and the "exact" summaries were silently off (mean by 0.26 sd, sd by 33 %
    against a dense 801 x 801 grid)."""
    x = np.linspace(0.05, 0.95, 30)[:, None]
    y = np.sin(2 * x + 1.5 * 0.8)
    with pytest.warns(UserWarning, match=r"ridge .* n_grid .* method='mcmc'"):
        post = Calibrator(sum_only_emulator()).update(x, y)
    assert post.info["conditional_sds"][0] < 0.1
    emu = two_param_emulator()  # resolved cases: no warning
    x = np.random.default_rng(1).uniform(0.05, 0.95, 40)[:, None]
    for n in (1, 2, 40):
        y = np.sin(2 * x[:n] + 1.5 * 0.3) + 0.8 * 0.7 * x[:n]
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            post = Calibrator(emu).update(x[:n], y)
        assert min(post.info["conditional_sds"]) > 0.5


def test_grid_cdf_is_exact_at_every_node_and_one_where_the_mass_ends():
    """The cdf at a node is the cumulative cell mass itself, not the ramp's formula evaluated
    at the cell's end (1 ulp off it, so that P(X > the support's end) read 1e-16)."""
    rng = np.random.default_rng(5)
    for _ in range(50):
        nodes = np.sort(rng.uniform(0, 10, 40))
        log_density = rng.normal(size=40)
        log_density[rng.integers(20, 40) :] = -np.inf  # the mass ends at a node
        g = GridMarginal.from_log_density(nodes, log_density)
        mass = 0.5 * np.diff(nodes) * (g.density[:-1] + g.density[1:])
        cum = np.concatenate([[0.0], np.cumsum(mass)])
        np.testing.assert_array_equal(g.cdf(nodes), np.clip(cum / cum[-1], 0.0, 1.0))
        last = nodes[np.flatnonzero(g.density > 0)[-1] + 1]  # the mass ends at this node
        assert g.cdf(last) == 1.0 and g.cdf(nodes[-1]) == 1.0
