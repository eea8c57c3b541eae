"""Mutation testing of gpmsa.fitting.fit, the odd half's sites session 92 left (its first pass:
test_fit_odd_s92): what a fit records of its basis, and how a continuation chooses to tune and
at which widths it runs, on tiny fits of 5 runs and 20 sweeps."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from _fit_cases import five_run_data

import gpmsa
from gpmsa.errors import GPMSAError


@pytest.fixture(scope="module")
def data() -> gpmsa.SimData:
    return five_run_data()


def _fit(data, **kw) -> gpmsa.Emulator:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # short chains: convergence warnings
        return gpmsa.fit(data, **({"n_iter": 20, "tune": False, "seed": 0} | kw))


def test_settings_record_the_number_of_components_and_where_the_basis_came_from(data):
    """n_pc: the basis's columns (p_u = 2), not the output points (4)."""
    pca = _fit(data, n_pc=2)
    assert (pca.settings["n_pc"], pca.settings["basis"]) == (2, "pca")
    given = _fit(data, basis=np.eye(4)[:, :2])
    assert (given.settings["n_pc"], given.settings["basis"]) == (2, "given")


def test_a_tempered_continuation_left_to_choose_resumes_its_hot_copies_untuned(data):
    """tune=None at the source's ladder (numpy): each copy resumes where it stopped."""
    emu = _fit(data, temperatures=2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        more = gpmsa.fit(data, n_iter=20, seed=1, init=emu)
    assert more.settings["tune"] is False
    assert more.settings["temperatures"] == [1.0, 2.0]


def test_an_untuned_tempered_continuation_without_hot_copies_is_refused(data):
    """An untempered source records no hot copies: tune=False at a ladder cannot resume them."""
    emu = _fit(data)
    with pytest.raises(GPMSAError, match=r"^tune=False with a tempered continuation \(temper"):
        gpmsa.fit(data, n_iter=20, tune=False, seed=0, init=emu, temperatures=2)


def test_an_untuned_continuation_runs_at_its_sources_widths(data):
    """tune=False, no step_widths: the source's (here twice GPM/SA's), not GPM/SA's again."""
    default = _fit(data).settings["step_widths"]
    doubled = {k: 2.0 * np.asarray(v) for k, v in default.items()}
    emu = _fit(data, step_widths=doubled)
    more = _fit(data, init=emu)
    for k, v in doubled.items():
        np.testing.assert_array_equal(more.settings["step_widths"][k], v)
