"""Ill-conditioned but valid emulators: a nugget too small for float64 is refused naming it.

Sigma_W = R / lamUz + (1/(lam_sim lamWOs) + 1/lamWs) I over many smooth runs is singular to
rounding where the nugget falls to ~1e-14 of 1/lamUz (lamWs, lamWOs held or bounded far beyond
GPM/SA's 1e5). Every entry says so, with the numbers and the remedy, instead of "not positive
definite"; a fit whose chain starts there is refused at the start (as the torch backend's);
a fit whose point estimate cannot factor warns; calibrate's series check leaks no numpy
warnings where the predictive variance is zero or negative by rounding.
"""

import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.fitting import fit as fit_module

NUGGET = r"Sigma_W of basis component 0 is not positive definite in float64 .*nugget 1/lamWs"
OPEN = gpmsa.Priors(
    lamWs=gpmsa.GammaPrior(3.0, 3e-3, 60.0, float("inf")),
    lamWOs=gpmsa.GammaPrior(5.0, 5e-3, 60.0, float("inf")),
)


def _smooth(m: int, seed: int = 0) -> gpmsa.SimData:
    rng = np.random.default_rng(seed)
    x, t = rng.random((m, 1)), rng.random((m, 1))
    return gpmsa.SimData(x=x, t=t, y=x + t)


def _emulator(lam: float, beta: float, m: int = 100) -> gpmsa.Emulator:
    params = {"betaU": np.full((2, 1), beta), "lamUz": [1.0], "lamWs": [lam], "lamWOs": [lam]}
    return gpmsa.Emulator.from_params(_smooth(m), params)


def test_every_entry_names_the_nugget_and_the_remedy():
    emu = _emulator(1e16, 0.01)  # cond(Sigma_W) ~ 4e19: dpotrf fails
    x, t = np.array([[0.3], [0.6]]), np.array([[0.4], [0.5]])
    y = x + 0.3
    calls = {
        "predict": lambda: emu.predict(x, t),
        "loo": emu.loo,
        "cross_validate": lambda: gpmsa.cross_validate(emu, draws=False),
        "sensitivity": lambda: gpmsa.sensitivity(emu, draws=False),
        "calibrate": lambda: gpmsa.calibrate(emu, x_obs=x, y_obs=y, n_samples=20, n_burn=5),
        "Calibrator": lambda: gpmsa.Calibrator(emu),
    }
    for name, call in calls.items():
        with pytest.raises(gpmsa.GPMSAError, match=NUGGET) as info:
            call()
        text = str(info.value)
        assert "= 2e-16" in text and "1/lamUz = 1" in text and "100 runs" in text, name
        assert "fixed=" in text and "1e5" in text, name


def test_fit_refuses_a_start_whose_sigma_w_does_not_factor():
    fixed = {"lamWs": 1e18, "lamWOs": 1e18}
    start = r"chain 0 of 1 failed: .* in float64 at the chain's start: its nugget .* = 2e-18"
    with pytest.raises(gpmsa.GPMSAError, match=start):
        gpmsa.fit(_smooth(60), n_iter=5, tune=False, seed=0, priors=OPEN, fixed=fixed)


@pytest.mark.filterwarnings("ignore::gpmsa.ConvergenceWarning")
def test_fit_warns_where_its_point_estimate_does_not_factor(monkeypatch):
    real = fit_module.point_estimate

    def beyond_float64(*args):  # the chain's draws factor; the point given to the emulator not
        out = real(*args)
        lam = np.array([1e16])
        return {**out, "betaU": np.full((2, 1), 0.01), "lamUz": np.ones(1), "lamWs": lam,
                "lamWOs": lam}  # fmt: skip

    monkeypatch.setattr(fit_module, "point_estimate", beyond_float64)
    with pytest.warns(UserWarning, match=r"in float64 at the fit's point estimate \(point='mean'\)"
                      r": its nugget .* refuse this emulator"):  # fmt: skip
        emu = gpmsa.fit(_smooth(100), n_iter=5, tune=False, seed=0)
    with pytest.raises(gpmsa.GPMSAError, match=NUGGET):
        emu.predict([[0.5]], [[0.5]])


def test_calibrate_leaks_no_numpy_warning_at_a_rounding_level_nugget():
    emu = _emulator(1e16, 3.0)  # factors, but predictive variances ~ +-1e-16
    x = np.array([[0.3], [0.6]])
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        post = gpmsa.calibrate(emu, x_obs=x, y_obs=x + 0.3, n_samples=60, n_burn=10, seed=1)
    assert np.all(np.isfinite(post.samples["t0"]))


def test_a_small_but_resolved_nugget_still_predicts():
    emu = _emulator(1e10, 0.001, m=60)  # cond ~ 3e11: resolved, and exact to 1e-6
    x, t = np.array([[0.3], [0.6]]), np.array([[0.4], [0.5]])
    mean, var = emu.predict(x, t, resid=False)
    assert np.all(np.isfinite(var)) and np.max(np.abs(mean - (x + t))) < 1e-4
