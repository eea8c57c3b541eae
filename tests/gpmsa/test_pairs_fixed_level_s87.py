"""A categorical theta held off its levels (`fixed=`), found by an all-pairs sweep of the
options: the refusal named the parameter but neither its levels nor the value given, where
``theta_init=``'s names both; it now names them, as native codes, in ``calibrate`` and
``fit`` alike."""

import warnings
from functools import cache

import numpy as np
import pytest

import gpmsa
from gpmsa import GPMSAError

NOT_A_LEVEL = (r"^fixed theta: categorical calibration parameter kind must be one of its "
               r"training levels \[2, 4, 6\], got 3\.5$")  # fmt: skip


def _case() -> tuple[gpmsa.SimData, gpmsa.ObsData]:
    """20 runs of a scalar output over x, a categorical theta 'kind' (codes 2, 4, 6), and k."""
    rng = np.random.default_rng(0)
    x, k = rng.uniform(size=(20, 1)), rng.uniform(size=(20, 1))
    kind = 2.0 + 2.0 * (np.arange(20) % 3)[:, None]
    sim = gpmsa.SimData(x=x, t=np.hstack([kind, k]), y=np.sin(x + 0.1 * kind + k),
                        t_names=["kind", "k"], t_categorical=["kind"])  # fmt: skip
    return sim, gpmsa.ObsData(x=[[0.3], [0.6]], y=[[0.9], [1.1]])


@cache
def _emulator() -> gpmsa.Emulator:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)  # 20 sweeps: a short chain
        return gpmsa.fit(_case()[0], n_iter=20, seed=0, tune=False)


def test_calibrate_names_the_levels_and_the_value_held_off_them():
    obs = _case()[1]
    with pytest.raises(GPMSAError, match=NOT_A_LEVEL):
        gpmsa.calibrate(_emulator(), obs, n_samples=20, n_burn=5, seed=0,
                        fixed={"theta": {"kind": 3.5}})  # fmt: skip


def test_a_joint_fit_names_them_too():
    sim, obs = _case()
    with pytest.raises(GPMSAError, match=NOT_A_LEVEL):
        gpmsa.fit(sim, obs, n_iter=20, seed=0, tune=False, fixed={"theta": [3.5, 0.5]})
