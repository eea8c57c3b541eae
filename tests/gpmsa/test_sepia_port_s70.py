"""Porting SEPIA workflows (session 70): create_D_basis('linear') on ragged observations."""

import numpy as np
import pytest

import gpmsa


def _ragged():
    rng = np.random.default_rng(0)
    s = np.linspace(0.0, 1.0, 11)
    x, t = rng.uniform(size=(12, 1)), rng.uniform(size=(12, 1))
    sim = gpmsa.SimData(x=x, t=t, y=np.sin(3 * x + s) + t * s, index=s)
    grids = [s[[0, 3, 5, 10]], s[[1, 4, 9]]]  # largest |index| 1.0 and 0.9
    ys = [np.sin(3 * 0.4 + g) + 0.5 * g for g in grids]
    return sim, gpmsa.ObsData(x=[[0.4], [0.6]], y=ys, index=grids)


def test_linear_on_ragged_grids_names_the_per_experiment_basis():
    # SEPIA's create_D_basis('linear') on ragged y_ind_obs builds [1, y_ind_j] per experiment,
    # scaled by one factor; the refusal must name that port, not only 'constant'
    sim, obs = _ragged()
    with pytest.raises(gpmsa.GPMSAError, match=r"discrepancy=\[np\.column_stack"):
        gpmsa.prepare(sim, obs, discrepancy="linear")
    bases = [np.column_stack([np.ones(g.size), g]) for g in obs.grids]
    prep = gpmsa.prepare(sim, obs, discrepancy=bases)  # the named port is accepted
    D = prep.problem.obs.D
    assert len(D) == 2 and all(d.shape[1] == 2 for d in D)
    ratio = np.concatenate([d[:, 1] / d[:, 0] for d in D])  # one scale: the index itself
    assert np.allclose(ratio, np.concatenate(obs.grids))
