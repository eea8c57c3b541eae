"""A Calibrator's MCMC update runs fresh chains on each update's observations: the options of an
offline calibration's continuation (``init=`` a Posterior, ``append=True``) are refused when the
Calibrator is built, saying so; start rules and ``append=False`` pass as before."""

import numpy as np
import pytest
from _calib_cases import road_emulator

import gpmsa


@pytest.fixture(scope="module")
def emu():
    return road_emulator()


@pytest.mark.parametrize(
    "opts, named",
    [
        ({"init": gpmsa.Posterior({"GD": np.zeros(3)})}, "mcmc_options['init']"),
        ({"append": True}, "mcmc_options['append']"),
        ({"init": gpmsa.Posterior({"GD": np.zeros(3)}), "append": True}, "mcmc_options['init']"),
    ],
)
def test_continuation_options_refused_at_construction(emu, opts, named):
    with pytest.raises(gpmsa.GPMSAError, match="fresh chains") as exc:
        gpmsa.Calibrator(emu, method="mcmc", mcmc_options=opts)
    assert named in str(exc.value)
    assert "gpmsa.calibrate" in str(exc.value)  # where a continuation belongs


def test_another_object_as_init_refused_at_construction(emu):
    with pytest.raises(gpmsa.GPMSAError, match=r"start rule.*got Emulator"):
        gpmsa.Calibrator(emu, method="mcmc", mcmc_options={"init": emu})


@pytest.mark.parametrize("opts", [{"init": "gpmsa", "fast": False}, {"append": False}, {}])
def test_start_rules_and_no_append_still_built(emu, opts):
    cal = gpmsa.Calibrator(emu, method="mcmc", mcmc_options=opts)
    assert cal.mcmc_options == opts
