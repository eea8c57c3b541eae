"""Mutation testing of control.tracker (s88): the prediction step against the module
docstring's law computed here (a reflected Gaussian walk of the density in log GD, sd
``drift_per_sqrt_m * sqrt(ds)``, then a change point with probability ``1 - exp(-ds / L)``),
the walk's cap at ten grids, the floor of a node's mass, an additive constant of the
likelihood however large, a domain holding GD = 1, the settings' defaults and the posterior's
draws, which the mutants changed unseen."""

import numpy as np
import pytest
from scipy.ndimage import gaussian_filter1d

from control import GDTracker, TrackerSettings
from gpmsa.calibration.posterior import trapezoid_weights

GRID = np.linspace(200.0, 600.0, 401)


def expected_prediction(tr: GDTracker, mass: np.ndarray, ds: float, sigma_idx: float):
    """Node masses after walking ``ds`` metres from ``mass``: the density (mass per trapezoid
    weight) blurred by a reflected Gaussian of ``sigma_idx`` nodes (none up to 0.05 node),
    truncated at 5 sd, back to masses, then mixed with the prior at the change-point hazard."""
    weights = trapezoid_weights(tr.grid)
    density = mass / weights
    if sigma_idx > 0.05:
        density = gaussian_filter1d(density, sigma_idx, mode="reflect", truncate=5.0)
    walked = density * weights
    walked /= walked.sum()
    hazard = 1.0 - np.exp(-ds / tr.settings.mean_segment_m)
    return (1.0 - hazard) * walked + hazard * np.exp(tr.log_prior)


def peaked(settings: TrackerSettings, center: float = 330.0) -> GDTracker:
    tr = GDTracker((200.0, 600.0), settings)
    tr.update(GRID, -0.5 * ((GRID - center) / 15.0) ** 2)
    return tr


def test_the_settings_defaults():
    s = TrackerSettings()
    assert (s.mean_segment_m, s.drift_per_sqrt_m, s.n_grid, s.prior) == (
        25.0,
        0.01,
        400,
        "uniform",
    )


@pytest.mark.parametrize("ds", [4.0, 0.25, 30.0, 0.03])
def test_the_walk_has_sd_drift_times_sqrt_ds_in_log_gd(ds):
    """n_grid 64 on [200, 600]: a node is ln(3) / 63 of log GD; drift 0.05 per sqrt(m) (at
    ds = 0.03 m the walk is half a node wide and still blurs, over 3 nodes)."""
    settings = TrackerSettings(mean_segment_m=40.0, drift_per_sqrt_m=0.05, n_grid=64)
    tr = peaked(settings)
    before = np.exp(tr.log_mass)
    tr.predict(ds)
    sigma_idx = 0.05 * np.sqrt(ds) / (np.log(3.0) / 63)  # 5.73 nodes at ds = 4 m
    expected = expected_prediction(tr, before, ds, sigma_idx)
    np.testing.assert_allclose(np.exp(tr.log_mass), expected, rtol=1e-9, atol=1e-300)


def test_the_default_walk_over_a_step_of_one_block():
    """The defaults (drift 0.01, 400 nodes, mean segment 25 m) over 2 m: 0.0141 of log GD,
    5.1 nodes of ln(3) / 399."""
    tr = peaked(TrackerSettings())
    before = np.exp(tr.log_mass)
    tr.predict(2.0)
    sigma_idx = 0.01 * np.sqrt(2.0) / (np.log(3.0) / 399)
    expected = expected_prediction(tr, before, 2.0, sigma_idx)
    np.testing.assert_allclose(np.exp(tr.log_mass), expected, rtol=1e-9, atol=1e-300)


def test_a_walk_wider_than_ten_grids_is_that_of_ten_grids():
    """16 nodes: the walk's sd is capped at 160 nodes; over 5.5e6 m it would be ~320."""
    settings = TrackerSettings(mean_segment_m=1e12, drift_per_sqrt_m=0.01, n_grid=16)
    tr = peaked(settings)
    before = np.exp(tr.log_mass)
    ds = 5.5e6
    assert 0.01 * np.sqrt(ds) / (np.log(3.0) / 15) > 300
    tr.predict(ds)
    expected = expected_prediction(tr, before, ds, 160.0)
    np.testing.assert_allclose(np.exp(tr.log_mass), expected, rtol=1e-12, atol=0)
    for other in (144.0, 176.0, 320.0):  # the cap is what this pins
        assert not np.allclose(
            expected, expected_prediction(tr, before, ds, other), rtol=1e-12, atol=0
        )


def test_a_node_whose_mass_underflows_keeps_a_mass_of_1e_300():
    """ds = 0: no walk and no change point; the nodes 13 sd and more from the peak hold
    exp(-85) x ... that underflows to 0 when the density is exponentiated: 1e-300."""
    tr = GDTracker((200.0, 600.0))
    tr.update(GRID, -0.5 * ((GRID - 400.0) / 1.0) ** 2)
    tr.predict(0.0)
    assert np.all(np.isfinite(tr.log_mass))
    assert tr.log_mass.min() == np.log(1e-300)
    assert np.exp(tr.log_mass).sum() == pytest.approx(1.0, rel=1e-12)


def test_an_additive_constant_of_the_likelihood_however_large_leaves_the_prior():
    """Flat at 1e17 but for the grid's first node: the posterior is the log-uniform prior on
    the nodes where the likelihood is flat (the constant would swamp the prior's log masses if
    it were not taken off first)."""
    tr = GDTracker((200.0, 600.0), TrackerSettings(prior="log_uniform", n_grid=64))
    loglik = np.full(GRID.size, 1e17)
    loglik[0] = 0.0
    tr.update(GRID, loglik)
    flat = tr.grid >= GRID[1]
    ratio = np.exp(tr.log_mass[flat] - tr.log_prior[flat])
    np.testing.assert_allclose(ratio, ratio[0], rtol=1e-12)
    assert np.exp(tr.log_mass[0]) == 0.0  # 1e17 below the rest


def test_a_uniform_prior_on_a_domain_holding_gd_1():
    """log(1) = 0 is a node of the log grid: the prior is still the trapezoid weights."""
    tr = GDTracker((1.0, 4.0), TrackerSettings(n_grid=16))
    assert tr.log_grid[0] == 0.0
    weights = trapezoid_weights(tr.grid)
    np.testing.assert_allclose(np.exp(tr.log_prior), weights / weights.sum(), rtol=1e-12)


def test_the_posterior_draws_4000_inverse_cdf_samples_seeded_0():
    tr = peaked(TrackerSettings(n_grid=64))
    post = tr.posterior()
    draws = post.samples["GD"]
    assert draws.shape == (4000,)
    expected = post.grids["GD"].sample(np.random.default_rng(0), 4000)
    np.testing.assert_array_equal(draws, expected)
    assert tr.posterior(n_draws=7).samples["GD"].shape == (7,)
