"""One chain's split R-hat just above RHAT_MAX at a moderate ESS is within a converged chain's
noise ((R-hat - 1) x ESS up to RHAT_NOISE in ~1% of chains): such an element is still flagged,
and its reason and the warning say so; several chains, a low ESS or an R-hat beyond the noise
read as before."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import lfilter

from gpmsa.errors import ConvergenceWarning
from gpmsa.mcmc.diagnostics import RHAT_NOISE, convergence, summarize, warn_unconverged

NOISE = "within one converged chain's noise"


def _ar1(rng, phi: float, n: int) -> np.ndarray:
    e = rng.normal(size=n)
    e[0] /= np.sqrt(1 - phi**2)  # stationary from its first draw
    return lfilter([1.0], [1.0, -phi], e)


def _record(chains: np.ndarray) -> dict:
    """The record of one parameter "a" of one element; ``chains`` (n_chains, n_draws)."""
    summary = summarize({"a": chains[:, :, None]})
    return convergence(summary, {"a": (1,)}, chains.shape[0], chains.shape[1])


def _converged_with_rhat_above_the_limit(phi: float, n: int) -> dict:
    """The record of the first seeded stationary AR(1) chain whose R-hat exceeds 1.01."""
    for seed in range(200):
        rec = _record(_ar1(np.random.default_rng(seed), phi, n)[None, :])
        if rec["flagged"]:
            return rec
    raise AssertionError("no chain above the limit in 200 seeds")


def test_a_converged_chain_just_above_the_limit_is_flagged_within_its_noise():
    rec = _converged_with_rhat_above_the_limit(0.86, 4000)  # ESS ~300
    why = rec["flagged"]["a[0]"]
    r, e = rec["rhat"]["a"][0], rec["ess"]["a"][0]
    assert 1.01 < r <= 1 + RHAT_NOISE / e and e >= 100
    assert why.startswith("R-hat 1.0") and f"({NOISE} at ESS {e:.0f})" in why
    assert not rec["converged"]  # the verdict stands
    with pytest.warns(ConvergenceWarning) as caught:
        warn_unconverged(rec, "test", length="n_samples")
    text = str(caught[0].message)
    assert "Each R-hat flagged lies within the noise of one converged chain" in text
    assert "a longer chain (n_samples) tells them apart" in text


def test_a_drift_reads_within_the_noise_until_its_ess_falls_and_several_chains_as_before():
    rng = np.random.default_rng(3)
    chain = _ar1(rng, 0.86, 4000)  # sd ~2
    drift = _record((chain + np.linspace(0.0, 2.0, 4000))[None, :])  # ~1 sd over the chain
    r, e = drift["rhat"]["a"][0], drift["ess"]["a"][0]
    assert 1.01 < r <= 1 + RHAT_NOISE / e and NOISE in drift["flagged"]["a[0]"]  # as it says
    rec = _record((chain + np.linspace(0.0, 3.0, 4000))[None, :])  # ~1.5 sd: ESS collapses
    assert rec["ess"]["a"][0] < 100 and NOISE not in rec["flagged"]["a[0]"]
    short = _record(_ar1(rng, 0.97, 2000)[None, :])  # ESS below 100: flagged by ESS too
    assert short["ess"]["a"][0] < 100 and NOISE not in short["flagged"]["a[0]"]
    for seed in range(100):  # two chains: the note is for one chain's split R-hat only
        two = _record(np.stack([_ar1(np.random.default_rng([seed, k]), 0.86, 2000)
                                for k in range(2)]))  # fmt: skip
        if two["flagged"] and two["rhat"]["a"][0] > 1.01:
            break
    else:
        raise AssertionError("no two-chain record above the limit")
    assert NOISE not in two["flagged"]["a[0]"]
    with pytest.warns(ConvergenceWarning) as caught:
        warn_unconverged(rec, "test", length="n_samples")
    assert "within the noise" not in str(caught[0].message)
