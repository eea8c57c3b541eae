"""A categorical theta whose one chain holds one level is not flagged (session 76: the one-chain
check flagged every well-identified categorical calibration, "constant draws (no proposal
accepted)"); several chains at one level are, as before, and a continuous element's constant
draws always are."""

import warnings

import numpy as np

import gpmsa
from gpmsa.mcmc.diagnostics import convergence


def _summary(rhat, ess):
    return {"k": {"rhat": [rhat], "ess": [ess]}, "kind": {"rhat": [np.nan], "ess": [np.nan]}}


def test_one_chain_at_one_level_is_not_flagged():
    rec = convergence(_summary(1.0, 900.0), {"k": (), "kind": ()}, 1, 4000, levels={"kind"})
    assert rec["converged"] and rec["flagged"] == {}


def test_several_chains_at_one_level_and_constant_continuous_draws_are_flagged():
    rec = convergence(_summary(1.0, 900.0), {"k": (), "kind": ()}, 2, 4000, levels={"kind"})
    assert rec["flagged"] == {"kind": "constant draws (one level in every chain)"}
    rec = convergence(_summary(1.0, 900.0), {"k": (), "kind": ()}, 1, 4000)
    assert rec["flagged"] == {"kind": "constant draws (no proposal accepted)"}


def test_a_well_identified_level_calibrates_without_a_constant_draws_warning():
    rng = np.random.default_rng(0)
    m = 30
    x = rng.random((m, 1))
    t = np.column_stack([rng.random(m), np.arange(m) % 3])
    y = np.sin(3 * x[:, 0]) + t[:, 0] + 2.0 * t[:, 1]
    sim = gpmsa.SimData(x, t, y[:, None], t_names=["k", "kind"], t_categorical=["kind"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = gpmsa.fit(sim, n_iter=300, seed=0)
    xo = np.linspace(0.1, 0.9, 4)[:, None]
    yo = np.sin(3 * xo) + 0.4 + 2.0 + 0.02 * rng.standard_normal((4, 1))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        post = gpmsa.calibrate(emu, xo, yo, seed=1, n_samples=1500, n_burn=500)
    assert np.unique(post.samples["kind"]).size == 1  # the case: one level holds the posterior
    assert "kind" not in post.info["convergence"]["flagged"]
    assert not any("constant draws" in str(w.message) for w in caught)
