"""The change-point filter's jump law and hazard, pinned to the module docstring's formulas
(mutation testing found both free: a jump law of another shape, or a hazard of 0 for runs
beyond the gamma survival's underflow, passed every test)."""

import numpy as np
import pytest
from scipy.special import gammaincc

from control import ChangePointFilter, ChangePointSettings

GD = np.geomspace(200.0, 600.0, 121)


def at_node(j: int) -> np.ndarray:
    """A block's log-likelihood that puts all but ~1e-300 of the mass on node ``j``."""
    loglik = np.full(GD.size, -700.0)
    loglik[j] = 0.0
    return loglik


def test_the_new_run_holds_the_hazard_times_the_jump_law():
    """One block pins GD to a node; the next ds metres end that run with the gamma hazard
    h = 1 - S(d + ds) / S(d), and the ended mass goes to GD' with the jump law: the prior
    (1/GD' times its node weight) times exp(-0.5 (log(GD'/GD) / jump_sd)^2), zero for
    |log(GD'/GD)| < min_jump."""
    s = ChangePointSettings()  # mean 40 m, shape 2, min_jump 0.15, jump_sd 0.5, log-uniform
    f = ChangePointFilter(GD, s)
    j = 60
    f.update(at_node(j), 5.0)
    f.predict(5.0)
    mass, dist = f.state()[:2]
    theta = s.mean_segment_m / s.segment_shape
    hazard = 1.0 - gammaincc(2.0, 10.0 / theta) / gammaincc(2.0, 5.0 / theta)
    assert mass[0].sum() == pytest.approx(hazard, rel=1e-9)
    assert dist.tolist() == [5.0, 10.0]
    jump = np.log(GD / GD[j])
    w = np.gradient(GD)  # trapezoid weights up to the ends' halves
    w[0], w[-1] = (GD[1] - GD[0]) / 2, (GD[-1] - GD[-2]) / 2
    law = w / GD * np.exp(-0.5 * (jump / s.jump_sd) ** 2) * (np.abs(jump) >= s.min_jump)
    np.testing.assert_allclose(mass[0] / mass[0].sum(), law / law.sum(), rtol=1e-9, atol=1e-300)
    assert mass[0][np.abs(jump) < s.min_jump].sum() < 1e-250  # (only the ~1e-300 elsewhere)


def test_a_very_long_run_ends_at_the_hazards_limit():
    """For a run so long that its gamma survival S(d) underflows, the hazard is its limit
    1 - exp(-ds / theta) (theta = mean / shape), not 0: a long steady stretch can still end."""
    s = ChangePointSettings(mean_segment_m=2.0, segment_shape=2.0)
    f = ChangePointFilter(GD, s)
    f.update(at_node(60), 1.0)
    mass = np.zeros((1, GD.size))
    mass[0, 60] = 1.0
    f.restore((mass, np.array([1e5]), True))  # S(1e5 m) = 0 in float64
    f.predict(0.5)
    assert f.state()[0][0].sum() == pytest.approx(-np.expm1(-0.5 / 1.0), rel=1e-12)


def test_a_move_without_data_redraws_gd_from_the_prior_and_starts_a_run_here():
    """``relocate``: the mass whose run ended over the move goes to GD from the prior (not the
    jump law from the last GD) in a new run that starts here (distance 0); the rest keeps its
    GD and ages by the move."""
    f = ChangePointFilter(GD)
    f.update(at_node(60), 5.0)
    f.relocate(5.0)
    mass, dist = f.state()[:2]
    hazard = 1.0 - gammaincc(2.0, 10.0 / 20.0) / gammaincc(2.0, 5.0 / 20.0)
    assert mass[0].sum() == pytest.approx(hazard, rel=1e-9)
    np.testing.assert_allclose(mass[0] / mass[0].sum(), f.prior, rtol=1e-9)
    assert dist.tolist() == [0.0, 10.0]
    assert mass[1].argmax() == 60 and mass[1].sum() == pytest.approx(1.0 - hazard, rel=1e-9)


def test_a_standstill_leaves_the_state_as_it_is():
    """No distance is no hazard: ``predict(0)`` keeps every run's mass and distance."""
    f = ChangePointFilter(GD)
    f.update(at_node(60), 5.0)
    f.update(at_node(30), 5.0)
    before = f.state()
    f.predict(0.0)
    for got, want in zip(f.state(), before, strict=True):
        np.testing.assert_array_equal(got, want)


def test_merged_old_runs_keep_their_gd():
    """Past ``max_runs`` the oldest runs merge into the last row with their GD mass per node:
    on a long steady road the GD posterior keeps pooling every block (its sd shrinks with the
    blocks) and stays on the true GD."""
    s = ChangePointSettings(max_runs=10)
    f, short = ChangePointFilter(GD, s), ChangePointFilter(GD, ChangePointSettings(max_runs=400))
    for _ in range(200):
        for g in (f, short):
            g.update(-0.5 * ((np.log(GD) - np.log(300.0)) / 0.3) ** 2, 1.0)
    post, exact = f.posterior(), short.posterior()
    assert post.mean("GD") == pytest.approx(300.0, rel=0.01)
    assert post.sd("GD") == pytest.approx(exact.sd("GD"), rel=0.05)
    assert post.sd("GD") < 0.3 * ChangePointFilter(GD).posterior().sd("GD")


def test_a_blocks_loglik_counts_up_to_its_additive_constant():
    """A block's log-likelihood carries all its normalising constants (thousands below 0 for a
    long block) and may span far more than exp's range across the grid: only its shape counts."""
    sharp = -0.5 * ((np.log(GD) - np.log(300.0)) / 0.01) ** 2  # spans ~2,400 across the grid
    ref = ChangePointFilter(GD)
    ref.update(sharp, 5.0)
    for offset in (-5000.0, 0.0, 800.0):
        f = ChangePointFilter(GD)
        f.update(sharp + offset, 5.0)
        np.testing.assert_allclose(f.gd_mass, ref.gd_mass, rtol=1e-12, atol=1e-300)
    assert np.all(np.isfinite(ref.gd_mass)) and ref.gd_mass.sum() == pytest.approx(1.0)
    assert ref.posterior().mean("GD") == pytest.approx(300.0, rel=0.01)


def test_prob_change_within_takes_zero_metres():
    f = ChangePointFilter(GD)
    f.update(at_node(60), 5.0)
    assert f.prob_change_within(0.0) == 0.0  # the only run spans the block's 5 m
    assert f.prob_change_within(5.0) == pytest.approx(1.0)


def test_a_mixture_of_one_filter_is_its_posterior():
    from control.changepoint import mixture_posterior

    f = ChangePointFilter(GD)
    f.update(-0.5 * ((np.log(GD) - np.log(350.0)) / 0.3) ** 2, 5.0)
    one = mixture_posterior([f], [2.0])
    assert one.mean("GD") == pytest.approx(f.posterior().mean("GD"), rel=1e-12)


def test_a_prior_on_two_nodes_is_a_prior():
    """Two nodes with mass are enough for a change to have somewhere to go."""
    two = ChangePointFilter(GD, ChangePointSettings(prior=lambda g: np.where(
        (g == GD[10]) | (g == GD[100]), 0.0, -np.inf)))  # fmt: skip
    assert np.count_nonzero(two.prior) == 2 and two.prior.sum() == pytest.approx(1.0)


def test_runs_past_max_runs_merge_with_their_mass_and_mean_distance():
    """Memoryless law (constant hazard h): one step from R = max_runs rows gives a new run of
    mass h, the first R - 2 runs aged by ds with mass (1 - h) times theirs, and the last row the
    two oldest merged: (1 - h) times their summed mass, at their mass-weighted mean distance."""
    s = ChangePointSettings(mean_segment_m=40.0, segment_shape=1.0, max_runs=3)
    f = ChangePointFilter(GD, s)
    f.update(at_node(60), 1.0)
    rows = np.zeros((3, GD.size))
    rows[0, 50], rows[1, 60], rows[2, 70] = 0.5, 0.3, 0.2
    f.restore((rows, np.array([2.0, 10.0, 30.0]), True))
    f.predict(4.0)
    mass, dist = f.state()[:2]
    h = -np.expm1(-4.0 / 40.0)
    np.testing.assert_allclose(mass.sum(axis=1), [h, 0.5 * (1 - h), 0.5 * (1 - h)], rtol=1e-12)
    np.testing.assert_allclose(mass[2, [60, 70]], [0.3 * (1 - h), 0.2 * (1 - h)], rtol=1e-12)
    assert dist[:2].tolist() == [4.0, 6.0]
    assert dist[2] == pytest.approx((0.3 * 14.0 + 0.2 * 34.0) / 0.5, rel=1e-12)
