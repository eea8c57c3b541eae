"""The grid posterior of two parameters with heavy tails (few observations, lamOs integrated):
refinement gave up silently when the nodes above MASS_CUTOFF spanned the whole axis."""

import warnings

import numpy as np
import pytest
from _calib_cases import road_emulator, road_obs, two_param_emulator
from scipy.integrate import cumulative_trapezoid
from test_calib_grid_posterior import symmetric_two_param_emulator

from gpmsa import Calibrator
from gpmsa.calibration.grid import mesh
from gpmsa.calibration.observations import reduce
from gpmsa.calibration.posterior import trapezoid_weights

LEVELS = np.array([0.01, 0.05, 0.25, 0.5, 0.75, 0.95, 0.99])


def five_observations():
    """5 observations of the two-parameter case at a = 0.3, b = 0.6, noise sd 0.01."""
    x = np.linspace(0.05, 0.95, 5)[:, None]
    y = np.sin(2.0 * x + 1.5 * 0.3) + 0.8 * 0.6 * x
    return x, y + 0.01 * np.random.default_rng(1).standard_normal(x.shape)


def dense_reference(cal, x, y, center, sd):
    """Per parameter (mean, sd, quantiles at LEVELS) of the exact posterior (the Calibrator's
    per-node likelihood, lamOs integrated) on a dense grid: the whole domain at 1/128 plus
    161 nodes over the mean +- 12 sd (unit scale)."""
    axes = [
        np.unique(np.concatenate([np.linspace(0, 1, 129),
                                  np.clip(np.linspace(c - 12 * s, c + 12 * s, 161), 0, 1)]))
        for c, s in zip(center, sd, strict=True)
    ]  # fmt: skip
    theta = mesh(axes)
    data = reduce(cal.emulator, x, y, False)
    logp = cal._combine(cal._marginals(data, theta)) + cal._theta_prior_at(theta, None)
    f = np.exp(logp - logp.max()).reshape(axes[0].size, axes[1].size)
    std = cal.emulator.standardizer
    out = []
    for k in range(2):
        w = trapezoid_weights(axes[1 - k])
        marg = f @ w if k == 0 else w @ f
        nodes = axes[k] * (std.t_max[k] - std.t_min[k]) + std.t_min[k]
        cdf = cumulative_trapezoid(marg, nodes, initial=0.0)
        marg, cdf = marg / cdf[-1], cdf / cdf[-1]
        mean = np.trapezoid(nodes * marg, nodes)
        sd_k = np.sqrt(np.trapezoid((nodes - mean) ** 2 * marg, nodes))
        out.append((mean, sd_k, np.interp(LEVELS, cdf, nodes)))
    return out


@pytest.mark.parametrize("n_grid", [65, 129])
def test_calib_a_heavy_tailed_posterior_is_refined_over_its_mass(n_grid):
    """The default grid refined a to 1.1 node spacings per sd over the whole axis and stopped
    (quantiles 0.19 sd and the cdf 0.025 off a dense grid); n_grid=129 could not refine at all
    (0.10 sd, 0.018); neither warned. Now each axis is cut to the nodes holding all but
    TAIL_MASS of its mass and refined there."""
    emu = two_param_emulator()
    x, y = five_observations()
    cal = Calibrator(emu, n_grid=n_grid)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        post = cal.update(x, y)
    std = emu.standardizer
    center = [(post.mean(n) - std.t_min[k]) / (std.t_max[k] - std.t_min[k])
              for k, n in enumerate(emu.t_names)]  # fmt: skip
    sd = [post.sd(n) / (std.t_max[k] - std.t_min[k]) for k, n in enumerate(emu.t_names)]
    ref = dense_reference(cal, x, y, center, sd)
    for name, (mean, sd_k, quantiles) in zip(emu.t_names, ref, strict=True):
        assert np.max(np.abs(post.quantile(name, LEVELS) - quantiles)) < 0.03 * sd_k
        assert np.max(np.abs(post.grids[name].cdf(quantiles) - LEVELS)) < 0.005
        assert post.mean(name) == pytest.approx(mean, abs=1e-3 * sd_k)
        assert post.sd(name) == pytest.approx(sd_k, rel=5e-3)
    assert post.info["refined"]
    assert 0.0 < post.info["discarded_mass"] < 1e-4
    assert min(post.info["resolution"]) > 2.0  # refinement stopped short of 4 spacings, not of 2


def test_calib_a_posterior_the_grid_cannot_resolve_is_named():
    """Two peaks of a 1.5 node spacings per sd on a 257 x 257 grid (too many nodes to refine):
    its quantiles were summarised silently."""
    emu = symmetric_two_param_emulator()
    x = np.linspace(0.05, 0.95, 12)[:, None]
    y = (0.3 - 0.5) ** 2 * (1 + x) + 0.3 * 0.5 * x
    match = r"does not resolve the posterior of a: .*method='mcmc', a narrower domain.*\(now 257\)"
    with pytest.warns(UserWarning, match=match):
        post = Calibrator(emu, n_grid=257).update(x, y)
    assert post.info["resolution"][0] < 2.0 and not post.info["refined"]
    with warnings.catch_warnings():  # refined from the default grid: resolved, no warning
        warnings.simplefilter("error")
        post = Calibrator(emu).update(x, y)
    assert min(post.info["resolution"]) > 2.0


def test_a_resolved_posterior_needs_no_resolution_measure():
    """Where refinement resolves every mode (the usual case: 4 node spacings per sd or more)
    info["resolution"] is None and no warning is raised; nothing is discarded."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        post = Calibrator(road_emulator()).update(*road_obs())
    assert post.info["resolution"] is None and post.info["discarded_mass"] == 0.0
