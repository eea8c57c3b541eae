"""GDTracker: combining window likelihoods, forgetting after a change."""

import numpy as np
import pytest

from control import ControlError, GDTracker, TrackerSettings

GRID = np.linspace(200, 600, 401)


def gauss_loglik(center: float, sd: float) -> np.ndarray:
    return -0.5 * ((GRID - center) / sd) ** 2


def test_memoryless_tracker_returns_the_one_window_posterior():
    tr = GDTracker((200, 600), TrackerSettings(mean_segment_m=0.0))
    for center in (300.0, 480.0):
        tr.predict(5.0)
        tr.update(GRID, gauss_loglik(center, 20))
        post = tr.posterior()
        # Uniform prior on GD times a Gaussian likelihood far from the bounds: that Gaussian.
        assert post.mean("GD") == pytest.approx(center, abs=0.5)
        assert post.sd("GD") == pytest.approx(20, rel=0.02)


def test_consistent_windows_sharpen_the_posterior():
    tr = GDTracker((200, 600), TrackerSettings(mean_segment_m=1e9, drift_per_sqrt_m=0.0))
    for _ in range(9):
        tr.predict(10.0)
        tr.update(GRID, gauss_loglik(400, 30))
    assert tr.posterior().sd("GD") == pytest.approx(10, rel=0.05)  # 30 / sqrt(9)


def test_change_point_lets_the_estimate_follow_a_jump():
    tr = GDTracker((200, 600), TrackerSettings(mean_segment_m=25.0))
    for _ in range(6):
        tr.predict(12.0)
        tr.update(GRID, gauss_loglik(300, 40))
    assert tr.posterior().mean("GD") == pytest.approx(300, abs=15)
    means = []
    for _ in range(3):
        tr.predict(12.0)
        tr.update(GRID, gauss_loglik(500, 40))
        means.append(tr.posterior().mean("GD"))
    assert means[0] > 400  # one window at the new roughness moves it most of the way
    assert means[-1] == pytest.approx(500, abs=20)
    # Without change points (and no drift) the old evidence holds it back.
    rigid = GDTracker((200, 600), TrackerSettings(mean_segment_m=1e9, drift_per_sqrt_m=0.0))
    for center in [300] * 6 + [500]:
        rigid.predict(12.0)
        rigid.update(GRID, gauss_loglik(center, 40))
    assert rigid.posterior().mean("GD") < 340


def test_tempered_updates_add_up_to_one_full_update():
    """k updates at power 1/k give exactly the posterior of one update at power 1."""
    rigid = TrackerSettings(mean_segment_m=1e9, drift_per_sqrt_m=0.0)
    full, tempered = GDTracker((200, 600), rigid), GDTracker((200, 600), rigid)
    full.update(GRID, gauss_loglik(350, 25))
    for _ in range(8):
        tempered.update(GRID, gauss_loglik(350, 25), power=0.125)
    np.testing.assert_allclose(np.exp(tempered.log_mass), np.exp(full.log_mass), atol=1e-12)
    # a tempered update is wider than a full one: sd grows by sqrt(1 / power)
    weak = GDTracker((200, 600), rigid)
    weak.update(GRID, gauss_loglik(400, 20), power=0.25)
    assert weak.posterior().sd("GD") == pytest.approx(40, rel=0.02)
    with pytest.raises(ControlError, match=r"power must be a real number in \(0, 1\]"):
        weak.update(GRID, gauss_loglik(400, 20), power=0.0)


def test_log_uniform_prior_removes_the_upward_tilt():
    """A likelihood Gaussian in log GD: log-uniform prior -> posterior median at its centre."""
    log_grid = np.linspace(np.log(200), np.log(600), 2001)
    loglik = -0.5 * ((log_grid - np.log(300)) / 0.15) ** 2
    medians = {}
    for prior in ("uniform", "log_uniform"):
        tr = GDTracker((200, 600), TrackerSettings(prior=prior))
        assert np.exp(tr.log_prior).sum() == pytest.approx(1.0)
        tr.update(np.exp(log_grid), loglik)
        medians[prior] = tr.posterior().quantile("GD", 0.5)
    assert medians["log_uniform"] == pytest.approx(300, rel=0.01)
    # uniform in GD = density proportional to GD in log GD: the median moves up by ~sigma^2
    assert medians["uniform"] == pytest.approx(300 * np.exp(0.15**2), rel=0.01)
    with pytest.raises(ControlError, match="prior must be one of"):
        TrackerSettings(prior="jeffreys")


def test_prediction_keeps_the_mass():
    tr = GDTracker((200, 600))
    tr.update(GRID, gauss_loglik(590, 5))  # near the upper bound: reflection keeps the mass
    tr.predict(400.0)
    assert np.exp(tr.log_mass).sum() == pytest.approx(1.0, abs=1e-9)


def test_bad_input_raises():
    with pytest.raises(ControlError, match="domain must satisfy"):
        GDTracker((600, 200))
    with pytest.raises(ControlError, match="mean_segment_m"):
        TrackerSettings(mean_segment_m=-1)
    tr = GDTracker((200, 600))
    for ds in (-1.0, True, "1"):
        with pytest.raises(ControlError, match="ds_m must be a real number >= 0"):
            tr.predict(ds)
    for domain in (("200", "600"), (True, 600), (200, 400, 600), 200):
        with pytest.raises(ControlError, match="domain must be a pair"):
            GDTracker(domain)
    with pytest.raises(ControlError, match=r"n_grid must lie in \[16, 100000\]"):
        TrackerSettings(n_grid=10**9)
    far = GDTracker((200, 600))  # a huge step flattens the walk without a huge kernel
    far.update(GRID, gauss_loglik(350, 25))
    far.predict(1e12)
    assert np.exp(far.log_mass).sum() == pytest.approx(1.0, abs=1e-9)
    with pytest.raises(ControlError, match="loglik must be finite"):
        tr.update(GRID, np.full(GRID.size, np.nan))
    with pytest.raises(ControlError, match="TrackerSettings.n_grid must be an integer"):
        TrackerSettings(n_grid=400.5)
    with pytest.raises(ControlError, match="n_draws must be an integer >= 1"):
        tr.posterior(n_draws=-1)


@pytest.mark.parametrize("hi", [300.0 * (1 + 1e-14), np.nextafter(300.0, 400.0)])
def test_a_domain_too_narrow_for_the_grid_is_refused(hi):
    # its nodes rounded to equal values: a divide-by-zero warning, then a GPMSAError about a
    # grid marginal's nodes from posterior()
    with pytest.raises(ControlError, match=r"domain \(300.0, 300.*\) is too narrow for 400 "
                       "distinct grid nodes"):  # fmt: skip
        GDTracker((300.0, hi))
    assert GDTracker((300.0, 300.0 * (1 + 1e-9))).posterior().quantile("GD", 0.5) > 300.0


@pytest.mark.parametrize(
    "grid", [[600.0, 200.0, 400.0], [200.0, np.nan, 600.0], [-1.0, 200.0, 600.0]]
)
def test_a_grid_that_is_not_increasing_finite_and_positive_is_refused(grid):
    with pytest.raises(ControlError, match="grid must hold increasing, finite, positive"):
        GDTracker((200, 600)).update(grid, [-10.0, -10.0, 0.0])


def test_the_prior_density_holds_at_the_end_nodes():
    """Node masses are density x trapezoid weight: the end nodes hold half a cell, so the
    prior density is flat (uniform) or 1 / GD (log-uniform) to the domain's ends, and the
    random walk keeps a flat density flat."""
    for prior, expected in (
        ("uniform", lambda gd: np.ones_like(gd)),
        ("log_uniform", np.reciprocal),
    ):
        tr = GDTracker((200, 600), TrackerSettings(prior=prior, n_grid=64))
        density = tr.posterior().grids["GD"].density
        ratio = density / expected(tr.grid)
        np.testing.assert_allclose(ratio, ratio[1], rtol=1e-12)  # the ends as the inside
    flat = GDTracker((200, 600), TrackerSettings(prior="uniform", n_grid=64, mean_segment_m=1e9))
    flat.predict(100.0)  # drift 0.01 / sqrt(m): a walk of sd 0.1 in log GD
    density = flat.posterior().grids["GD"].density
    np.testing.assert_allclose(density, density[1], rtol=1e-9)
