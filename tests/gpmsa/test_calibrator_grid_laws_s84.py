"""A Posterior's summaries of draws and of a grid at their edges (session 84, mutation
testing): equal draws summarise as their value (mean exactly it, sd exactly 0), two draws have
an sd, and the quantile/interval/tail probability of a grid marginal follow its CDF."""

from __future__ import annotations

import numpy as np
import pytest

from gpmsa.calibration.posterior import GridMarginal, Posterior


def test_equal_draws_have_their_value_as_mean_and_an_sd_of_exactly_zero():
    post = Posterior({"a": np.full(6, 0.1), "b": np.full(6, 0.7)})
    assert np.mean(np.full(6, 0.1)) < 0.1 < np.mean(np.full(6, 0.7)) - 0.6  # (rounding)
    assert post.mean("a") == 0.1 and post.mean("b") == 0.7
    assert post.sd("a") == 0.0 and isinstance(post.sd("a"), float)
    assert post.summary()["a"]["sd"] == 0.0
    assert post.summary()["a"]["held"] is False  # constant draws, but no parameter held


def test_two_draws_have_an_sd_and_one_has_none():
    post = Posterior({"a": np.array([1.0, 3.0])})
    assert post.sd("a") == pytest.approx(np.sqrt(2.0))
    one = Posterior({"a": np.array([1.0])})
    with pytest.raises(Exception, match="at least 2 draws"):
        one.sd("a")
    assert post.summary()["a"]["sd"] == pytest.approx(np.sqrt(2.0))
    assert np.isnan(one.summary()["a"]["sd"]) and one.summary()["a"]["mean"] == 1.0


def _triangle() -> Posterior:
    """A grid posterior with density 2x on [0, 1]: CDF x^2."""
    x = np.linspace(0.0, 1.0, 11)
    gm = GridMarginal.from_log_density(x, np.log(np.maximum(x, 1e-300)))
    return Posterior(draw=lambda: {"a": np.array([0.5, 0.5])}, grids={"a": gm},
                     info={"names": ("a",)})  # fmt: skip


def test_a_grid_posteriors_quantiles_interval_and_tail_follow_its_cdf():
    post = _triangle()
    q = np.array([0.04, 0.25, 0.81])
    np.testing.assert_allclose(post.quantile("a", q), np.sqrt(q), rtol=1e-12)
    assert post.quantile("a", 0.25) == pytest.approx(0.5)
    lo, hi = post.interval("a", 0.5)  # (0.25, 0.75) quantiles
    assert (lo, hi) == pytest.approx((np.sqrt(0.25), np.sqrt(0.75)))
    assert post.prob_above("a", 0.5) == pytest.approx(0.75)
    assert post.prob_above("a", 1.0) == pytest.approx(0.0, abs=1e-15)
    s = post.summary(0.5)["a"]
    assert (s["q25"], s["median"], s["q75"]) == pytest.approx((0.5, np.sqrt(0.5), np.sqrt(0.75)))
    assert post.sd("a") == pytest.approx(post.grids["a"].sd()) and post.sd("a") > 0.2
    assert s["exact_grid"] is True and s["mean"] == pytest.approx(2.0 / 3.0, rel=0.01)
