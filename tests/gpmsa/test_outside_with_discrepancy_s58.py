"""The warning for an observation far from every emulator prediction said that "theta falls back
towards its prior" also when a discrepancy model was calibrated (found in a SEPIA-user
walkthrough: theta did not fall back, the discrepancy explained the offset). With a
discrepancy it now says that the discrepancy term must explain the difference."""

import warnings

import pytest
from _calib_cases import road_emulator

from gpmsa import ConvergenceWarning, OutsideEmulatorWarning, calibrate

X, Y = [[1.0], [1.25], [1.5]], [[57.5], [62.1], [66.0]]  # the road case's outputs + 50


def test_with_a_discrepancy_the_warning_names_it():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        calibrate(road_emulator(), X, Y, discrepancy="constant", n_samples=300, n_burn=100,
                  seed=1)  # fmt: skip
    (warning,) = [w for w in caught if issubclass(w.category, OutsideEmulatorWarning)]
    text = str(warning.message)
    assert "(the emulator alone)" in text and "discrepancy term" in text
    assert "falls back towards its prior" not in text


@pytest.mark.filterwarnings("ignore", category=ConvergenceWarning)
def test_without_one_it_says_theta_falls_back():
    with pytest.warns(OutsideEmulatorWarning, match="falls back towards its prior") as caught:
        calibrate(road_emulator(), X, Y, n_samples=300, n_burn=100, seed=1)
    assert all("discrepancy" not in str(w.message) for w in caught)
