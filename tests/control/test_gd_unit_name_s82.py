"""Review of 30bb922 (session 82): the GD-unit check (`control.bcr.check_gd_unit`) reads a
parameter named GD only; an emulator of a user's own roughness measure under another name, whose
domain lies below 1 in its own unit, builds a BCR and passes `check_emulator`."""

import numpy as np
import pytest

import control
import gpmsa
from control import BCR, PAPER_WINDOW, EmulatorMismatchError, ObservationModel
from control.observation_model import BlockScatter

SCATTER = BlockScatter(speed=np.array([0.5, 2.0]), cov=np.full((2, 1, 1), 0.01))


def _emulator(name: str, lo: float, hi: float):
    """A small emulator of (v, ``name``) over ``name`` in [lo, hi]."""
    rng = np.random.default_rng(0)
    v, theta = rng.uniform(0.5, 2.0, 30), rng.uniform(lo, hi, 30)
    data = gpmsa.SimData(x=v, t=theta, y=theta * v, x_names=["v"], t_names=[name])
    params = {"betaU": [[2.0], [0.2]], "lamUz": [1.0], "lamWs": [1e5], "lamWOs": [1e5]}
    return gpmsa.Emulator.from_params(data, params)


def test_a_roughness_measure_of_another_name_is_not_read_as_gd_in_m3():
    """Before: refused as "the emulator's IRI domain [0.331213, 0.860426] lies below 1: IRI is
    Gd(n0) in units of 1e-6 m^3 ... train it on IRI x 1e6", with no way to use it."""
    emu = _emulator("IRI", 0.3, 0.9)  # m/km: a smooth floor's
    assert BCR(ObservationModel(emu, scatter=SCATTER)).gd_name == "IRI"
    assert BCR(gpmsa.Calibrator(emu), method="window", feature=PAPER_WINDOW).gd_range[1] < 1.0
    control.check_emulator(emu)


@pytest.mark.parametrize("name", ["GD", "gd", "Gd"])
def test_gd_in_m3_is_refused_under_any_case_of_its_name(name):
    emu = _emulator(name, 2e-4, 6e-4)
    with pytest.raises(EmulatorMismatchError, match=rf"{name} domain \[0\.0002.*m\^3"):
        BCR(ObservationModel(emu, scatter=SCATTER))
    with pytest.raises(EmulatorMismatchError, match=r"trained on GDs in m\^3"):
        control.check_emulator(emu)
