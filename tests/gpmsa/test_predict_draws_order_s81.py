"""``predict(draws=True)`` keeps the values of its former form, the draws' means and variances
stacked and averaged by numpy (``np.array(list).mean(axis=0)``), also where each draw gives a
single value: numpy sums a contiguous column pairwise, not term by term as an accumulation
would (the review of the blocked predictions, session 81); and its memory refusal names the
remedy."""

from __future__ import annotations

import numpy as np
import pytest
from _calib_cases import road_emulator, with_draws

import gpmsa
import gpmsa.fitting.emulator as emulator_mod
from gpmsa._threads import one_thread
from gpmsa.fitting.emulator import EMULATOR_PARAMS


def _stacked(emu, x, t, resid: bool = True):
    """The former ``_predict_draws``: every draw's standardised mean and variance in lists,
    stacked, then numpy's mean and var over the draws (native units)."""
    z = emu._inputs(x, t)
    means, vars_ = [], []
    with one_thread():
        for i in range(emu.n_draws):
            prm = {k: emu.draws[k][i] for k in EMULATOR_PARAMS}
            m, v = emu._predict_std(z, prm, emu._predict_factors(prm), resid)
            means.append(m)
            vars_.append(v)
    means = np.array(means)
    var = np.array(vars_).mean(axis=0) + means.var(axis=0)
    s = emu.standardizer
    return s.y_from_std(means.mean(axis=0)), s.var_from_std(var)


@pytest.mark.parametrize("values", [None, 100])  # 100: the variances summed as they come
@pytest.mark.parametrize("n_points", [1, 2, 5])
@pytest.mark.parametrize("resid", [True, False])
def test_draws_prediction_is_numpys_mean_over_the_stacked_draws(monkeypatch, values, n_points,
                                                                resid):  # fmt: skip
    # one point of a scalar output and 40 draws: the accumulated variances differed from
    # numpy's pairwise mean of the stacked ones in the last bit
    if values is not None:  # one block of points still (64 rows at least)
        monkeypatch.setattr(emulator_mod, "PREDICT_BLOCK_VALUES", values)
    emu = with_draws(road_emulator(), n=40)
    rng = np.random.default_rng(4)
    x = rng.uniform(*emu.domain["v"], (n_points, 1))
    t = rng.uniform(*emu.domain["GD"], (n_points, 1))
    mean, var = emu.predict(x, t, draws=True, resid=resid)
    ref_mean, ref_var = _stacked(emu, x, t, resid)
    np.testing.assert_array_equal(mean, ref_mean)
    np.testing.assert_array_equal(var, ref_var)


def test_the_draws_memory_refusal_names_n_draws(monkeypatch):
    emu = with_draws(road_emulator(), n=40)
    n = 100_000
    x, t = np.full((n, 1), 1.2), np.full((n, 1), 400.0)
    rows = emulator_mod.predict_block_rows(emu.m)
    point = 8.0 * (4 * rows * emu.m + n * (6 + 4 * 2))  # one block, the inputs and outputs
    monkeypatch.setattr(gpmsa.limits, "MAX_MEMORY_BYTES", point + 8.0 * n * 20)  # 20 draws' means
    emu._check_predict_memory(x, t)  # the point estimate's prediction fits
    emu._check_predict_memory(x, t, 20)
    with pytest.raises(gpmsa.ResourceLimitError, match=r"40 draws.*n_draws= takes fewer"):
        emu.predict(x, t, draws=True)
    with pytest.raises(gpmsa.ResourceLimitError, match=r"21 draws.*n_draws= takes fewer"):
        emu.predict_mean(x, t, draws=True, n_draws=21)
