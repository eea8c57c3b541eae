"""A joint fit (``gpmsa.fit(sim, obs)``, ``gpmsa.fit_study``) names an observed value far beyond
every simulation run, as ``gpmsa.calibrate`` does with a fitted emulator.

One -999 among the 36 values of three functional experiments (25 runs of
y = sin(3x + 2s) + t^2 s on 12 points s) left the joint fit silent while lamOs fell from 760 to
2.2e-5 and theta's posterior from 0.500 +- 0.018 to its prior (0.51 +- 0.28; 3,000 sweeps). The
value is now named in an ``OutsideEmulatorWarning`` before the sampling starts, in the words of
the calibration's warning; the fitted draws are unchanged.
"""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa import OutsideEmulatorWarning
from gpmsa.fitting import fit as fit_module
from gpmsa.fitting.emulator import Emulator
from tests.gpmsa._far_cases import (
    GRID,
    functional,
    scalar_sim,
    stop_sampling,
)
from tests.gpmsa._far_cases import (
    functional_sim as _sim,
)
from tests.gpmsa._far_cases import (
    texts_before_sampling as _outside,
)

NAMED = (r"y_obs\[1\] holds -999 at time 0\.4545\d* s, 1\.\d+e\+03 sds of the simulation "
         r"outputs below every simulation run's value there \(\[-?\d\.\d+, \d\.\d+\]\): a "
         r"missing-value code")  # fmt: skip


def _observed() -> tuple[np.ndarray, np.ndarray]:
    """Three experiments at k = 0.5 with noise of sd 0.02 (the outputs' sd is about 0.7)."""
    x = np.array([[0.2], [0.4], [0.7]])
    noise = 0.02 * np.random.default_rng(0).standard_normal((3, GRID.size))
    return x, functional(x[:, 0], np.full(3, 0.5)) + noise


@pytest.fixture
def _stopped(monkeypatch):
    stop_sampling(monkeypatch)


def test_joint_fit_names_a_missing_value_code_before_sampling(_stopped):
    x, y = _observed()
    y[1, 5] = -999.0  # a logger's missing-value code
    texts = _outside(lambda: gpmsa.fit(_sim(), gpmsa.ObsData(x=x, y=y), n_iter=100_000, seed=0))
    assert len(texts) == 1
    assert re.match(NAMED, texts[0]), texts[0]
    assert "lamOs" in texts[0] and "drop or correct the value" in texts[0]


def test_joint_fit_warns_as_the_calibration_does():
    """The same words as the Calibrator's warning for these data with an emulator of these
    runs; the warning points at the user's line."""
    x, y = _observed()
    y[1, 5] = -999.0
    params = {"betaU": [[1.0, 1.0], [1.5, 1.5]], "lamUz": [1.0, 1.0],
              "lamWs": [2000.0, 2000.0], "lamWOs": [2000.0]}  # fmt: skip
    emu = Emulator.from_params(_sim(), params, n_pc=2)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        gpmsa.Calibrator(emu).update(x, y)
        gpmsa.fit(_sim(), gpmsa.ObsData(x=x, y=y), n_iter=4, tune=False, seed=0)
    found = [w for w in caught if issubclass(w.category, OutsideEmulatorWarning)]
    assert len(found) == 2
    assert str(found[0].message) == str(found[1].message)
    assert found[1].filename == __file__


def test_the_fitted_draws_are_those_without_the_check(monkeypatch):
    """Only the warning is new: the fit of data holding -999 draws what it drew unchecked."""
    x, y = _observed()
    y[1, 5] = -999.0

    def draws() -> dict:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            emu = gpmsa.fit(_sim(), gpmsa.ObsData(x=x, y=y), n_iter=20, tune=False, seed=3)
        return {**emu.draws, **emu.calibration}

    checked = draws()
    monkeypatch.setattr(fit_module, "joint_far_value", lambda *args: None)
    unchecked = draws()
    assert checked.keys() == unchecked.keys()
    for k in checked:
        np.testing.assert_array_equal(checked[k], unchecked[k])


def test_noise_beyond_the_runs_and_clean_data_do_not_warn(_stopped):
    x, y = _observed()
    sim = _sim()
    assert _outside(lambda: gpmsa.fit(sim, gpmsa.ObsData(x=x, y=y), seed=0)) == []
    sd = float(np.std(sim.y, ddof=1))  # the outputs' sd (the standardising scale)
    y[1, 5] = sim.y[:, 5].max() + 3.0 * sd  # 3 sds above every run: noise may put it there
    assert _outside(lambda: gpmsa.fit(sim, gpmsa.ObsData(x=x, y=y), seed=0)) == []


def test_ragged_and_interpolated_grids(_stopped):
    """Experiments on grids of their own (between the simulation points) within the runs'
    range: no warning; -999 on such a grid: named at its point there."""
    x, y = _observed()
    mid = 0.5 * (GRID[1:] + GRID[:-1])  # interpolated: no simulation point
    clean = [y[0, ::2], np.sin(3 * 0.4 + 2 * mid) + 0.25 * mid, y[2, 1:]]
    grids = [GRID[::2], mid, GRID[1:]]
    sim = _sim()
    obs = gpmsa.ObsData(x=x, y=clean, index=grids)
    assert _outside(lambda: gpmsa.fit(sim, obs, seed=0)) == []
    bad = [clean[0], clean[1].copy(), clean[2]]
    bad[1][4] = -999.0
    obs = gpmsa.ObsData(x=x, y=bad, index=grids)
    texts = _outside(lambda: gpmsa.fit(sim, obs, seed=0))
    assert len(texts) == 1
    assert texts[0].startswith(f"y_obs[1] holds -999 at time {mid[4]:.6g} s, "), texts[0]


def test_scalar_output_named_only_far_beyond_the_runs(_stopped):
    """Noisy scalar data lie beyond the runs legitimately (stated noise of 5 output sds: 20
    sds beyond at 4 sds of noise); a -999 code lies thousands of sds away."""
    sim = scalar_sim()
    sd = float(np.std(sim.y, ddof=1))
    x = np.linspace(0.05, 0.95, 10)[:, None]
    y = np.sin(3 * x) + 0.25
    y[4] = sim.y.max() + 20 * sd
    noisy = gpmsa.ObsData(x=x, y=y, precision=1 / (5 * sd) ** 2)
    assert _outside(lambda: gpmsa.fit(sim, noisy, seed=0)) == []
    y[4] = -999.0
    texts = _outside(lambda: gpmsa.fit(sim, gpmsa.ObsData(x=x, y=y), seed=0))
    assert len(texts) == 1
    assert re.match(r"y_obs\[4\] = -999, 2\.\d+e\+03 sds of the simulation outputs below every "
                    r"simulation run's value \(\[0\.14\d*, 1\.65\d*\]\): a missing-value",
                    texts[0]), texts[0]  # fmt: skip


def test_fit_study_names_the_model(_stopped):
    x, y = _observed()
    bad = y.copy()
    bad[1, 5] = -999.0
    obs = [gpmsa.ObsData(x=x, y=y), gpmsa.ObsData(x=x, y=bad)]
    texts = _outside(lambda: gpmsa.fit_study([_sim(), _sim()], obs, labels=["a", "b"],
                                             shared=["k"], n_iter=100_000, seed=1))  # fmt: skip
    assert len(texts) == 1
    assert texts[0].startswith("model 'b': y_obs[1] holds -999 at time 0.4545"), texts[0]
    assert re.match(NAMED, texts[0][len("model 'b': ") :]), texts[0]


def test_with_a_discrepancy_the_warning_says_it_may_take_up_the_value(_stopped):
    x, y = _observed()
    y[1, 5] = -999.0
    obs = gpmsa.ObsData(x=x, y=y)
    texts = _outside(lambda: gpmsa.fit(_sim(), obs, discrepancy="linear", seed=0))
    assert len(texts) == 1 and re.match(NAMED, texts[0]), texts
    assert "a large observation error (small lamOs) or the discrepancy and theta" in texts[0]
