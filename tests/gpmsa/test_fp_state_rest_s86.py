"""gpmsa's public calls under a caller's ``np.seterr(all="raise")``, the rest (session 86):
``plots.rho_boxplots`` of a rough emulator (betaU 3000: rho = exp(-750) underflows), a
categorical posterior whose far level's probability is subnormal (its mean and sd, and
``LevelMarginal.from_probabilities``), and the width tuning's 1/e point of a nearly flat
acceptance raised FloatingPointError; they now give numpy's default state's numbers and leave
the caller's state as it was. ``Priors.log_beta`` at such a beta was NaN (log(0) * 0) and
``scalar_log_prior`` raised ValueError (math domain error) in the default state too."""

import warnings

import matplotlib
import numpy as np
import pytest

import gpmsa
from gpmsa.calibration.posterior import LevelMarginal
from gpmsa.mcmc.tuning import choose_widths

matplotlib.use("Agg")


def _same_under_raise(call):
    """``call()`` in the default state and under ``all="raise"``: the two results."""
    default = call()
    with np.errstate(all="raise"):
        raised = call()
        assert np.geterr()["under"] == "raise"  # the caller's state, after the call
    return default, raised


@pytest.fixture(scope="module")
def rough_draws():
    """A fitted emulator whose retained betaU draws are all 3000 (a rough input's)."""
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(12, 1)), rng.uniform(size=(12, 1))
    sim = gpmsa.SimData(x=x, t=t, y=np.sin(8 * x) + t)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.GPMSAWarning)
        emu = gpmsa.fit(sim, n_iter=10, seed=0, tune=False)
    manifest, arrays = emu.to_record()
    arrays = {k: np.full_like(v, 3000.0) if "betaU" in k else v for k, v in arrays.items()}
    return gpmsa.Emulator.from_record(manifest, arrays)


def test_rho_boxplots_of_a_rough_emulator_under_raise(rough_draws):
    import matplotlib.pyplot as plt

    def boxes():
        fig = gpmsa.plots.rho_boxplots(rough_draws)
        out = [line.get_ydata().tolist() for line in fig.axes[0].lines]
        plt.close(fig)
        return out

    default, raised = _same_under_raise(boxes)
    assert raised == default and set(default[0]) == {0.0}  # rho underflowed to 0


def test_a_subnormal_level_probability_under_raise():
    made = _same_under_raise(
        lambda: LevelMarginal.from_probabilities([0.0, 1.0, 3.0], [2.0, 1e-310, 1.0]).density
    )
    np.testing.assert_array_equal(*made)
    far = LevelMarginal.from_probabilities([0.0, 1.0, 3.0], [1.0, 1e-310, 0.0])
    post = gpmsa.Posterior({"kind": np.zeros(4)}, grids={"kind": far})
    default, raised = _same_under_raise(lambda: (post.mean("kind"), post.sd("kind"),
                                                 post.summary()["kind"]))  # fmt: skip
    assert raised == default and default[0] == pytest.approx(1e-310, rel=1e-3)


def test_the_tuned_width_of_a_nearly_flat_acceptance_under_raise():
    """Acceptance ~1 % at widths 0.01 ... 10: the fitted 1/e point is exp(-860), the narrowest."""
    candidates = np.array([[0.01], [0.1], [1.0], [10.0]])
    accepted = np.array([[4], [11], [10], [4]])
    default, raised = _same_under_raise(
        lambda: choose_widths(np.array([0.5]), candidates, accepted, 1000)
    )
    np.testing.assert_array_equal(raised, default)
    assert default.tolist() == [0.01]


@pytest.mark.parametrize(("rho_a", "want"), [(1.0, 0.0), (2.0, -750.0)])
def test_the_rho_prior_at_a_beta_whose_rho_underflows_to_zero(rho_a, want):
    """log rho = -beta/4 exactly; (rho_a - 1) log rho, the Beta(rho_a, 0.1) prior's."""
    priors = gpmsa.Priors(rho_a=rho_a)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # log(0) warned, then 0 * -inf (rho_a = 1) gave NaN
        default, raised = _same_under_raise(
            lambda: (
                priors.log_beta(np.full((2, 1), 3000.0)) / 2,
                priors.scalar_log_prior("betaU")(3000.0),
            )  # fmt: skip
        )
    assert raised == default == (want, want)
    # where rho is subnormal the value is that of before, log(rho) of the subnormal
    with np.errstate(all="raise"):
        assert np.isfinite(priors.log_beta(np.full((1, 1), 2900.0)))
