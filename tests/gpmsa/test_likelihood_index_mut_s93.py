"""Exact cases for the mutants of the GPM/SA log-likelihood and the index-point interpolation
that the older tests let live (the mutation testing of session 93, after session 88's): a mean
basis singular on the design (-inf, not an error, in the incremental form), a log posterior
that skips the likelihood where the prior is zero, the rounding slack's size and closed ends, a
-0.0 lower end, and which point an error names (the first repeat, the first outside point, a
spans ratio just over 1e6)."""

from __future__ import annotations

import numpy as np
import pytest

from gpmsa.model import index_points
from gpmsa.model.likelihood import IncrementalLikelihood
from gpmsa.model.mean_basis import MeanBasis
from gpmsa.model.problem import Problem
from tests.gpmsa.test_likelihood_mutation_s88 import dense_reference, make_problem


def _with_mean(prob: Problem, basis: MeanBasis) -> Problem:
    """``prob`` with another mean basis."""
    return Problem(prob.x_sim, prob.t_sim, prob.w, prob.lam_sim, prob.priors, prob.init,
                   frozenset(), prob.obs, categorical=prob.categorical,
                   mean_basis=basis)  # fmt: skip


@pytest.mark.parametrize("p_v", [0, 1])
def test_a_mean_basis_singular_on_the_design_gives_minus_infinity_incrementally(p_v):
    """H = [1, 0]: H^T Sigma^-1 H has a zero pivot, so the restricted likelihood is -inf, at
    the start and for a proposal (not an error); with H = [1] it is the dense normal's."""
    prob, prm = make_problem(4, p_v=p_v, p_u=1, mean="constant")
    zero_col = MeanBasis(
        "callable", 4, fn=lambda z: np.column_stack([np.ones(len(z)), 0 * z[:, 0]])
    )
    singular = _with_mean(prob, zero_col)
    lik = IncrementalLikelihood(singular, prm)
    assert lik.loglik == -np.inf
    assert lik.propose("lamUz", (0,), 2.0 * float(prm["lamUz"][0])) == -np.inf
    good = IncrementalLikelihood(prob, prm)
    assert good.loglik == pytest.approx(dense_reference(prob, prm), rel=1e-9)


def test_the_rounding_slack_is_one_billionth_of_the_span_with_its_ends_taken():
    """`HULL_TOL` is 1e-9 (a literal here: a doubled slack would take 1.5e-9), and a value at
    exactly lo - slack or hi + slack is within (closed ends)."""
    lo, hi = 2.0, 6.0
    assert index_points.within(np.array([lo - 0.9e-9 * 4.0, hi]), lo, hi)
    assert not index_points.within(np.array([lo - 1.5e-9 * 4.0, hi]), lo, hi)
    assert not index_points.within(np.array([lo, hi + 1.5e-9 * 4.0]), lo, hi)
    slack = 1e-9 * hi - 1e-9 * lo  # as `within` forms it
    assert index_points.within(np.array([lo - slack, hi + slack]), lo, hi)
    assert index_points.within(np.array([lo - slack, hi]), lo, hi)
    assert index_points.within(np.array([lo, hi + slack]), lo, hi)


def test_too_few_points_name_spans_just_over_a_million_times_apart():
    """The "too far apart" clause starts just past a ratio of 1e6 (1e6 + 0.5 here)."""
    pts = np.array([[0.0, 0.0], [1.0000005e6, 1.0]])
    with pytest.raises(index_points.GPMSAError, match="spans are too far apart for float64"):
        index_points.check_points(pts, "grid")
    with pytest.raises(index_points.GPMSAError, match=r"or all on a line or plane\)"):
        index_points.check_points(np.array([[0.0, 0.0], [1e6, 1.0]]), "grid")  # 1e6: not


def test_points_in_general_position_are_triangulated_in_their_own_units():
    """No frame (the points' own units) where Qhull takes them as they are."""
    pts = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [0.3, 0.6]])
    found = index_points._triangulation(pts, "q")
    assert found.frame is None
    np.testing.assert_array_equal(found.local(pts), pts)


def test_coincident_points_do_not_span_a_triangle():
    """Three copies of one point: a zero width in the frame too, so the same GPMSAError."""
    with pytest.raises(index_points.GPMSAError, match="does not span 2 dimensions"):
        index_points.triangles(np.full((3, 2), 0.25), "grid")


def test_log_posterior_skips_the_likelihood_where_the_prior_is_zero(monkeypatch):
    """A point the prior rules out (theta beyond [0, 1]) is -inf without a likelihood."""
    from gpmsa.model import likelihood

    prob, prm = make_problem(4, p_v=1, p_u=1)
    out = {**prm, "theta": np.array([1.5, 0.5])}
    assert likelihood.log_prior(prob, out) == -np.inf

    def no_call(*args):
        raise AssertionError("the likelihood was evaluated")

    monkeypatch.setattr(likelihood, "log_likelihood", no_call)
    assert likelihood.log_posterior(prob, out) == -np.inf
    with pytest.raises(AssertionError, match="evaluated"):
        likelihood.log_posterior(prob, prm)


def test_of_two_repeated_points_the_first_repeat_is_named():
    pts = np.array([[0.0, 0.0], [0.0, 0.0], [1.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    with pytest.raises(index_points.GPMSAError, match=r"\(0, 0\) twice \(rows 0 and 1\)"):
        index_points.check_points(pts, "grid")


def test_of_two_points_outside_the_hull_the_first_is_named():
    pts = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]])
    q = np.array([[0.5, 0.5], [2.0, 0.5], [3.0, 0.5]])
    with pytest.raises(index_points.GPMSAError, match=r"point \(2, 0.5\) \(row 1\) outside"):
        index_points.weights(pts, q, "q")


def test_a_minus_zero_lower_end_reached_by_rounding_is_exactly_that_point():
    """A column whose lowest value is -0.0 (the older case has -0.0 as the highest): a point
    below it by rounding is that simulation point, one-hot."""
    rng = np.random.default_rng(162)
    pts = rng.uniform(0, 3, (10, 2))
    pts[0] = [-0.0, rng.uniform(0.5, 2.5)]
    for q in ([-1e-13, pts[0, 1]], [0.0, pts[0, 1]], [-0.0, pts[0, 1]]):
        W = index_points.weights(pts, np.array([q]), "q")
        assert W.indices.tolist() == [0] and W.data.tolist() == [1.0], q
