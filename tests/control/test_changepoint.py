"""The change-point filter on (run length, GD): mass, hazard, pooling, detection, state."""

import numpy as np
import pytest
from scipy.special import gammaincc

from control import ChangePointFilter, ChangePointSettings, ControlError
from gpmsa.calibration.posterior import trapezoid_weights

GD = np.geomspace(200.0, 600.0, 121)


def gauss_loglik(gd_true, sd_log=0.3):
    return -0.5 * ((np.log(GD) - np.log(gd_true)) / sd_log) ** 2


def test_the_prior_is_log_uniform_or_uniform():
    log_u = ChangePointFilter(GD).posterior()
    # log-uniform on [200, 600]: median at sqrt(200 * 600)
    assert log_u.quantile("GD", 0.5) == pytest.approx(np.sqrt(200 * 600), rel=0.01)
    uni = ChangePointFilter(GD, ChangePointSettings(prior="uniform")).posterior()
    assert uni.mean("GD") == pytest.approx(400.0, rel=0.01)


def test_a_prior_of_the_users_own():
    def log_prior(gd):  # a normal belief around 300, nothing above 450
        return np.where(gd <= 450, -0.5 * ((gd - 300) / 40) ** 2, -np.inf)

    post = ChangePointFilter(GD, ChangePointSettings(prior=log_prior)).posterior()
    assert post.mean("GD") == pytest.approx(300, abs=10) and post.prob_above("GD", 460) == 0
    with pytest.raises(ControlError, match="must return 121 log densities"):
        ChangePointFilter(GD, ChangePointSettings(prior=lambda gd: 0.0))
    with pytest.raises(ControlError, match="finite somewhere"):
        ChangePointFilter(GD, ChangePointSettings(prior=lambda gd: np.full(gd.size, -np.inf)))


def test_a_prior_on_one_node_is_named_as_such():
    for one in (lambda gd: np.where(gd > 599, 0.0, -np.inf), lambda gd: gd * 1e6):
        with pytest.raises(ControlError, match=r"puts all its mass on one grid node \(GD 600\)"):
            ChangePointFilter(GD, ChangePointSettings(prior=one))


def test_runs_longer_than_max_runs_keep_their_age():
    """The merged last row kept the distance of run R - 1, so on a long steady road the run
    length read as about R blocks (45 m for 1,000 m) and every change as recent."""
    f = ChangePointFilter(GD, ChangePointSettings(max_runs=50))
    for _ in range(1000):
        f.update(gauss_loglik(300.0), 1.0)
    assert f.expected_run_m() > 500.0  # 45.4 before
    assert f.prob_change_within(60.0) < 0.3  # 1.0 before
    assert f.mass_by_run([100.0])[1].sum() > 0.7  # 0 before
    short = ChangePointFilter(GD, ChangePointSettings(max_runs=50))
    for _ in range(40):  # under max_runs: nothing merged, the distances exact
        short.update(gauss_loglik(300.0), 1.0)
    assert short.state()[1].max() == 40.0


def test_a_refused_block_leaves_the_filter_as_it_was():
    f = ChangePointFilter(GD, ChangePointSettings(prior=lambda g: np.where(g <= 300, 0.0, -np.inf)))
    f.update(gauss_loglik(250.0), 1.0)
    before = f.state()
    far = np.where(GD <= 300, -2000.0, 0.0)  # finite, but none where the filter has mass
    with pytest.raises(ControlError, match="their product underflows on every grid node"):
        f.update(far, 1.0)
    after = f.state()
    assert all(np.array_equal(a, b) for a, b in zip(before[:2], after[:2], strict=True))
    with pytest.raises(ControlError, match="loglik must hold 121 finite values"):
        f.update(["0"] * GD.size, 1.0)  # numbers as text are not numbers
    for bad in (np.nan, True, "5", -1.0):
        with pytest.raises(ControlError, match="distance_m must be a distance >= 0"):
            f.prob_change_within(bad)


def test_steady_blocks_pool_and_the_mass_stays_normalised():
    f = ChangePointFilter(GD)
    sds = []
    for _ in range(60):
        f.update(gauss_loglik(300.0), 1.5)
        assert f.gd_mass.sum() == pytest.approx(1.0)
        sds.append(f.posterior().sd("GD"))
    assert sds[-1] < 0.4 * sds[0]  # the change hypotheses keep it wider than 1 / sqrt(n)
    assert f.posterior().mean("GD") == pytest.approx(300.0, rel=0.03)
    assert f.prob_change_within(5.0) < 0.15 and f.expected_run_m() > 40


def test_a_step_is_detected_and_the_old_blocks_forgotten():
    f = ChangePointFilter(GD)
    for _ in range(40):
        f.update(gauss_loglik(300.0), 1.5)
    means, changes = [], []
    for _ in range(10):
        f.update(gauss_loglik(500.0), 1.5)
        means.append(f.posterior().mean("GD"))
        changes.append(f.prob_change_within(10.0))
    assert means[-1] == pytest.approx(500.0, rel=0.05)
    assert max(changes[:4]) > 0.5
    assert np.argmax(np.array(means) > 400) <= 4  # within a few 1.5 m blocks


def test_the_hazard_of_a_gamma_segment_length():
    s = ChangePointSettings(mean_segment_m=40.0, segment_shape=1.0)
    f = ChangePointFilter(GD, s)
    f.update(gauss_loglik(300.0), 1.0)
    f.predict(10.0)  # memoryless: P(change within 10 m) = 1 - exp(-10 / 40)
    assert f.prob_change_within(10.0) == pytest.approx(1 - np.exp(-0.25), rel=1e-9)
    assert f.prob_change_within(9.99) == 0.0  # the new run spans the 10 m, as they came
    g = ChangePointFilter(GD, ChangePointSettings(mean_segment_m=40.0, segment_shape=2.0))
    g.update(gauss_loglik(300.0), 1.0)
    g.predict(10.0)  # shape 2: a new segment rarely ends in its first metres
    assert g.prob_change_within(10.0) < f.prob_change_within(10.0)


def test_a_new_run_spans_its_first_block_as_the_first_run_does():
    s = ChangePointSettings(mean_segment_m=40.0, segment_shape=2.0)
    f = ChangePointFilter(GD, s)
    f.update(gauss_loglik(300.0), 1.5)
    assert f.state()[1].tolist() == [1.5]  # the first block: its run spans 1.5 m
    state = f.state()
    f.predict(1.5)  # the hazard of a run 1.5 m long over the next 1.5 m: 1 - S(3.0) / S(1.5)
    survive = gammaincc(2.0, 3.0 / 20.0) / gammaincc(2.0, 1.5 / 20.0)
    assert f.prob_change_within(1.5) == pytest.approx(1.0 - survive, rel=1e-12)
    f.restore(state)
    f.update(gauss_loglik(300.0), 1.5)
    assert f.state()[1].tolist() == [1.5, 3.0]  # a run begun with the second block: 1.5 m too


def test_the_jump_law_excludes_small_changes():
    f = ChangePointFilter(GD, ChangePointSettings(min_jump=0.3, jump_sd=None))
    row = f._jump[np.argmin(np.abs(GD - 350.0))]
    near = np.abs(np.log(GD / 350.0)) < 0.3
    assert row[near].sum() == 0 and row.sum() == pytest.approx(1.0)


def test_state_and_restore_undo_a_block():
    f = ChangePointFilter(GD)
    f.update(gauss_loglik(300.0), 1.0)
    saved = f.state()
    before = f.gd_mass.copy()
    f.update(gauss_loglik(550.0), 1.0)
    f.restore(saved)
    np.testing.assert_array_equal(f.gd_mass, before)


def test_the_mass_by_run_length_sums_to_the_posterior_and_moves_after_a_step():
    f = ChangePointFilter(GD)
    with pytest.raises(ControlError, match="no block has been used yet"):
        f.mass_by_run([5.0])
    for _ in range(40):
        f.update(gauss_loglik(300.0), 1.5)
    parts = f.mass_by_run([5.0, 15.0])
    assert parts.shape == (3, GD.size)
    np.testing.assert_allclose(parts.sum(axis=0), f.gd_mass, rtol=1e-12)
    assert parts[0].sum() == pytest.approx(f.prob_change_within(5.0))
    assert parts[2].sum() > 0.5  # steady ground: most mass on the long run
    # the short runs hold the hedge that the roughness just changed: away from the truth
    short_mean = parts[0] @ GD / parts[0].sum()
    long_mean = parts[2] @ GD / parts[2].sum()
    assert abs(short_mean - 300) > abs(long_mean - 300)
    for _ in range(4):
        f.update(gauss_loglik(500.0), 1.5)
    after = f.mass_by_run([5.0, 15.0])
    assert after[0].sum() + after[1].sum() > 0.5  # a step: the mass moves to recent runs
    for bad in ([], [0.0, 5.0], [15.0, 5.0], [5.0, np.inf], "5", [[5.0]]):
        with pytest.raises(ControlError, match="edges_m must be"):
            f.mass_by_run(bad)


def test_bad_settings_and_inputs():
    with pytest.raises(ControlError, match="mean_segment_m must be finite and > 0"):
        ChangePointSettings(mean_segment_m=0.0)
    with pytest.raises(ControlError, match="prior must be one of"):
        ChangePointSettings(prior="jeffreys")
    with pytest.raises(ControlError, match="leaves no GD to jump to"):
        ChangePointFilter(GD, ChangePointSettings(min_jump=5.0))
    f = ChangePointFilter(GD)
    with pytest.raises(ControlError, match="loglik must hold 121 finite values"):
        f.update(np.full(121, np.nan), 1.0)
    with pytest.raises(ControlError, match="ds_m must be finite and >= 0"):
        f.predict(-1.0)
    with pytest.raises(ControlError, match="increasing 1-D grid"):
        ChangePointFilter(np.array([3.0, 2.0, 1.0]))
    for grid in ([1.0, np.nan, 3.0], [100.0, 200.0, 300.0, np.inf]):
        with pytest.raises(ControlError, match="positive, finite values"):
            ChangePointFilter(np.array(grid))
    with pytest.raises(ControlError, match="ChangePointSettings.mean_segment_m must be a real"):
        ChangePointSettings(mean_segment_m="40")
    with pytest.raises(ControlError, match="ChangePointSettings.max_runs must be an integer"):
        ChangePointSettings(max_runs=300.0)
    with pytest.raises(ControlError, match="n_draws must be an integer >= 1"):
        f.posterior(n_draws=0)


def test_a_mixture_of_filters_needs_one_grid_and_positive_weights():
    from control.changepoint import mixture_posterior

    gd = np.geomspace(200, 600, 41)
    a, b = ChangePointFilter(gd), ChangePointFilter(gd)
    a.update(-0.5 * ((np.log(gd) - np.log(300)) / 0.1) ** 2, 0.0)
    b.update(-0.5 * ((np.log(gd) - np.log(500)) / 0.1) ** 2, 0.0)
    mix = mixture_posterior([a, b], [2.0, 1.0]).grids["GD"]
    expected = (2 * a.gd_mass + b.gd_mass) / 3
    np.testing.assert_allclose(mix.density * trapezoid_weights(gd), expected, rtol=1e-9)
    for weights in ([1.0], [1.0, 0.0], [1.0, np.nan]):
        with pytest.raises(ControlError, match="one finite positive weight per filter"):
            mixture_posterior([a, b], weights)
    with pytest.raises(ControlError, match="one GD grid"):
        mixture_posterior([a, ChangePointFilter(np.geomspace(200, 600, 21))], [1.0, 1.0])


def test_a_state_is_a_snapshot_and_the_summaries_follow_every_step():
    """`state` shares the filter's arrays (read-only: each step makes new ones), so a state
    taken stays as it was; `gd_mass` is the caller's own copy, and the summaries computed once
    a step (`gd_mass`, `prob_change_within`) follow each step, restore and reset."""
    f = ChangePointFilter(np.geomspace(200.0, 600.0, 61))
    loglik = lambda gd: -0.5 * ((np.log(f.gd) - np.log(gd)) / 0.3) ** 2  # noqa: E731
    f.update(loglik(300.0), 1.0)
    taken = f.state()
    mass, dist = taken[0].copy(), taken[1].copy()
    with pytest.raises(ValueError, match="read-only"):
        taken[0][0, 0] = 1.0
    mine = f.gd_mass
    mine[:] = 0.0  # the caller's copy: the filter keeps its own
    before = (f.gd_mass.copy(), f.prob_change_within(5.0))
    assert before[0].sum() == pytest.approx(1.0)
    for _ in range(5):
        f.update(loglik(550.0), 1.0)
    np.testing.assert_array_equal(taken[0], mass)  # later steps left the state alone
    np.testing.assert_array_equal(taken[1], dist)
    assert not np.array_equal(f.gd_mass, before[0])
    assert f.prob_change_within(5.0) != before[1]
    f.restore(taken)
    np.testing.assert_array_equal(f.gd_mass, before[0])
    assert f.prob_change_within(5.0) == before[1]
    f.reset()
    np.testing.assert_allclose(f.gd_mass, f.prior)
    assert np.isnan(f.prob_change_within(5.0))
