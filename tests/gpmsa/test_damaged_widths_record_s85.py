"""A continuation from a record whose numbers are damaged (session 85): a study's recorded step
widths given as text, bools or a number beyond float64 were read as numbers ("0.5" as 0.5, true
as 1.0) or raised a bare OverflowError; a tempered fit's hot theta beyond float64 with a
categorical theta raised OverflowError. Each is refused naming the record."""

import copy
import warnings

import numpy as np
import pytest
from _level_cases import three_theta_case

import gpmsa
from gpmsa.errors import GPMSAError
from gpmsa.studies import continuation as cont
from tests.gpmsa.test_study_continue_s67 import _calibrate


@pytest.fixture(scope="module")
def source():
    return _calibrate(60, 1, n_burn=10)


@pytest.mark.parametrize("bad", [["0.5", "0.5"], [10**400, 0.1], [True, 0.1], [None, 0.1]])
def test_a_study_s_damaged_step_widths_are_refused(source, bad):
    names = list(source.settings[cont.WIDTHS_BY_CHAIN])
    assert cont.continued_widths(source, names, 2) is not None  # the record as written: read
    damaged = copy.deepcopy(source)
    damaged.settings[cont.WIDTHS_BY_CHAIN][names[0]] = bad
    with pytest.raises(GPMSAError, match="not finite positive widths for 2 chain.*tune=True"):
        cont.continued_widths(damaged, names, 2)


def test_a_hot_categorical_theta_beyond_float64_is_named():
    sim, obs = three_theta_case(np.random.default_rng(0))
    opts = {"temperatures": 2, "progress": False}
    with warnings.catch_warnings():  # short chains: not converged
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        emu = gpmsa.fit(sim, obs, n_iter=30, seed=1, tune_rounds=1, tune_levels=2, **opts)
    assert np.shape(emu.settings["hot_states"]["theta"]) == (1, 1, 3)
    settings = copy.deepcopy(emu.settings)
    settings["hot_states"]["theta"] = [[[10**400, 0.1, 0.0]]]
    damaged = copy.copy(emu)
    object.__setattr__(damaged, "settings", settings)
    with pytest.raises(GPMSAError, match=r"hot_step_widths'\]\) do not fit .*too large for float"):
        gpmsa.fit(sim, obs, n_iter=10, seed=2, init=damaged, **opts)
