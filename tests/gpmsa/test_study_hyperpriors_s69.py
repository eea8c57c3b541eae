"""Hierarchical groups at extreme hyperpriors (session 69 walkthrough of studies): a vague gamma
prior on the precision (BUGS's Gamma(0.01, 0.01)) lets lam wander below 1e-32, where the
truncated normal's mass P(0 < X < 1) rounded to 0 and log1p(-1) raised "math domain error"
inside the chain; a mu hyperprior whose log density overflows on (0, 1) crashed with an
OverflowError instead of being refused."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from _study_cases import emulator, observations
from scipy import stats

import gpmsa
from gpmsa.studies.sampler import log_mass01


@pytest.mark.parametrize("lam", [1e-300, 1e-40, 1e-32, 1e-20, 1e-8])
def test_truncated_normal_mass_of_a_tiny_precision(lam):
    for mu in (1e-9, 0.3, 0.5, 0.999):
        sd = 1 / math.sqrt(lam)
        want = stats.norm.logpdf(0.5, mu, sd) if lam < 1e-6 else math.log(
            stats.norm.cdf(1, mu, sd) - stats.norm.cdf(0, mu, sd))  # fmt: skip
        assert math.isclose(log_mass01(mu, lam), want, rel_tol=1e-9)


def test_vague_gamma_precision_prior_runs():
    rng = np.random.default_rng(0)
    obs = [observations(t, n, 0.05, rng) for t, n in ((0.1, 15), (0.5, 15), (0.9, 2))]
    hyper = gpmsa.HyperPriors(sd_prior="gamma", lam_a=0.01, lam_b=0.01)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        study = gpmsa.calibrate_study([emulator()] * 3, [o[0] for o in obs], [o[1] for o in obs],
                                      hierarchical=["t"], hyper=hyper, n_samples=3000,
                                      n_burn=200, seed=3)  # fmt: skip
    lam = study.posterior.samples["t.lam"]
    assert np.all(np.isfinite(lam)) and lam.min() > 0
    for i, t in enumerate((0.1, 0.5, 0.9)):
        assert abs(study.posterior.mean(f"t[model{i}]") - t) < 0.05


@pytest.mark.parametrize("kw", [{"mu_mean": 1e300}, {"mu_mean": -1e300, "mu_sd": 1.0},
                                {"mu_sd": 1e-200}])  # fmt: skip
def test_mu_prior_that_overflows_is_refused(kw):
    with pytest.raises(gpmsa.GPMSAError, match="HyperPriors.*mu_mean.*mu_sd"):
        gpmsa.HyperPriors(**kw)


def test_far_but_usable_mu_prior_is_kept():
    assert gpmsa.HyperPriors(mu_mean=-1e6).mu_mean == -1e6
    assert gpmsa.HyperPriors(mu_sd=1e-12).mu_sd == 1e-12
