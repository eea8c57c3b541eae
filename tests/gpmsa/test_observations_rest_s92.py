"""Mutation testing of gpmsa/calibration/observations.py, every 4th site from site 3 (session
92): exact checks of what the existing tests left open."""

from __future__ import annotations

import warnings

from gpmsa.calibration import observations as obsmod
from gpmsa.errors import OutsideEmulatorWarning


def test_warn_if_outside_without_discrepancy_names_the_emulator_only_case():
    # discrepancy defaults to False: the message says the posterior explains the miss by the
    # observation error, not that a discrepancy term (the emulator alone) must
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        obsmod.warn_if_outside(obsmod.Fit(10.0, 0.0))
    assert [w.category for w in caught] == [OutsideEmulatorWarning]
    text = str(caught[0].message)
    assert text.startswith(
        "y_obs lies 10 predictive sds from the nearest emulator prediction at x_obs over the "
        "whole theta domain (more than 5): the observation is outside what the emulator has "
        "seen. The posterior then explains it by a large observation error (small lamOs)"
    )
    assert "(the emulator alone)" not in text and "discrepancy term" not in text
