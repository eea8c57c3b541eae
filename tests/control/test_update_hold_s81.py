"""An update interval longer than ``max_age_s``: between two updates a controller holds an
estimate older than max_age_s that never turns stale, so the settings warn."""

import warnings

import pytest

from control import PAPER_WINDOW, BCRSettings, ControlWarning


def test_an_update_interval_longer_than_max_age_warns_with_the_remedy():
    with pytest.warns(ControlWarning, match=r"update_every \(1000 samples, 8\.33333 s at 120 Hz\)"
                      r".*max_age_s \(5 s\).*at most 600 samples"):  # fmt: skip
        BCRSettings(method="window", feature=PAPER_WINDOW, update_every=1000)


def test_intervals_within_max_age_are_quiet():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        BCRSettings()
        BCRSettings(method="window", feature=PAPER_WINDOW)
        BCRSettings(method="window", feature=PAPER_WINDOW, update_every=600)
        BCRSettings(method="window", feature=PAPER_WINDOW, update_every=1000, max_age_s=10.0)
