"""Two of session 75's walkthrough suggestions: a continuation whose priors differ names the
fields and their values (it said only "its priors differ"), and a calibration option that needs
the fast sampler names what stands in the way as the user gave it (it listed fast=False for a
user who left fast unset on another backend)."""

import warnings

import numpy as np
import pytest

import gpmsa


@pytest.fixture(scope="module")
def case():
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(20, 1)), rng.uniform(size=(20, 1))
    sim = gpmsa.SimData(x=x, t=t, y=np.sin(3 * x + 2 * t))
    obs = gpmsa.ObsData(x=[[0.3], [0.6]], y=[[np.sin(1.9)], [np.sin(2.8)]])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = gpmsa.fit(sim, obs, n_iter=30, seed=1, priors=gpmsa.Priors(theta_sd=0.3))
    return sim, obs, emu


def test_a_continuation_with_other_priors_names_the_field_and_values(case):
    sim, obs, emu = case
    want = (
        r"its priors differ from this fit's \(priors: theta_sd: \[0\.3\] there, \[10\.0\] "
        r"here: give priors= as the source"
    )
    with pytest.raises(gpmsa.GPMSAError, match=want):
        gpmsa.fit(sim, obs, n_iter=30, seed=1, init=emu)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        again = gpmsa.fit(sim, obs, n_iter=30, seed=1, init=emu,
                          priors=gpmsa.Priors(theta_sd=0.3))  # fmt: skip
    assert again.log_post.size > 0 and np.all(np.isfinite(again.log_post))  # the same model


def test_the_fast_samplers_options_name_what_stands_in_the_way(case):
    pytest.importorskip("torch")
    _, _, emu = case
    with pytest.raises(gpmsa.GPMSAError, match=r"got backend='torch'$"):
        gpmsa.calibrate(emu, [[0.3]], [[0.9]], backend="torch", emulator_params="draws")
    with pytest.raises(gpmsa.GPMSAError, match=r"got fast=False$"):
        gpmsa.calibrate(emu, [[0.3]], [[0.9]], fast=False, emulator_params="draws")
