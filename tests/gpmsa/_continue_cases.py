"""The small joint problem the continuation tests share (test_continue_fit_s61.py,
test_continue_widths_s63.py, test_continue_steps_s67.py, ...): 24 runs of sin(3x) + t^2, two
observations, 2 chains."""

import functools
import warnings

import numpy as np

import gpmsa


@functools.cache
def continue_data(seed: int = 1):
    """(SimData, ObsData) of the problem, its runs drawn with ``seed``."""
    rng = np.random.default_rng(seed)
    x, t = rng.random((24, 1)), rng.random((24, 1))
    data = gpmsa.SimData(x=x, t=t, y=np.sin(3 * x) + t**2, x_names=["x"], t_names=["t"])
    obs = gpmsa.ObsData(x=[[0.2], [0.7]], y=[[np.sin(0.6) + 0.16], [np.sin(2.1) + 0.16]])
    return data, obs


def continue_fit(**kw):
    """``gpmsa.fit`` of the problem, seed 0, 2 chains (short chains: no ConvergenceWarning)."""
    data, obs = continue_data()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        return gpmsa.fit(data, obs, seed=0, n_chains=2, **kw)
