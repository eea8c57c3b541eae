"""One-parameter grid refinement at its edges: heavy tails holding the grid beyond its node
budget (the region above 1e-14 of the peak spanning the whole axis: no refinement factor fitted
MAX_REFINED, refinement stopped unresolved and said nothing), and a posterior narrower than the
four refinement passes reached (sd under about 1e-9 of the range: sd, quantiles and draws
silently wrong), down to float64's resolution of the parameter."""

import warnings
from dataclasses import replace
from functools import cache

import numpy as np
import pytest
from _calib_cases import road_emulator, road_obs
from scipy.integrate import cumulative_trapezoid
from scipy.stats import norm

import gpmsa
from gpmsa import Calibrator
from gpmsa.calibration.grid import MAX_REFINED, N_REFINE, _resolution, refined_axis
from gpmsa.calibration.observations import reduce
from gpmsa.fitting.emulator import Emulator

LEVELS = np.array([0.001, 0.01, 0.05, 0.25, 0.5, 0.75, 0.95, 0.99, 0.999])


def vague_lamos_emulator() -> Emulator:
    """y = 0.3 x + t (60 runs, emulator variance ~1e-5) with a vague lamOs prior, Gamma(1, 1e-6):
    a few observations give a narrow peak (sd ~1e-3 of the range) whose Student-t tails (lamOs
    integrated out) stay above 1e-14 of the peak over the whole axis."""
    rng = np.random.default_rng(5)
    x, t = rng.uniform(0, 1, 60), rng.uniform(0, 1, 60)
    sim = gpmsa.SimData(x=x[:, None], t=t[:, None], y=(0.3 * x + t)[:, None], x_names=["x"],
                        t_names=["t"])  # fmt: skip
    params = {"betaU": [[0.1], [0.1]], "lamUz": [1.0], "lamWs": [1e5], "lamWOs": [1e5]}
    priors = replace(gpmsa.Priors(), lamOs=gpmsa.GammaPrior(a=1.0, b=1e-6))
    return Emulator.from_params(sim, params, priors=priors)


def observations(n: int):
    x = np.linspace(0.1, 0.9, n)[:, None]
    return x, 0.3 * x + 0.4 + 1e-4 * np.random.default_rng(0).standard_normal(x.shape)


@cache
def dense_log_posterior(n: int, around: float) -> tuple[np.ndarray, np.ndarray]:
    """(unit-scale nodes, log posterior) of `observations` (n) on `vague_lamos_emulator` (the
    Calibrator's per-node likelihood, lamOs integrated): the whole axis at 1/20000 plus nodes
    1/400000 apart within 0.05 of ``around`` (tens of nodes per sd). It depends on neither the
    Calibrator's n_grid nor its constraint (the same to the bit), so the tests of one ``n``
    share it (1.2 s each); read-only."""
    u = np.unique(np.concatenate([np.linspace(0, 1, 20001),
                                  np.linspace(around - 0.05, around + 0.05, 40001)]))  # fmt: skip
    cal = Calibrator(vague_lamos_emulator())
    data = reduce(cal.emulator, *observations(n), False)
    logp = np.concatenate([cal._combine(cal._marginals(data, t)) + cal._theta_prior_at(t, None)
                           for t in np.array_split(u[:, None], 15)])  # fmt: skip
    u.setflags(write=False)
    logp.setflags(write=False)
    return u, logp


def dense_reference(n: int, around: float, cut: float | None = None):
    """(sd, quantiles at LEVELS) of the exact posterior of `observations` (n) on
    `vague_lamos_emulator` (`dense_log_posterior`); ``cut``: cut below this (native), a node
    inserted there."""
    u, logp = dense_log_posterior(n, around)
    std = vague_lamos_emulator().standardizer
    nodes = u * (std.t_max[0] - std.t_min[0]) + std.t_min[0]
    if cut is not None:
        native, nodes = nodes, np.unique(np.concatenate([nodes[nodes >= cut], [cut]]))
        logp = np.interp(nodes, native, logp)
    f = np.exp(logp - logp.max())
    cdf = cumulative_trapezoid(f, nodes, initial=0.0)
    f, cdf = f / cdf[-1], cdf / cdf[-1]
    mean = np.trapezoid(nodes * f, nodes)
    sd = np.sqrt(np.trapezoid((nodes - mean) ** 2 * f, nodes))
    return sd, np.interp(LEVELS, cdf, nodes)


@pytest.mark.parametrize(("n", "n_grid"), [(2, 129), (3, 129), (2, 33)])
def test_heavy_tails_beyond_the_node_budget_are_refined_over_their_core(n, n_grid):
    """Refinement stopped on 513 nodes at 0.5 node spacings per sd: quantiles 0.87 sd (n = 2)
    and 1.45 sd (n = 3) off the dense grid, the cdf 0.14 and 0.18, sd() 18 % and 43 % high,
    silently. Now the core holding all but TAIL_MASS is refined (its tails thinned): within
    0.01 sd and 0.001, sd() within 0.1 %, at about 8 spacings per sd, no warning."""
    emu = vague_lamos_emulator()
    x, y = observations(n)
    cal = Calibrator(emu, method="grid", n_grid=n_grid)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        post = cal.update(x, y)
    sd, quantiles = dense_reference(n, around=0.4)
    gm = post.grids["t"]
    assert np.max(np.abs(post.quantile("t", LEVELS) - quantiles)) < 0.015 * sd
    assert np.max(np.abs(gm.cdf(quantiles) - LEVELS)) < 0.001
    assert gm.sd() == pytest.approx(sd, rel=1e-3)
    assert _resolution(gm.nodes, gm.density) > 6.0
    assert post.info["refined"] and post.info["n_nodes"] <= MAX_REFINED * N_REFINE


@pytest.mark.parametrize("scale", [1e-10, 1e-12])
def test_a_posterior_far_narrower_than_the_grid_is_refined_to_it(scale):
    """A Gaussian prior of sd ``scale`` times the range on the road case: four passes stopped
    at spacings of about 5e-10 of the range, so that at 1e-10 sd() was 0.034 of the truth and
    the quantiles 1.7 sd off (1e-12: sd() 1.4e-4 of it, quantiles 300 sd off), silently. Now
    refinement goes on (MAX_REFINE_ONE passes): sd and quantiles of the (essentially prior)
    posterior within 1 % and 0.01 sd."""
    emu = road_emulator()
    sd = scale * (emu.standardizer.t_max[0] - emu.standardizer.t_min[0])
    centre = 400.123456789
    cal = Calibrator(emu, method="grid", seed=1)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        post = cal.update(*road_obs(), prior=lambda t: -0.5 * ((t - centre) / sd) ** 2)
    quantiles = centre + sd * norm.ppf(LEVELS[1:-1])
    assert np.max(np.abs(post.quantile("GD", LEVELS[1:-1]) - quantiles)) < 0.01 * sd
    assert post.sd("GD") == pytest.approx(sd, rel=0.01)
    assert np.std(post.samples["GD"]) == pytest.approx(sd, rel=0.05)
    assert post.info["refined"]


def test_a_posterior_narrower_than_float64_resolves_is_named():
    """sd 1e-15 of the range: refinement stops where nodes would be closer than MIN_STEP_ULPS
    float64 spacings (the posterior on 3 nodes, sd() 0); a warning says so, with the spacing
    to which its summaries are good."""
    emu = road_emulator()
    sd = 1e-15 * (emu.standardizer.t_max[0] - emu.standardizer.t_min[0])
    cal = Calibrator(emu, method="grid")
    match = r"posterior of GD is narrower than the grid can represent: .* float64's resolution"
    with pytest.warns(UserWarning, match=match) as caught:
        post = cal.update(*road_obs(), prior=lambda t: -0.5 * ((t - 400.1) / sd) ** 2)
    spacing = float(str(caught[0].message).rsplit(", ", 1)[1])  # "... there, 2.92e-11"
    assert spacing < 1e-10
    assert post.quantile("GD", 0.5) == pytest.approx(400.1, abs=spacing)


def test_refined_axis_says_why_it_stops():
    """`refined_axis`: a resolved peak ("resolved", the hot path), an unresolved one
    ("refine"), and one that needs nodes closer than ``min_step`` ("float")."""
    axis = np.linspace(0.0, 1.0, 129)
    assert refined_axis(axis, -0.5 * ((axis - 0.4) / 0.1) ** 2, None, 1e-15) == (None, "resolved")
    narrow = -0.5 * ((axis - 0.4) / 1e-3) ** 2
    finer, why = refined_axis(axis, narrow, None, 1e-15)
    assert why == "refine" and finer.size == N_REFINE and np.diff(finer).max() < 1e-3
    assert refined_axis(axis, narrow, None, 1e-3) == (None, "float")


@pytest.mark.parametrize("n_grid", [513, 1025, 2049])
def test_a_fine_gridded_prior_with_zeros_no_longer_holds_refinement_at_its_nodes(n_grid):
    """A gridded prior with zeros made every refined grid keep all its lines, so a base grid
    finer than the node budget was never refined: with the prior zero beyond 0.6 (where no mass
    lies) the quantiles were 0.87 / 0.27 / 0.063 sd off at n_grid 513 / 1025 / 2049 (the first
    two warned, the last silent). Only the lines at the prior's zero edge are kept now."""
    emu = vague_lamos_emulator()
    x, y = observations(2)
    cal = Calibrator(emu, method="grid", n_grid=n_grid)
    unit = np.linspace(0.0, 1.0, n_grid)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        post = cal.update(x, y, prior=np.where(unit > 0.6, -np.inf, 0.0))
    sd, quantiles = dense_reference(2, around=0.4)
    inner = slice(1, -1)  # 0.01-0.99: the prior's zero beyond 0.6 cuts the far tail only
    assert np.max(np.abs(post.quantile("t", LEVELS[inner]) - quantiles[inner])) < 0.015 * sd
    assert post.prob_above("t", post.grids["t"].nodes[-1]) == 0.0
    assert post.samples["t"].max() <= emu.standardizer.t_from_unit(np.array([[0.6]]))[0, 0]
