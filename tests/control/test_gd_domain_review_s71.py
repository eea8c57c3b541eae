"""Session 71 review: a GD domain given through ``SimData(t_range=)`` that reaches 0 is refused
by the block likelihood (``ObservationModel``) with a named error instead of numpy's."""

import numpy as np
import pytest

import gpmsa
from control.errors import EmulatorMismatchError
from control.observation_model import BlockScatter, ObservationModel


@pytest.mark.parametrize("lo", [0.0, -10.0])
def test_the_block_likelihood_refuses_a_gd_domain_reaching_zero(lo):
    """SimData(t_range={"GD": (0, 600)}) is a natural range for a roughness; the block
    likelihood's grid is uniform in log GD: numpy's 'Geometric sequence cannot include zero'
    (lo = 0) or a NaN grid (lo < 0) before, a named EmulatorMismatchError now."""
    rng = np.random.default_rng(0)
    v, gd = rng.uniform(0.5, 2.0, 30), rng.uniform(50.0, 550.0, 30)
    data = gpmsa.SimData(x=v, t=gd, y=1e-3 * gd * v, x_names=["v"], t_names=["GD"],
                         t_range={"GD": (lo, 600.0)})  # fmt: skip
    params = {"betaU": [[2.0], [0.2]], "lamUz": [1.0], "lamWs": [1e5], "lamWOs": [1e5]}
    emu = gpmsa.Emulator.from_params(data, params)
    scatter = BlockScatter(speed=np.array([0.5, 2.0]), cov=np.full((2, 1, 1), 0.01))
    with pytest.raises(EmulatorMismatchError, match=r"GD domain \[.*, 600\].*positive"):
        ObservationModel(emu, scatter=scatter)
