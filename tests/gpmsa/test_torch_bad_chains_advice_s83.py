"""The torch backend's n_jobs refusal does not call a bad n_chains "one chain" (session 83
review). Before: ``Calibrator(..., backend="torch", mcmc_options={"n_jobs": 2, "n_chains": 0})``
was told "n_chains=0 is one chain, which runs in one process: leave n_jobs out"."""

import pytest

import gpmsa
from tests._extras import TORCH


@TORCH
@pytest.mark.parametrize("n_chains", [0, -2])
def test_a_bad_n_chains_is_not_called_one_chain(n_chains):
    from gpmsa.backends import torch_backend

    with pytest.raises(gpmsa.GPMSAError, match="n_jobs=2 with chain_groups=1") as err:
        torch_backend.check_n_jobs(2, 1, n_chains)
    assert "is one chain" not in str(err.value)
    assert "give chain_groups=2 (or more)" in str(err.value)
