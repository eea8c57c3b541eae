"""The estimator's building blocks against brute force: the change-point filter against an
enumeration of every change-point configuration, its pooled posterior against the product of
the block likelihoods and a quadrature, the band feature of a sinusoid, the learned scatter of
data of known covariance; and the inputs they must refuse by name."""

import itertools

import numpy as np
import pytest
from scipy import integrate
from scipy.special import gammaincc

from control import ChangePointFilter, ChangePointSettings, ControlError, GDTracker
from control.changepoint import mixture_posterior
from control.feature import FeatureSpec, block_features, feature_of_variance
from control.training import block_scatter, feature_statistics

GD = np.geomspace(200.0, 600.0, 9)


def _enumerated(f: ChangePointFilter, logliks, ds) -> dict[float, np.ndarray]:
    """P(run length, GD | blocks) by summing over all 2^(n-1) change-point configurations: a
    run's distance counts all of its blocks (a change falls at a block's start, for the first
    run as for the others), the hazard is the gamma law's, GD follows the prior and then the
    filter's jump law."""
    s, n = f.settings, len(ds)
    theta = s.mean_segment_m / s.segment_shape
    survival = lambda d: gammaincc(s.segment_shape, d / theta)  # noqa: E731
    out: dict[float, np.ndarray] = {}
    for config in itertools.product((0, 1), repeat=n - 1):
        starts = [0] + [k for k in range(1, n) if config[k - 1]]
        p = 1.0
        for j in range(1, n):
            start = max(k for k in starts if k <= j - 1)
            d = ds[start:j].sum()
            h = 1.0 - survival(d + ds[j]) / survival(d)
            p *= h if config[j - 1] else 1.0 - h
        ends = starts[1:] + [n]
        alpha = f.prior * np.exp(sum(logliks[starts[0] : ends[0]]))
        for a, b in zip(starts[1:], ends[1:], strict=True):
            alpha = (alpha @ f._jump) * np.exp(sum(logliks[a:b]))
        last = starts[-1]
        key = round(float(ds[last:].sum()), 9)
        out[key] = out.get(key, 0.0) + p * alpha
    return out


@pytest.mark.parametrize(
    "settings",
    [
        ChangePointSettings(),
        ChangePointSettings(segment_shape=1.0),
        ChangePointSettings(mean_segment_m=5.0, min_jump=0.0, jump_sd=None),
        ChangePointSettings(mean_segment_m=3.0, segment_shape=3.0, prior="uniform"),
    ],
)
def test_the_filter_is_the_exact_sum_over_change_point_configurations(settings):
    rng = np.random.default_rng(1)
    n = 7
    ds = rng.uniform(0.5, 3.0, n)
    logliks = [-0.5 * ((np.log(GD) - np.log(rng.uniform(200, 600))) / 0.3) ** 2 for _ in ds]
    f = ChangePointFilter(GD, settings)
    for loglik, step in zip(logliks, ds, strict=True):
        f.update(loglik, step)
    exact = _enumerated(f, logliks, ds)
    total = sum(m.sum() for m in exact.values())
    mass, dist, _ = f.state()
    assert len(exact) == dist.size == n
    for row, d in zip(mass, dist, strict=True):
        np.testing.assert_allclose(row, exact[round(float(d), 9)] / total, rtol=0, atol=1e-14)


def test_a_steady_road_pools_every_block_and_its_summaries_are_the_integrals():
    gd = np.geomspace(200.0, 600.0, 121)
    centres = np.random.default_rng(0).normal(np.log(330.0), 0.3, 10)
    f = ChangePointFilter(gd, ChangePointSettings(mean_segment_m=1e12))  # no change, ever
    for c in centres:
        f.update(-0.5 * ((np.log(gd) - c) / 0.3) ** 2, 1.5)
    product = f.prior * np.exp(-0.5 * (((np.log(gd)[:, None] - centres) / 0.3) ** 2).sum(1))
    np.testing.assert_allclose(f.gd_mass, product / product.sum(), rtol=0, atol=1e-15)

    def density(g):  # log-uniform prior times the blocks' likelihoods, unnormalised
        return np.exp(-0.5 * np.sum(((np.log(g) - centres) / 0.3) ** 2) + 20.0) / g

    z = integrate.quad(density, 200, 600, limit=200)[0]
    mean = integrate.quad(lambda g: g * density(g), 200, 600, limit=200)[0] / z
    sd = np.sqrt(integrate.quad(lambda g: (g - mean) ** 2 * density(g), 200, 600)[0] / z)
    post = f.posterior()
    assert post.mean("GD") == pytest.approx(mean, rel=1e-6)
    assert post.sd("GD") == pytest.approx(sd, rel=1e-5)
    assert post.prob_above("GD", 350.0) == pytest.approx(
        integrate.quad(density, 350, 600)[0] / z, abs=1e-3
    )
    lo, hi = post.interval("GD", 0.9)
    assert integrate.quad(density, 200, lo)[0] / z == pytest.approx(0.05, abs=1e-3)
    assert integrate.quad(density, hi, 600)[0] / z == pytest.approx(0.05, abs=1e-3)


@pytest.mark.parametrize("f0, band", [(3.0, 0), (8.5, 2), (12.0, 3), (25.0, 5), (37.5, 6)])
def test_a_sinusoids_power_lands_in_its_band(f0, band):
    spec = FeatureSpec()
    t = np.arange(spec.block_samples) / spec.rate_hz
    power = np.exp(block_features(2.0 * np.sin(2 * np.pi * f0 * t + 0.3), spec)[0, :8])
    assert power.sum() == pytest.approx(2.0, rel=0.01)  # A^2 / 2
    assert power[band] / power.sum() > 0.9


def test_the_full_band_power_is_the_tapered_energy_parseval():
    from scipy.signal.windows import dpss

    for n, rate in ((125, 120.0), (128, 128.0)):  # odd and even blocks: no Nyquist bin, one
        spec = FeatureSpec(block_samples=n, rate_hz=rate, bands_hz=(0.0, rate / 2), quantiles=())
        x = np.random.default_rng(n).normal(size=(5, n))
        x -= x.mean(axis=1, keepdims=True)
        energy = ((x[:, None, :] * dpss(n, 2.0, 3)[None]) ** 2).sum(axis=2).mean(axis=1)
        np.testing.assert_allclose(np.exp(block_features(x, spec)[:, 0]), energy, rtol=1e-12)


def test_the_learned_scatter_of_independent_blocks_is_their_covariance():
    rng = np.random.default_rng(0)
    cov = np.array([[1.0, 0.4, -0.2], [0.4, 2.0, 0.3], [-0.2, 0.3, 0.5]])
    feats = rng.normal(size=(60, 800, 3)) @ np.linalg.cholesky(cov).T
    feats += rng.normal(size=(60, 1, 3)) * 5.0  # each run its own mean
    scatter = block_scatter(np.repeat(np.linspace(0.5, 2.0, 6), 10), feature_statistics(feats))
    pooled = scatter.cov.mean(axis=0)
    np.testing.assert_allclose(pooled, cov, atol=0.05 * np.abs(cov).max())
    assert scatter.dof > 100  # Gaussian blocks: a Student t of (nearly) no heavier tails


def test_a_likelihood_on_a_narrower_grid_than_the_trackers_domain_is_refused():
    """np.interp held the grid's end values beyond it: a likelihood given on [300, 500] was
    read as flat over [500, 600], and P(GD > 520) came out 1.2e-5 instead of 1.3e-12 (7 sd)."""
    tracker = GDTracker((200.0, 600.0))
    grid = np.geomspace(300.0, 500.0, 50)
    with pytest.raises(ControlError, match=r"grid spans GD \[300, 500\] but the tracker's domain"):
        tracker.update(grid, -0.5 * ((grid - 450.0) / 10.0) ** 2)
    full = np.linspace(200.0, 600.0, 129)  # the Calibrator's grid: its ends to rounding
    tracker.update(full * (1 + 1e-13), -0.5 * ((full - 450.0) / 10.0) ** 2)
    assert tracker.posterior().prob_above("GD", 520.0) < 1e-11


def test_block_scatter_names_its_nodes_and_a_campaign_at_one_speed():
    stats = feature_statistics(np.random.default_rng(0).normal(size=(4, 32, 2)))
    speed = np.array([1.0, 1.0, 2.0, 2.0])
    for nodes in ([1.0], [2.0, 1.0]):  # were reported as "speed must be >= 2 increasing"
        with pytest.raises(ControlError, match="nodes must be >= 2 increasing finite speeds"):
            block_scatter(speed, stats, nodes=nodes)
    with pytest.raises(ControlError, match="every run drove at 1 m/s.*give nodes"):
        block_scatter(np.ones(4), stats)
    assert block_scatter(np.ones(4), stats, nodes=[0.9, 1.1]).cov.shape == (2, 2, 2)
    with pytest.raises(ControlError, match="stats_ must be a control.BlockStatistics"):
        block_scatter(speed, "stats")


def test_mixtures_and_variances_name_what_they_cannot_take():
    f = ChangePointFilter(GD)
    with pytest.raises(ControlError, match="filters must be a list of ChangePointFilters"):
        mixture_posterior(np.array([f, f]), [1.0, 1.0])  # was numpy's "truth value" error
    with pytest.raises(ControlError, match=r"filters\[1\] must be a control.ChangePointFilter"):
        mixture_posterior([f, "x"], [1.0, 1.0])
    for bad in (None, "x"):  # None was NaN, a "log f" of no variance
        with pytest.raises(ControlError, match="f must be an array of real numbers"):
            feature_of_variance(bad)
    assert feature_of_variance(np.e**2) == pytest.approx(2.0)
