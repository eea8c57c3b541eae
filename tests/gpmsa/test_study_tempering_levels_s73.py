"""Parallel tempering moves a model's own categorical theta that trades off with a shared
continuous one (session 73; docs/models.md, "Parallel tempering" and "Limitations").

The case of ``test_study_categorical_s72.py`` (y = sin(3x) + k + 0.5 kind: kind 1 at k = 0.4
and kind 0 at k = 0.9 explain the data alike), two experiments, k shared and kind each model's
own. A level change must happen in both models at once: the plain study's chains stay at their
start's levels (measured: seeds 1-4, 4 chains x 1,200, every chain at one joint level, pooled
P(kind 0) 0, 0.5, 0.25, 0.25 against the brute-force grid's 0.844). With the ladder (1, 4, 16,
64) the hot copies pass through the mismatched levels and the chain moves between (0, 0) and
(1, 1): 4 chains x 5,000, P(kind 0) 0.835 and 0.857 (seeds 1, 2), R-hat of kind <= 1.013.
The emulator is the s72 fixture's 600-sweep fit, its parameters written out (no fit here).
"""

import warnings

import numpy as np
from _level_cases import level_function, level_sim

import gpmsa

PARAMS = {"betaU": [[0.854], [0.0655], [0.3338]], "lamUz": [0.3356], "lamWs": [3919.0],
          "lamWOs": [3171.0]}  # fmt: skip


def _case():
    rng = np.random.default_rng(2)
    sim = level_sim(rng, 60)
    emu = gpmsa.Emulator.from_params(sim, PARAMS)
    obs = []
    for lo, hi, n in [(0.1, 0.9, 6), (0.15, 0.85, 5)]:
        xo = np.linspace(lo, hi, n)[:, None]
        truth = np.column_stack([np.full(n, 0.4), np.full(n, 1)])
        obs.append((xo, level_function(xo, truth) + rng.normal(0, 0.05, n)))
    return emu, obs


def test_tempered_study_moves_each_models_own_level_with_the_shared_k():
    emu, ((xa, ya), (xb, yb)) = _case()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)  # one short chain
        study = gpmsa.calibrate_study([emu, emu], [xa, xb], [ya, yb], shared=["k"],
                                      labels=["a", "b"], seed=1, n_samples=240, n_burn=0,
                                      n_jobs=1, tune_rounds=2, tune_levels=10,
                                      temperatures=[1, 4, 16, 64])  # fmt: skip
    a, b = study.posterior.chains["kind[a]"][0], study.posterior.chains["kind[b]"][0]
    # the grid puts 0.844 on (0, 0), 0.156 on (1, 1), < 1e-4 on mismatched levels; the plain
    # chain (temperatures=None) stays at (1, 1) here
    assert np.mean(a != b) < 0.02
    assert 0.1 < np.mean(a == 0) < 0.95, np.mean(a == 0)  # both joint levels visited
    assert np.sum(np.diff(a) != 0) >= 10  # and switched between repeatedly (measured 45)
    rates = np.array(study.settings["swap_rate"])
    assert rates.shape == (1, 3) and np.all((rates > 0.2) & (rates < 0.9)), rates
