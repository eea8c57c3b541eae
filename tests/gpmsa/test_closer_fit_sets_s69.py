"""The closer outside check (`closer_fit`) with several emulator parameter sets (session 69).

``emulator_params="draws"`` conditions on 20 sets; the check ran its local searches for every
set that read outside on the probe nodes, even where another set read the data inside, so the
verdict could not change: q = 6, 400 runs, 20 sets took 174 s instead of 14 s before the
search, for data inside. It now searches only where every set reads outside, and from the
best set's nodes only.
"""

import numpy as np
import pytest
import scipy.optimize
from _outside_cases import PARAMS, X_OBS, simulator, three_parameter_emulator

from gpmsa.calibration.calibrate import observation_fit
from gpmsa.calibration.observations import CLOSER_STARTS, OUTSIDE_SDS, reduce


@pytest.fixture(scope="module")
def emulator():
    return three_parameter_emulator()


@pytest.fixture
def searches(monkeypatch):
    calls = []
    minimize = scipy.optimize.minimize

    def counted(*args, **kwargs):
        calls.append(args[1])
        return minimize(*args, **kwargs)

    monkeypatch.setattr(scipy.optimize, "minimize", counted)
    return calls


def _data(emulator, scale=1.0):
    y = simulator(X_OBS[:, 0], np.tile([0.37, 0.61, 0.23], (3, 1)))
    y = y + 0.002 * np.random.default_rng(0).standard_normal(y.shape)
    return reduce(emulator, X_OBS, scale * y)


def _sets(n):
    return [{**PARAMS, "lamUz": PARAMS["lamUz"] * (1.0 + 0.02 * k)} for k in range(n)]


def test_only_the_best_set_is_searched(emulator, searches):
    fit = observation_fit(emulator, _data(emulator), _sets(4))
    assert fit.outside_sds < OUTSIDE_SDS
    assert len(searches) == 1


def test_a_units_error_costs_one_sets_searches(emulator, searches):
    fit = observation_fit(emulator, _data(emulator, 100.0), _sets(4))
    assert fit.outside_sds > 10 * OUTSIDE_SDS
    assert len(searches) <= CLOSER_STARTS


def test_no_search_where_a_set_reads_the_data_inside(emulator, searches):
    loose = {**PARAMS, "lamWOs": np.array([3.0])}  # a large nugget: inside on the nodes
    fit = observation_fit(emulator, _data(emulator), [*_sets(3), loose])
    assert fit.outside_sds < OUTSIDE_SDS
    assert searches == []
