"""A Calibrator with ``emulator_params="draws"`` given a backend sampler's option: the remedy
leaves it out. Before, it advised ``mcmc_options['fast'] = False`` or ``backend='torch'``, each
of which the Calibrator then refused ("emulator_params='draws' needs the fast numpy
sampler", "... needs backend='numpy'")."""

import pytest
from _calib_cases import road_emulator

from gpmsa import Calibrator, GPMSAError


@pytest.mark.parametrize("where", ["argument", "mcmc_options"])
def test_the_draws_samplers_refusal_advises_what_it_takes(where):
    draws = {"emulator_params": "draws"}
    options = {"step_widths": {"theta": 0.1}, **(draws if where == "mcmc_options" else {})}
    given = draws if where == "argument" else {}
    with pytest.raises(GPMSAError) as err:
        Calibrator(road_emulator(), method="mcmc", mcmc_options=options, **given)
    message = str(err.value)
    assert "['step_widths']" in message and "emulator_params='draws'" in message
    assert "fast'] = False" not in message and "torch" not in message
    assert "leave them out" in message
