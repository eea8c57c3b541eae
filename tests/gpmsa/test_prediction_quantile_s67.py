"""``quantile(q)`` of EmulatorPrediction and FullPrediction: the realizations' empirical
quantiles (users called ``np.quantile(pred.y, q, axis=0)``), q checked as
``Posterior.quantile`` checks it, and ``interval`` their values at (1 -+ level) / 2."""

import warnings
from functools import cache

import numpy as np
import pytest
from _study_cases import emulator, observations

import gpmsa
from gpmsa import GPMSAError
from gpmsa.predictive import EmulatorPrediction, FullPrediction

X_NEW = [[0.2], [0.5], [0.8]]


@cache
def _emulator_prediction() -> EmulatorPrediction:
    """Realizations of a from_params emulator (point estimate): y (60, 3, 1)."""
    return gpmsa.emulator_prediction(emulator(None), X_NEW, [[0.4]], draws=False, n_rlz=60,
                                     seed=0)  # fmt: skip


@cache
def _full_prediction() -> FullPrediction:
    """A full prediction from a short calibration of the same emulator: 20 draws x 3."""
    x, y = observations(0.45, 6, 0.03, np.random.default_rng(1))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # so short a chain is not converged
        post = gpmsa.calibrate(emulator(None), x, y, n_samples=120, n_burn=20, seed=0,
                               tune=False)  # fmt: skip
    obs = gpmsa.ObsData(x=x, y=y)
    return gpmsa.full_prediction(emulator(None), obs, X_NEW, posterior=post, n_draws=20,
                                 n_rlz=3, seed=2)  # fmt: skip


Q_CASES = [0.5, 0.0, 1.0, np.float32(0.25), [0.1, 0.9], np.array([[0.05, 0.5], [0.7, 0.95]])]


@pytest.mark.parametrize("q", Q_CASES)
def test_emulator_prediction_quantile_is_numpys_on_the_realizations(q):
    pred = _emulator_prediction()
    got = pred.quantile(q)
    assert np.array_equal(got, np.quantile(pred.y, np.asarray(q, dtype=float), axis=0))
    assert got.shape == np.shape(q) + pred.y.shape[1:]


@pytest.mark.parametrize("what", ["y", "eta", "delta", "zeta"])
def test_full_prediction_quantile_of_each_quantity(what):
    pred = _full_prediction()
    draws = getattr(pred, what)
    assert draws.shape == (60, 3, 1)
    for q in Q_CASES:
        got = pred.quantile(q, what)
        assert np.array_equal(got, np.quantile(draws, np.asarray(q, dtype=float), axis=0))
        assert got.shape == np.shape(q) + draws.shape[1:]
    assert np.array_equal(pred.quantile(0.3), pred.quantile(0.3, what="y"))  # y by default


@pytest.mark.parametrize("level", [0.5, 0.9])
def test_interval_is_the_quantiles_at_its_ends_as_before(level):
    """``interval`` keeps its numbers bit for bit (np.quantile at both ends at once) and they
    are ``quantile`` at (1 -+ level) / 2."""
    ends = [(1 - level) / 2, (1 + level) / 2]
    emu_pred, full = _emulator_prediction(), _full_prediction()
    lo, hi = emu_pred.interval(level)
    assert np.array_equal(np.stack([lo, hi]), np.quantile(emu_pred.y, ends, axis=0))
    assert np.array_equal(lo, emu_pred.quantile(ends[0]))
    assert np.array_equal(hi, emu_pred.quantile(ends[1]))
    for what in ("y", "zeta"):
        lo, hi = full.interval(what, level)
        assert np.array_equal(np.stack([lo, hi]), np.quantile(getattr(full, what), ends, axis=0))
        assert np.array_equal(np.stack([lo, hi]), full.quantile(ends, what))


BAD_Q = [
    (1.5, r"q must lie in \[0, 1\], got 1.5"),
    (-0.1, r"q must lie in \[0, 1\], got -0.1"),
    (float("nan"), r"q must lie in \[0, 1\], got nan"),
    (float("inf"), r"q must lie in \[0, 1\], got inf"),
    ([0.2, 1.01], r"q must lie in \[0, 1\], got \[0.2, 1.01\]"),
    ([], r"q must hold at least one probability, got \[\]"),
    ("0.5", "q must be a numeric array, got str '0.5'"),
    (True, "q must be a numeric array, got bool"),
    (None, "q must be a numeric array, got None"),
]


@pytest.mark.parametrize(("q", "match"), BAD_Q)
def test_bad_q_is_named_with_its_value(q, match):
    with pytest.raises(GPMSAError, match=match):
        _emulator_prediction().quantile(q)
    with pytest.raises(GPMSAError, match=match):
        _full_prediction().quantile(q, "eta")


def test_full_prediction_quantile_names_a_bad_what_and_swapped_arguments():
    pred = _full_prediction()
    with pytest.raises(GPMSAError, match="what must be one of"):
        pred.quantile(0.5, "ysim")
    with pytest.raises(GPMSAError, match=r"got 'eta': the quantity comes second, quantile\(q, "):
        pred.quantile("eta")
    with pytest.raises(GPMSAError, match=r"q must lie in \[0, 1\], got 2"):
        pred.quantile(2, what="delta")
