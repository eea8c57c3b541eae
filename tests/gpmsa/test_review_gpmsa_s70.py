"""Review of session 70's gpmsa changes: an ExtrapolationWarning names the user's call (the
line a filter or a reader needs), not a line inside gpmsa, wherever calibration or a joint fit
meets x_obs outside the design (before: calibrator.py, calibrate.py, problem.py)."""

from __future__ import annotations

import warnings
from functools import cache

import numpy as np

import gpmsa
from gpmsa.fitting.emulator import Emulator


def _f(x, t):
    return np.sin(2.0 * x + 1.5 * t)


@cache
def _case() -> tuple[gpmsa.SimData, Emulator]:
    rng = np.random.default_rng(7)
    x, t = rng.uniform(0, 1, 30), rng.uniform(0, 1, 30)
    sim = gpmsa.SimData(x=x[:, None], t=t[:, None], y=_f(x, t)[:, None], t_names=["a"])
    params = {"betaU": [[1.0], [1.5]], "lamUz": [1.0], "lamWs": [5000.0], "lamWOs": [5000.0]}
    return sim, Emulator.from_params(sim, params)


def _sources(run) -> list[str]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        warnings.simplefilter("ignore", gpmsa.OutsideEmulatorWarning)
        run()
    return [w.filename for w in caught if issubclass(w.category, gpmsa.ExtrapolationWarning)]


def test_extrapolation_warnings_name_the_users_call():
    sim, emu = _case()
    x = np.array([[float(sim.x.max()) + 0.05]])
    y = _f(x, 0.4)
    cal = gpmsa.Calibrator(emu, extrapolate=True)
    runs = {
        "Calibrator.update": lambda: cal.update(x, y),
        "log_likelihood_grid": lambda: cal.log_likelihood_grid(x, y),
        "calibrate": lambda: gpmsa.calibrate(
            emu, x, y, n_samples=20, n_burn=5, seed=0, extrapolate=True
        ),
        "fit": lambda: gpmsa.fit(sim, gpmsa.ObsData(x=x, y=y), n_iter=4, seed=0),
    }
    for name, run in runs.items():
        assert _sources(run) == [__file__], name
