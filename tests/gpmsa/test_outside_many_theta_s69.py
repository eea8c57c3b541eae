"""The outside-the-emulator check with three or more calibration parameters (session 69).

For q >= 3 the check probes 3^q lattice points and 256 Sobol points; informative data (a
functional output, a few experiments) pin theta far more tightly than those points' spacing,
so data made by the simulator at an interior theta read 12-18 predictive sds "outside what the
emulator has seen" (an OutsideEmulatorWarning telling the user to check the units) while the
posterior was right. The check now looks closer (a local search from the best probe points)
before it warns.
"""

import warnings

import numpy as np
import pytest
from _outside_cases import X_OBS, simulator, three_parameter_emulator

import gpmsa
from gpmsa.calibration.calibrate import observation_fit
from gpmsa.calibration.observations import OUTSIDE_SDS, reduce

TRUTH = np.array([0.37, 0.61, 0.23])


@pytest.fixture(scope="module")
def emulator():
    return three_parameter_emulator(corners=True)


def _observed(noise: float, seed: int = 0) -> np.ndarray:
    y = simulator(X_OBS[:, 0], np.tile(TRUTH, (3, 1)))
    return y + noise * np.random.default_rng(seed).standard_normal(y.shape)


@pytest.mark.parametrize("noise", [0.01, 0.002])
def test_simulator_data_inside_with_three_parameters(emulator, noise):
    data = reduce(emulator, X_OBS, _observed(noise))
    fit = observation_fit(emulator, data, [emulator.params])
    assert fit.outside_sds < OUTSIDE_SDS
    with warnings.catch_warnings():
        warnings.simplefilter("error", gpmsa.OutsideEmulatorWarning)
        post = gpmsa.calibrate(emulator, X_OBS, _observed(noise), n_samples=400, n_burn=100,
                               seed=0)  # fmt: skip
    assert post.info["outside_sds"] < OUTSIDE_SDS
    for name, truth in zip(emulator.t_names, TRUTH, strict=True):
        assert abs(post.mean(name) - truth) < 0.03


def test_units_error_still_warned_with_three_parameters(emulator):
    y = 100.0 * _observed(0.002)  # centimetres for metres
    data = reduce(emulator, X_OBS, y)
    assert observation_fit(emulator, data, [emulator.params]).outside_sds > 10 * OUTSIDE_SDS
    with pytest.warns(gpmsa.OutsideEmulatorWarning, match="predictive sds"):
        gpmsa.calibrate(emulator, X_OBS, y, n_samples=200, n_burn=50, seed=0)
