"""Session 75's walkthrough as a MATLAB GPM/SA / SEPIA user: the defects it found."""

import numpy as np
import pytest

import gpmsa


@pytest.fixture(scope="module")
def walk():
    """A small sim + obs problem (x, two thetas, one output) and its emulator."""
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(20, 1)), rng.uniform(size=(20, 2))
    sim = gpmsa.SimData(x=x, t=t, y=x + t[:, :1] + 0.5 * t[:, 1:], t_names=["a", "b"])
    obs = gpmsa.ObsData(x=[[0.2], [0.5], [0.8]], y=[[0.65], [0.95], [1.25]])
    return sim, obs, gpmsa.fit(sim, n_iter=40, tune=False, seed=0)


def test_short_run_names_the_default_burn_in(walk):
    """n_samples=1000 (a SEPIA/GPM/SA user's do_mcmc(1000)) without n_burn: the refusal said
    "n_burn must be an integer in [0, n_samples - 1), got 1000", of an argument never passed."""
    sim, obs, emu = walk
    hint = r"got 1000 with n_samples=1000 \(n_burn defaults to 1000 burned sweeps"
    with pytest.raises(gpmsa.GPMSAError, match=hint):
        gpmsa.calibrate(emu, obs, n_samples=1000)
    with pytest.raises(gpmsa.GPMSAError, match=hint):
        gpmsa.calibrate_study([emu, emu], [obs, obs], shared=["a"], n_samples=1000)
    with pytest.raises(gpmsa.GPMSAError, match=r"got -1 with n_samples=1000$"):
        gpmsa.calibrate(emu, obs, n_samples=1000, n_burn=-1)


def test_posterior_read_back_without_discrepancy_names_it(walk):
    """A calibration with a discrepancy saved by ArviZ and read back (docs/calibration.md's
    recipe) keeps no info: full_prediction(posterior=) without discrepancy= said "the draws have
    discrepancy parameters but discrepancy=None gives 0 discrepancy basis vectors", of a None
    the user never passed."""
    sim, obs, emu = walk
    post = gpmsa.calibrate(emu, obs, discrepancy="constant", n_samples=30, n_burn=10, tune=False,
                           seed=0)  # fmt: skip
    back = gpmsa.Posterior(dict(post.samples))  # as from arviz.from_netcdf: no info
    with pytest.raises(gpmsa.GPMSAError, match="records no discrepancy basis .* pass the "
                       "calibration's discrepancy="):  # fmt: skip
        gpmsa.full_prediction(emu, obs, [[0.4]], posterior=back)
    given = gpmsa.full_prediction(emu, obs, [[0.4]], posterior=back, discrepancy="constant",
                                  seed=1)  # fmt: skip
    same = gpmsa.full_prediction(emu, obs, [[0.4]], posterior=post, seed=1)
    assert np.array_equal(given.mean("y"), same.mean("y"))
    hand = gpmsa.Posterior({k: v for k, v in post.samples.items() if k in ("a", "b", "lamOs")})
    assert gpmsa.full_prediction(emu, obs, [[0.4]], posterior=hand).delta.max() == 0.0
