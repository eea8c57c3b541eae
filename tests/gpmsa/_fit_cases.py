"""The tiny simulation-only design the fit mutation tests share (test_fit_mutation_s90.py,
test_fit_odd_s92.py, test_fit_rest_s92.py)."""

import numpy as np

import gpmsa


def five_run_data() -> gpmsa.SimData:
    """5 runs of one known input and one parameter, a 4-point output."""
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(5, 1)), rng.uniform(size=(5, 1))
    grid = np.arange(1, 5)
    return gpmsa.SimData(x=x, t=t, y=np.sin(grid * (3 * x + t)))
