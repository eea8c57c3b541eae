"""``calibrate(fast=False)`` follow-ups of session 72: a categorical theta's default start, the
joint level move's shifts during the step-size tuning, and parallel tempering's records.

1. An even number of levels: the default start (0.5, unit) fell between two levels and
   ``calibrate(fast=False)`` (one chain, init "gpmsa" or "auto") raised "start theta ...
   outside the support of the theta prior"; ``gpmsa.prepare`` and the fast sampler snap it to
   the nearest level, ``calibration_problem`` now does too.
2. The generic numpy sampler learnt the level move's shifts after tuning only: a chain that sat
   at an unlikely level while tuning kept a lamOs step ~15x too short (widths 150-220, lamOs'
   acceptance 0.93-0.94; ESS of lamOs 9-79 on some seeds). It learns them before tuning too.
3. ``calibrate(fast=False, temperatures=)``: the memory estimate counts a likelihood state per
   temperature (as ``fit``'s), ``info`` records the ladder and the swap rates.
"""

import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.calibration import calibrate as cal_module
from gpmsa.calibration.calibrate import calibration_problem


def _f(x, t):
    return np.sin(3 * x[:, 0]) + t[:, 0] + 0.5 * t[:, 1]


def _case(n_levels: int, m: int = 60):
    """y = sin(3x) + k + 0.5 kind, kind in 0 .. n_levels - 1; the emulator at the point
    estimate of ``fit(sim, n_iter=600, seed=0)`` for three levels (no fit here)."""
    rng = np.random.default_rng(2)
    x = rng.random((m, 1))
    t = np.column_stack([rng.random(m), np.arange(m) % n_levels])
    sim = gpmsa.SimData(x, t, _f(x, t), x_names=["s"], t_names=["k", "kind"],
                        t_categorical=["kind"])  # fmt: skip
    prm = {"betaU": [[0.854], [0.066], [0.334]], "lamUz": [0.336], "lamWs": [3919.3],
           "lamWOs": [3170.7]}  # fmt: skip
    xo = np.linspace(0.1, 0.9, 6)[:, None]
    yo = _f(xo, np.column_stack([np.full(6, 0.4), np.ones(6)])) + rng.normal(0, 0.05, 6)
    return sim, gpmsa.Emulator.from_params(sim, prm), xo, yo


@pytest.mark.parametrize("n_levels", [2, 4])
@pytest.mark.parametrize("init", [None, "auto", "gpmsa"])
def test_an_even_number_of_levels_starts_at_the_nearest_level(n_levels, init):
    _, emu, xo, yo = _case(n_levels, m=24)
    problem = calibration_problem(emu, xo, yo)
    levels = problem.theta_levels[1]
    assert problem.init["theta"][1] in levels  # before: 0.5, between two levels
    assert problem.init["theta"][1] == levels[np.argmin(np.abs(levels - 0.5))]
    kw = {} if init is None else {"init": init}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        post = gpmsa.calibrate(emu, xo, yo, n_samples=60, n_burn=10, seed=1, fast=False,
                               tune_rounds=2, **kw)  # fmt: skip
    assert set(np.unique(post.samples["kind"])) <= set(range(n_levels))
    assert post.info["step_widths"]["theta"]  # it ran


def test_a_given_start_is_kept():
    _, emu, xo, yo = _case(4, m=24)
    problem = calibration_problem(emu, xo, yo, theta_init=[0.5, 3])
    assert problem.init["theta"][1] == 1.0


def test_the_widths_are_tuned_with_the_level_moves():
    """A chain started at k = 0.05 drifts to kind 2 while tuning (where lamOs is small) and, its
    level move not yet joint, stayed there: lamOs' width 153-190 (acceptance 0.93-0.94) against
    2,700-3,400 (0.39-0.43) with the shifts learnt before tuning."""
    _, emu, xo, yo = _case(3)
    for seed in (1, 3):
        post = gpmsa.calibrate(emu, xo, yo, n_samples=200, n_burn=50, seed=seed, fast=False,
                               theta_init=[0.05, 0], tune_rounds=20)  # fmt: skip
        assert post.info["step_widths"]["lamOs"][0][0] > 1000
        assert post.info["accept_rate"]["lamOs"][0][0] < 0.7


def test_a_joint_fit_tunes_with_the_level_moves():
    """The joint fit runs the same sampler: lamOs' width 149-220 before, 2,300-4,300 after."""
    sim, _, xo, yo = _case(3)
    emu = gpmsa.fit(sim, gpmsa.ObsData(xo, yo), n_iter=200, seed=2, theta_init=[0.05, 0],
                    tune_rounds=20)  # fmt: skip
    assert emu.settings["step_widths"]["lamOs"][0][0] > 1000


def _continuous():
    rng = np.random.default_rng(2)
    x, t = rng.random((20, 1)), rng.random((20, 1))
    sim = gpmsa.SimData(x, t, np.sin(3 * x[:, 0]) + t[:, 0])
    prm = {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [1e4], "lamWOs": [1e4]}
    xo = np.linspace(0.1, 0.9, 6)[:, None]
    return gpmsa.Emulator.from_params(sim, prm), xo, np.sin(3 * xo[:, 0]) + 0.4


def test_tempering_is_recorded_as_fit_records_it():
    emu, xo, yo = _continuous()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)  # 2 x 30 draws
        post = gpmsa.calibrate(emu, xo, yo, n_samples=40, n_burn=10, seed=1, fast=False,
                               tune_rounds=2, temperatures=3, swap_every=2, n_chains=2,
                               n_jobs=1)  # fmt: skip
    assert post.info["temperatures"] == [1.0, 2.0, 4.0] and post.info["swap_every"] == 2
    rates = np.array(post.info["swap_rate"])
    assert rates.shape == (2, 2) and np.all((rates >= 0) & (rates <= 1))
    plain = gpmsa.calibrate(emu, xo, yo, n_samples=40, n_burn=10, seed=1, fast=False,
                            tune_rounds=2)  # fmt: skip
    assert not {"temperatures", "swap_every", "swap_rate"} & set(plain.info)


def test_memory_counts_a_likelihood_state_per_temperature(monkeypatch):
    from gpmsa.fitting import fit as fit_module

    emu, xo, yo = _continuous()
    seen = []
    monkeypatch.setattr(cal_module, "check_memory", lambda n, what: seen.append((n, what)))
    cal_module._check_calibrate_memory(emu, 100, 2, False)
    cal_module._check_calibrate_memory(emu, 100, 2, False, copies=4)
    state = fit_module._factor_nbytes(20, 1, 1, 1)  # fit's figure for one likelihood state
    assert seen[1][0] - seen[0][0] == pytest.approx(4 * state)
    assert "at 4 temperatures" in seen[1][1] and "temperatures" not in seen[0][1]
    monkeypatch.undo()
    monkeypatch.setattr(gpmsa.limits, "MAX_MEMORY_BYTES", (seen[0][0] + seen[1][0]) / 2)
    with pytest.raises(gpmsa.ResourceLimitError, match="at 4 temperatures"):
        gpmsa.calibrate(
            emu, xo, yo, n_samples=100, n_burn=10, n_chains=2, fast=False, temperatures=4
        )
    with pytest.raises(gpmsa.GPMSAError, match="temperatures"):  # checked before any work
        gpmsa.calibrate(emu, xo, yo, n_samples=100, n_burn=10, fast=False, temperatures=0)
