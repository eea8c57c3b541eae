"""Review of session 75's gpmsa commits: the pyro backend's theta constraint asked only where
theta's prior allows it, as the numpy and torch samplers ask it (a constraint written for the
design's range may fail outside it: the joint level move's mode search steps past the unit
range's ends, where pyro called it and the run failed)."""

import warnings

import numpy as np
import pytest
from _level_cases import level_case

import gpmsa
from gpmsa.calibration.calibrate import calibration_problem

torch = pytest.importorskip("torch")
pb = pytest.importorskip("gpmsa.backends.pyro_backend")


def _table_constraint(emu):
    """A constraint read off a table over the design's range of k: it fails outside it."""
    lo, hi = emu.standardizer.t_min[0], emu.standardizer.t_max[0]

    def allowed(th) -> bool:
        if not lo <= th[0] <= hi:
            raise ValueError(f"k = {th[0]} lies outside the table")
        return bool(th[0] < lo + 0.9 * (hi - lo))

    return allowed


def test_pyro_asks_the_constraint_only_inside_thetas_prior():
    _, emu, xo, yo = level_case()
    prob = calibration_problem(emu, xo, yo, constraint=_table_constraint(emu))
    model = pb.PyroModel(prob)
    prm = {k: torch.as_tensor(v, dtype=torch.float64).unsqueeze(0).repeat(3, *([1] * v.ndim))
           for k, v in prob.init.items()}  # fmt: skip
    prm["theta"] = torch.tensor([[-0.01, 0.5], [0.5, 0.5], [0.95, 0.5]], dtype=torch.float64)
    lp = model.log_prior(prm).numpy()  # outside (0, 1): -inf, the constraint not asked
    assert lp[0] == -np.inf and np.isfinite(lp[1]) and lp[2] == -np.inf


def test_pyro_level_moves_with_a_constraint_that_fails_outside_the_range():
    """kind 2 fits the data at k below the range: its mode search steps past k's unit range."""
    _, emu, xo, yo = level_case()
    con = _table_constraint(emu)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.OutsideEmulatorWarning)
        post = gpmsa.calibrate(emu, xo, yo, n_samples=20, n_burn=0, backend="pyro", seed=1,
                               n_warmup=10, max_tree_depth=3, constraint=con,
                               theta_init=[0.4, 1])  # fmt: skip
    assert all(con([k, 1.0]) for k in post.samples["k"])
