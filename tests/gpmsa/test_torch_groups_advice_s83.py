"""The torch backend's refusal of n_jobs with one chain group advises a chain_groups that the
chains allow (session 83). Before: ``gpmsa.fit(..., backend="torch", n_jobs=2)`` at the default
n_chains=1 was told "give chain_groups=2 (or more)", and chain_groups=2 was then refused:
"chain_groups must be an integer in [1, n_chains=1], got 2"."""

import pytest
from _calib_cases import road_emulator, road_obs

import gpmsa
from tests._extras import TORCH

SHORT = {"backend": "torch", "n_samples": 4, "n_burn": 2, "seed": 0}


@TORCH
def test_one_chain_is_told_to_leave_n_jobs_out_not_to_add_groups():
    x, y = road_obs()
    with pytest.raises(gpmsa.GPMSAError, match="n_jobs=2 with chain_groups=1") as err:
        gpmsa.calibrate(road_emulator(), x, y, n_jobs=2, **SHORT)
    assert "give chain_groups=2 (or more)" not in str(err.value)
    assert "leave n_jobs out" in str(err.value)
    with pytest.raises(gpmsa.GPMSAError, match="n_chains=1 is one chain") as err:
        gpmsa.Calibrator(road_emulator(), backend="torch", mcmc_options={"n_jobs": 2})


@TORCH
def test_the_advised_chain_groups_is_accepted():
    x, y = road_obs()
    with pytest.raises(gpmsa.GPMSAError, match="n_jobs=2 with chain_groups=1") as err:
        gpmsa.calibrate(road_emulator(), x, y, n_chains=2, n_jobs=2, **SHORT)
    assert "give chain_groups=2 to sample in 2 processes" in str(err.value)
    with pytest.warns(gpmsa.ConvergenceWarning):  # (4 draws a chain: too few to judge)
        post = gpmsa.calibrate(road_emulator(), x, y, n_chains=2, n_jobs=2, chain_groups=2,
                               **SHORT)  # fmt: skip
    assert post.info["n_chains"] == 2
