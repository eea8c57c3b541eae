"""The outside-the-emulator check for a categorical theta looks at its levels (session 67).

Before: it probed `theta_probe`'s nodes, off the levels, where the predictive mean is no
level's and its sd about the prior's, so an observation that no level explains read within a
few sds and did not warn (1 parameter, levels 0, 1, 3: 4.49 sds beyond every level, 1.01
between two; with a continuous parameter beside it 3.3). Now the levels, crossed with the
continuous parameters' nodes: 33.3, 15.7 and 13.5, a warning each; an observation that a level
explains still reads within the threshold."""

import functools
import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.calibration.calibrate import observation_fit
from gpmsa.calibration.observations import (
    LEVEL_PROBE_BUDGET,
    OUTSIDE_SDS,
    continuous_probe,
    fit_at_levels,
    fit_of,
    fixed_gp,
    lamos_start,
    level_probe_blocks,
    reduce,
)
from gpmsa.errors import OutsideEmulatorWarning

X_OBS = np.linspace(0.1, 0.9, 5)[:, None]
PARAMS = {"lamUz": [1.0], "lamWs": [1e3], "lamWOs": [1e3]}


@functools.cache
def _one_level_parameter():
    """theta: levels 0, 1, 3 (unit 0, 1/3, 1: level 1 off the 129 old nodes), shifts 0, 1, -0.7."""
    rng = np.random.default_rng(0)
    x, t = rng.random(30), np.array([0, 1, 3])[np.arange(30) % 3]
    shift = np.array([0.0, 1.0, 0.0, -0.7])
    sim = gpmsa.SimData(x, t, x + shift[t], t_categorical=[0])
    return gpmsa.Emulator.from_params(sim, {"betaU": [[1.0], [1.0]], **PARAMS})


@functools.cache
def _level_and_continuous():
    """t0: levels 0, 1, 2 (shifts 0, 1, -0.7); t1 continuous, + 0.3 t1."""
    rng = np.random.default_rng(0)
    x, t0, t1 = rng.random(60), np.arange(60) % 3, rng.random(60)
    y = x + np.array([0.0, 1.0, -0.7])[t0] + 0.3 * t1
    sim = gpmsa.SimData(x, np.column_stack([t0, t1]), y, t_categorical=[0])
    return gpmsa.Emulator.from_params(sim, {"betaU": [[1.0], [1.0], [1.0]], **PARAMS})


def _outside(emu, x, y):
    return observation_fit(emu, reduce(emu, x, y[:, None], False), [emu.params]).outside_sds


@pytest.mark.parametrize(
    ("case", "offset", "warns"),
    [
        (_one_level_parameter, 1.0 + 0.02, False),  # level 1 (unit 1/3): 2.22 before, 1.15
        (_one_level_parameter, -0.7, False),  # level 3
        (_one_level_parameter, 2.0, True),  # beyond every level: 4.49 before
        (_one_level_parameter, 0.5, True),  # between levels 0 and 1: 1.01 before
        (_level_and_continuous, 1.0 + 0.3 * 0.5, False),  # level 1 at t1 = 0.5
        (_level_and_continuous, -0.7 + 0.3 * 0.9, False),  # level 2 at t1 = 0.9
        (_level_and_continuous, 1.8, True),  # beyond every level and t1: 3.3 before
    ],
)
def test_warns_iff_no_level_explains_the_observation(case, offset, warns):
    emu = case()
    for x in (X_OBS, X_OBS[2:3]):  # judged jointly (5 values), and one datum on its own
        y = x[:, 0] + offset
        assert (_outside(emu, x, y) > 2 * OUTSIDE_SDS) == warns
        assert (_outside(emu, x, y) < 2.0) == (not warns)


def test_calibrate_prints_the_warning_for_an_observation_no_level_explains():
    emu = _one_level_parameter()
    with pytest.warns(OutsideEmulatorWarning, match=r"lies 3\d\.\d predictive sds"):
        gpmsa.calibrate(emu, X_OBS, X_OBS[:, 0] + 2.0, n_samples=20, n_burn=5, seed=0)
    with warnings.catch_warnings():
        warnings.simplefilter("error", OutsideEmulatorWarning)
        post = gpmsa.calibrate(emu, X_OBS, X_OBS[:, 0] + 1.02, n_samples=20, n_burn=5, seed=0)
    assert post.info["outside_sds"] < 2.0


def test_the_level_probe_is_every_combination_crossed_with_the_continuous_nodes():
    blocks = list(level_probe_blocks([(0.0, 0.5, 1.0), None]))
    theta = np.vstack([b[0] for b in blocks])
    assert sum(b[1] for b in blocks) == 3 and blocks[0][2] == (129,)
    assert theta.shape == (3 * 129, 2)
    np.testing.assert_array_equal(np.unique(theta[:, 0]), [0.0, 0.5, 1.0])
    chunks = list(level_probe_blocks([(0.0, 0.5, 1.0), tuple(np.linspace(0, 1, 7))], nodes=4))
    assert [c[1] for c in chunks] == [4, 4, 4, 4, 4, 1] and chunks[0][2] is None
    assert {tuple(r) for c in chunks for r in c[0]} == {
        (a, b) for a in (0.0, 0.5, 1.0) for b in np.linspace(0, 1, 7)
    }


def test_many_combinations_of_levels_stay_within_the_probe_budget():
    """10 x 10 levels beside two continuous parameters asked 108,900 predictions (5 s at 200
    runs; 20^3 levels 70 s): the continuous nodes get coarser so that the whole probe stays
    within LEVEL_PROBE_BUDGET, and beyond it the check is theta_probe's (review, session 67)."""
    ten = tuple(np.linspace(0, 1, 10))
    blocks = list(level_probe_blocks([ten, ten, None, None]))
    n = sum(b[0].shape[0] for b in blocks)
    assert n <= LEVEL_PROBE_BUDGET and blocks[0][2] == (9, 9) and sum(b[1] for b in blocks) == 100
    twenty = tuple(np.linspace(0, 1, 20))
    blocks = list(level_probe_blocks([twenty, twenty, twenty, None]))
    assert sum(b[0].shape[0] for b in blocks) == 8000 and blocks[0][2] is None
    np.testing.assert_array_equal(np.vstack([b[0] for b in blocks])[:, 3], 0.5)  # the centre
    assert list(level_probe_blocks([twenty, twenty, twenty, (0.0, 1.0)])) == []
    base, layout = continuous_probe(1, 3)
    assert base.shape == (129, 1) and layout == (129,)  # few levels: theta_probe's, unchanged


def test_too_many_combinations_fall_back_to_the_continuous_probe():
    levels = [tuple(np.linspace(0, 1, 20))] * 3 + [(0.0, 1.0)]
    assert fit_at_levels(None, None, levels) is None  # nothing predicted
    rng = np.random.default_rng(0)
    x = rng.random(63)  # three parameters of 21 levels: 9,261 combinations, over the budget
    t = np.column_stack([np.arange(63) % 21, (np.arange(63) // 3) % 21, rng.integers(0, 21, 63)])
    sim = gpmsa.SimData(x, t, x + 0.05 * t[:, 0], t_categorical=[0, 1, 2])
    emu = gpmsa.Emulator.from_params(sim, {"betaU": [[1.0]] * 4, **PARAMS})
    post = gpmsa.calibrate(emu, X_OBS, X_OBS[:, 0] + 0.5, n_samples=20, n_burn=5, seed=0)
    assert np.isfinite(post.info["outside_sds"])  # theta_probe's, as before session 67


def _fit(emu, offset):
    data = reduce(emu, X_OBS, (X_OBS[:, 0] + offset)[:, None], False)
    return data, observation_fit(emu, data, [emu.params])


def test_the_lamos_start_is_taken_at_the_levels():
    """The lamOs start (excess_var) came from theta_probe's nodes, off the levels (session 68):
    data that level 1 explains (1.15 sds) read an excess of 1.03 there, the chain started at
    lamOs 0.97 against a posterior near 1,300 and its lamOs steps were accepted 0.93-0.96 of
    the time at 300 sweeps (0.98-0.99 at 3,000, ESS 4-7 of 2,000); data between two levels read
    none (start 1,000, posterior 3.3). Now both from the levels: 0 and 0.38."""
    emu = _one_level_parameter()
    data, fit = _fit(emu, 1.0 + 0.02)
    assert fit.excess_var == 0.0
    assert lamos_start(fit, data.lamos) == max(20.0, data.lamos.shape / data.lamos.rate)
    data, fit = _fit(emu, 0.5)
    levels = np.array([[0.0], [1.0 / 3.0], [1.0]])  # the unit-scale levels
    at = fit_of(*fixed_gp(emu).predict(data.x, levels), data)
    assert fit.excess_var == at.excess_var > 0.3
    assert lamos_start(fit, data.lamos) < 3.0
    post = gpmsa.calibrate(emu, X_OBS, X_OBS[:, 0] + 1.02, n_samples=300, n_burn=100, seed=0)
    assert post.info["accept_rate"][0][-1] < 0.6  # lamOs: 0.96 before


@pytest.mark.parametrize(
    ("case", "rows", "levels"),
    [
        (_one_level_parameter, 3, [0.0, 1.0 / 3.0, 1.0]),
        (_level_and_continuous, 387, [0.0, 0.5, 1.0]),
    ],
)
def test_observation_fit_predicts_once_and_at_the_levels_only(case, rows, levels, monkeypatch):
    """One probe serves the outside check and the lamOs start: before, theta_probe's 129
    (1,089) nodes off the levels were predicted too."""
    from gpmsa.calibration.model import FixedGP

    emu, seen = case(), []
    predict = FixedGP.predict
    monkeypatch.setattr(FixedGP, "predict", lambda gp, x, t: seen.append(t) or predict(gp, x, t))
    _fit(emu, 2.0)
    theta = np.vstack(seen)
    assert theta.shape[0] == rows
    assert np.isin(theta[:, 0], levels).all()
