"""A torch Calibrator leaves a ``chain_groups`` that is not the integer 1 to its update, as its
docstring says (session 83). Before: ``chain_groups=1.0`` with ``n_jobs=2`` read as one group,
and the Calibrator was refused with "n_jobs=2 with chain_groups=1: ... give chain_groups=2",
where the update (and ``gpmsa.calibrate``) refuse the float chain_groups itself."""

import pytest
from _calib_cases import road_emulator, road_obs

from gpmsa import Calibrator, GPMSAError
from tests._extras import TORCH

GROUPS = r"chain_groups must be an integer in \[1, n_chains=2\], got 1.0"


@TORCH
@pytest.mark.parametrize("n_jobs", [2, 0])
def test_a_float_chain_groups_is_refused_by_name_not_as_one_group(n_jobs):
    options = {"n_jobs": n_jobs, "chain_groups": 1.0, "n_chains": 2, "n_samples": 8, "n_burn": 2}
    cal = Calibrator(road_emulator(), backend="torch", mcmc_options=options)
    with pytest.raises(GPMSAError, match=GROUPS):
        cal.update(*road_obs())
