"""A precision so small that its variance overflows float64 (lamWs = 5e-324, positive) is
refused where the emulator is built or loaded, naming it; before (found by coverage-guided
fuzzing, session 83) such a file loaded and failed at the first prediction with a nugget of
inf and numpy's overflow warning."""

import numpy as np
import pytest
from _calib_cases import road_case

import gpmsa
from gpmsa import Emulator


def _road():
    case = road_case()
    sim = gpmsa.SimData(x=case["v"][:, None], t=case["GD"][:, None], y=case["f"][:, None],
                        x_names=["v"], t_names=["GD"], y_names=["f"])  # fmt: skip
    return sim, case["sepia_calibration_only"]["fixed_emulator_params_unit_scale"]


@pytest.mark.parametrize("name", ["lamWs", "lamUz", "lamWOs"])
def test_a_precision_whose_variance_overflows_is_named(name):
    sim, params = _road()
    params = {k: np.array(v, dtype=float) for k, v in params.items()}
    params[name] = np.full_like(params[name], 5e-324)
    with pytest.raises(gpmsa.GPMSAError, match=rf"params\['{name}'\].*overflows float64"):
        Emulator.from_params(sim, params)


def test_the_smallest_precision_whose_variance_is_finite_is_taken():
    sim, params = _road()
    params = {k: np.array(v, dtype=float) for k, v in params.items()}
    params["lamWs"] = np.full_like(params["lamWs"], 1e-300)
    assert np.all(Emulator.from_params(sim, params).params["lamWs"] == 1e-300)
