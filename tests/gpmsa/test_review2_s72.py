"""Review of session 72's parallel tempering (``gpmsa.mcmc.tempering``).

``swap_every`` above ``n_iter`` ran no swap round among the draws: the copies never exchanged
states there, and ``settings["swap_rate"]`` read 0.0 for every pair (30 sweeps, swap_every=100:
[[0.0, 0.0], [0.0, 0.0]]), which the docs read as a ladder too sparse. It is refused by name.
"""

import numpy as np
import pytest
from _tempering_cases import two_mode_case as _case

import gpmsa
from gpmsa.errors import GPMSAError
from gpmsa.mcmc import tempering


def test_swap_every_above_n_iter_refused():
    sim, obs = _case()
    with pytest.raises(GPMSAError, match=r"swap_every=100 exceeds n_iter=30: no swap round"):
        gpmsa.fit(sim, obs, n_iter=30, seed=3, temperatures=3, swap_every=100, tune=False)
    with pytest.raises(GPMSAError, match=r"swap_every=31 exceeds n_iter=30"):
        tempering.check_swap_every(31, (1.0, 2.0), 30)
    assert tempering.check_swap_every(30, (1.0, 2.0), 30) == 30  # one round, at the end
    assert tempering.check_swap_every(1, None, 0) == 1  # no tempering: nothing to check


def test_swap_every_up_to_n_iter_records_its_rounds():
    sim, obs = _case()
    emu = gpmsa.fit(sim, obs, n_iter=20, seed=3, temperatures=2, swap_every=20, tune=False)
    rate = emu.settings["swap_rate"]
    assert emu.settings["swap_every"] == 20 and np.shape(rate) == (1, 1)
    assert rate[0][0] in (0.0, 1.0)  # one round: accepted or not
