"""The ConvergenceWarning for constant draws says what they can mean for a categorical theta
(session 73: a study whose chains all started at kind 1 stayed there, P = 1 against a grid's
0.156, and the warning said only "Run longer chains")."""

from __future__ import annotations

import warnings

import pytest

from gpmsa.errors import ConvergenceWarning
from gpmsa.mcmc.diagnostics import warn_unconverged


def _record(why: str) -> dict:
    return {"n_chains": 4, "n_draws": 1200, "rhat_max": 1.01, "ess_min": 100.0,
            "flagged": {"kind": why}, "max_rhat": ["", None]}  # fmt: skip


def test_constant_draws_point_at_stuck_levels_and_tempering():
    with pytest.warns(ConvergenceWarning, match="never leave the levels they started at") as rec:
        warn_unconverged(_record("constant draws (no proposal accepted)"), "gpmsa.calibrate_study")
    assert "temperatures=" in str(rec[0].message)


def test_other_reasons_keep_their_message():
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        warn_unconverged(_record("ESS 40 < 100"), "gpmsa.fit")
    assert len(rec) == 1 and "never leave" not in str(rec[0].message)
