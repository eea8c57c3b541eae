"""``gpmsa.calibrate`` has no private keyword: it is ``sample_calibration`` (the run) judged
(convergence and the domain's bounds, ``calibration.judge``), and a Calibrator's MCMC update runs
``sample_calibration`` and judges several chains' convergence only. Before, calibrate's public
signature held ``_online=False`` for the Calibrator alone (shown by ``help``, accepted from
users). The draws, records and warnings of both are those of the code before the split: the
references below were computed on it."""

from __future__ import annotations

import hashlib
import inspect
import json
import re
import warnings
from functools import cache

import numpy as np
import pytest

import gpmsa

GRID = np.linspace(0.0, 1.0, 12)
X_OBS = np.array([[0.3], [0.7]])
SHORT = {"n_samples": 300, "n_burn": 50, "tune_rounds": 5, "tune_levels": 5}
HEX = re.compile(r"[0-9a-f]{64}")


def simulator(x: np.ndarray, t: np.ndarray) -> np.ndarray:
    """A 12-value output (n, 12) at x (n,) and t (n, 2)."""
    return (1.0 + t[:, :1]) * np.sin(np.pi * GRID * (0.5 + x[:, None])) + 0.3 * t[:, 1:2]


@cache
def emulator(q: int = 2) -> gpmsa.Emulator:
    """An emulator at given parameters (no fit) of 30 runs, a and b in [0.1, 1] (q = 1: a)."""
    rng = np.random.default_rng(1)
    x, t = rng.uniform(0, 1, 30), rng.uniform(0.1, 1.0, (30, 2))
    y = simulator(x, t)
    if q == 1:
        t, y = t[:, :1], (1.0 + t[:, :1]) * np.sin(np.pi * GRID * (0.5 + x[:, None]))
    sim = gpmsa.SimData(x=x[:, None], t=t, y=y, index=GRID, x_names=["x"],
                        t_names=["a", "b"][:q])  # fmt: skip
    params = {"betaU": np.full((1 + q, 2), 2.0), "lamUz": np.ones(2), "lamWs": np.full(2, 3000.0),
              "lamWOs": [3000.0]}  # fmt: skip
    return gpmsa.Emulator.from_params(sim, params, n_pc=2)


def observed(a: float, b: float = 0.5) -> np.ndarray:
    """Observations (2, 12) at X_OBS of the truth (a, b); a = 1.3 lies past a's upper bound."""
    noise = np.random.default_rng(0).standard_normal((2, GRID.size))
    return simulator(X_OBS[:, 0], np.array([[a, b], [a, b]])) + 0.02 * noise


def fingerprint(post: gpmsa.Posterior, caught: list) -> tuple[str, float, float, float]:
    """BLAS-independent: a digest of the record's structure and exact leaves (keys, in order;
    strings (sha256 digests as one token), integers, flags; floats as their kind), the warnings'
    categories, and three sums compared at rtol 1e-10: of the record's finite float leaves'
    magnitudes, of the draws, and of the draws weighted by their position."""
    floats: list[float] = []

    def shape(v):
        if isinstance(v, dict):
            return [[str(k), shape(x)] for k, x in v.items()]
        if isinstance(v, list | tuple | np.ndarray):
            return [shape(x) for x in (v.tolist() if isinstance(v, np.ndarray) else v)]
        if isinstance(v, np.generic):
            v = v.item()
        if isinstance(v, float):
            if np.isfinite(v):
                floats.append(abs(v))
            return "float" if np.isfinite(v) else repr(v)
        return "sha256" if isinstance(v, str) and HEX.fullmatch(v) else v

    record = {k: v for k, v in post.info.items() if k not in ("seconds", "versions")}  # (host's)
    kinds = [w.category.__name__ for w in caught]
    text = json.dumps([shape(record), kinds])
    draws = np.stack(list(post.samples.values()))
    weights = np.linspace(1.0, 2.0, draws.shape[1])
    return (hashlib.sha256(text.encode()).hexdigest()[:16], float(np.sum(floats)),
            float(draws.sum()), float((draws * weights).sum()))  # fmt: skip


def run(case: str) -> tuple[gpmsa.Posterior, list]:
    """One seeded calibration or Calibrator update (its second) with every warning caught."""
    y, yb = observed(0.5), observed(1.3)
    calls = {
        "calibrate_at_bound": lambda: gpmsa.calibrate(emulator(), X_OBS, yb, seed=1, **SHORT),
        "calibrate_backend_2_chains": lambda: gpmsa.calibrate(
            emulator(1), X_OBS, y, seed=4, fast=False, n_chains=2, n_jobs=1, **SHORT),
        "update_1_chain_at_bound": lambda: update({}, yb),
        "update_2_chains_at_bound": lambda: update({"n_chains": 2, "n_jobs": 1}, yb, seed=12),
        "update_prior": lambda: update({}, y, prior=lambda t: -np.sum(np.atleast_2d(t) ** 2, 1)),
    }  # fmt: skip
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        post = calls[case]()
    return post, caught


def update(opts: dict, y: np.ndarray, **kw) -> gpmsa.Posterior:
    cal = gpmsa.Calibrator(emulator(), method="mcmc", seed=9, mcmc_options={**SHORT, **opts})
    cal.update(X_OBS, y)
    return cal.update(X_OBS, y, **kw)


REFERENCE = {
    "calibrate_at_bound": ("3eb4a82ae4baed1f", 252.082500148, 2953.60064321, 4429.65016112),
    "calibrate_backend_2_chains": ("c8e151d6458c1c65", 864.666201555, 30996.3686985, 46339.8216955),
    "update_1_chain_at_bound": ("26190e8906ee2ff9", 55.1066991849, 3530.18226427, 5282.96230728),
    "update_2_chains_at_bound": ("6727a95988b95054", 272.183900168, 7150.96892027, 10730.3557156),
    "update_prior": ("d0ac5d83e4e10b88", 458.009230656, 27408.5598594, 41148.2516521),
}
"""Each case's fingerprint, computed on the code before the split (``_online``)."""


@pytest.mark.parametrize("case", sorted(REFERENCE))
def test_draws_records_and_warnings_are_as_before(case):
    digest, record, total, weighted = fingerprint(*run(case))
    ref = REFERENCE[case]
    assert digest == ref[0]
    np.testing.assert_allclose([record, total, weighted], ref[1:], rtol=1e-10)


def test_calibrate_judges_and_a_calibrator_update_judges_several_chains_only():
    post, caught = run("calibrate_at_bound")
    assert {"diagnostics", "convergence", "at_bound"} <= set(post.info)
    assert post.info["at_bound"] == {"a": "upper"}
    kinds = {w.category for w in caught}
    assert {gpmsa.AtBoundWarning, gpmsa.ConvergenceWarning, gpmsa.OutsideEmulatorWarning} <= kinds
    assert all(w.filename == __file__ for w in caught)  # the user's call, not gpmsa's
    one, caught = run("update_1_chain_at_bound")
    assert not {"diagnostics", "convergence", "at_bound"} & set(one.info)
    assert not [w for w in caught if issubclass(w.category, gpmsa.ConvergenceWarning)]
    two, caught = run("update_2_chains_at_bound")
    assert {"diagnostics", "convergence"} <= set(two.info) and "at_bound" not in two.info
    said = [str(w.message) for w in caught if issubclass(w.category, gpmsa.ConvergenceWarning)]
    assert said and all("init=the returned posterior" not in s for s in said)  # no continuation
    assert all(w.filename == __file__ for w in caught)  # the user's update, not the Calibrator's
    assert not [w for w in caught if issubclass(w.category, gpmsa.AtBoundWarning)]


def test_calibrate_has_no_private_keyword_and_refuses_online():
    params = inspect.signature(gpmsa.calibrate).parameters
    assert not [name for name in params if name.startswith("_")]
    assert "_online" not in inspect.getdoc(gpmsa.calibrate)
    with pytest.raises(gpmsa.GPMSAError, match=r"calibrate: unknown option\(s\) \['_online'\]"):
        gpmsa.calibrate(emulator(), X_OBS, observed(0.5), seed=0, _online=True, **SHORT)


def test_the_run_takes_calibrates_arguments():
    """The Calibrator passes calibrate's keywords (mcmc_options) to the run: one signature."""
    from gpmsa.calibration.calibrate import sample_calibration

    ours = inspect.signature(sample_calibration).parameters
    assert list(ours.values()) == list(inspect.signature(gpmsa.calibrate).parameters.values())
