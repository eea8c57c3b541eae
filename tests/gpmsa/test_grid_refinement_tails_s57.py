"""Two-parameter grid refinement where heavy tails hold the grid beyond its node budget: the
marginal's tails (about 1e-7.5 of the peak over the whole domain, few observations) kept every
REFINE_FACTOR over MAX_REFINED, so refinement stopped on a posterior it had not resolved, and
said nothing."""

import warnings

import numpy as np
import pytest
from _calib_cases import two_param_emulator
from scipy.integrate import cumulative_trapezoid
from test_calib_grid_posterior import fine_peaks_posterior, peaks_data, symmetric_two_param_emulator
from test_constraint_two_params import broad_case, cut_posterior, peaks_case

from gpmsa import Calibrator
from gpmsa.calibration.grid import UNRESOLVED_SD, mesh
from gpmsa.calibration.observations import reduce
from gpmsa.calibration.posterior import trapezoid_weights

LEVELS = np.array([0.01, 0.05, 0.25, 0.5, 0.75, 0.95, 0.99])


def five_observations():
    """5 observations of `two_param_emulator` at a = 0.3, b = 0.6, noise sd 0.01."""
    x = np.linspace(0.05, 0.95, 5)[:, None]
    y = np.sin(2.0 * x + 1.5 * 0.3) + 0.8 * 0.6 * x
    return x, y + 0.01 * np.random.default_rng(1).standard_normal(x.shape)


def dense_reference(cal, x, y):
    """Per parameter (mean, sd, quantiles at LEVELS) of the exact posterior (the Calibrator's
    per-node likelihood, lamOs integrated) on a dense grid: the whole domain at 1/256 plus
    nodes 1/2000 apart over the region of the mass (a in [0.2, 0.42], b in [0.45, 0.78], unit
    scale; about 30 node spacings per sd)."""
    axes = [np.unique(np.concatenate([np.linspace(0, 1, 257), np.arange(lo, hi, 5e-4)]))
            for lo, hi in ((0.2, 0.42), (0.45, 0.78))]  # fmt: skip
    theta = mesh(axes)
    data = reduce(cal.emulator, x, y, False)
    logp = np.concatenate([cal._combine(cal._marginals(data, t)) + cal._theta_prior_at(t, None)
                           for t in np.array_split(theta, 8)])  # fmt: skip
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
        sd = np.sqrt(np.trapezoid((nodes - mean) ** 2 * marg, nodes))
        out.append((mean, sd, np.interp(LEVELS, cdf, nodes)))
    return out


@pytest.fixture(scope="module")
def five_dense():
    """`dense_reference` of `five_observations` (10 s): the per-node likelihood does not depend
    on the Calibrator's n_grid (the same to the bit at 65 and 129), so both grids share it."""
    return dense_reference(Calibrator(two_param_emulator()), *five_observations())


@pytest.mark.parametrize("n_grid", [65, 129])
def test_heavy_tailed_posterior_is_refined_over_its_core(n_grid, five_dense):
    """The default grid stopped with a at 0.91 node spacings per sd (quantiles 0.19 sd and the
    cdf 0.029 off the dense grid); n_grid=129 could not refine at all (0.105 sd, 0.019); neither
    warned. Now the core holding all but TAIL_MASS of each marginal is refined, the tails kept
    thinned: within 0.01 sd and 0.002 measured, and the moments no worse than 3e-4 sd."""
    emu = two_param_emulator()
    x, y = five_observations()
    cal = Calibrator(emu, n_grid=n_grid)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        post = cal.update(x, y)
    for name, (mean, sd, quantiles) in zip(emu.t_names, five_dense, strict=True):
        assert np.max(np.abs(post.quantile(name, LEVELS) - quantiles)) < 0.03 * sd
        assert np.max(np.abs(post.grids[name].cdf(quantiles) - LEVELS)) < 0.005
        assert post.mean(name) == pytest.approx(mean, abs=1e-3 * sd)
        assert post.sd(name) == pytest.approx(sd, rel=2e-3)
    assert post.info["refined"] and post.info["n_nodes"] <= 4 * 49**2
    assert min(post.info["resolution"]) > 3.5


def test_resolved_posteriors_raise_no_warning():
    """No warning, and the resolution reported, where the grid (refined or not) resolves the
    posterior: a broad one on the fixed grid, two constrained peaks refined to non-uniform axes
    (2.2 spacings per sd of a), and two peaks on a 257 x 257 grid (1.7 spacings per sd of each,
    quantiles within 0.004 sd of a dense grid, the cdf within 0.006)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        broad = Calibrator(two_param_emulator()).update(*broad_case()[1:3])
        constrained = cut_posterior(peaks_case())[0]
        fine = fine_peaks_posterior()  # shared with test_calib_grid_posterior (warning: error)
    assert min(broad.info["resolution"]) > 4.0 and not broad.info["refined"]
    assert constrained.info["refined"]
    assert UNRESOLVED_SD < constrained.info["resolution"][0] < 4.0
    assert UNRESOLVED_SD < fine.info["resolution"][0] < 4.0 and not fine.info["refined"]


def test_a_posterior_the_budget_cannot_resolve_is_named():
    """Two unconstrained peaks of a (near 0.3 and 0.7, sd 0.006) refined as far as MAX_REFINED
    allows: 0.81 node spacings per sd, the cdf of a 0.026 and the quantiles of b 0.12 sd off a
    dense grid. Their core spans both peaks, too many nodes to refine: a warning names a."""
    match = r"does not resolve the posterior of a: its width \(.*\) spans 0\.81 node .*\(now 65\)"
    with pytest.warns(UserWarning, match=match):
        post = Calibrator(symmetric_two_param_emulator()).update(*peaks_data())
    assert post.info["resolution"][0] < UNRESOLVED_SD
