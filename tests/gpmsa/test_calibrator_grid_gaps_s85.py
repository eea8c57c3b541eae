"""Calibrator grid laws that mutation testing (session 85, part 5) found unchecked: a refined
one-parameter grid keeps the node where a gridded prior is zero inside the refined region
(`grid.zero_edges`), and a constrained two-parameter draw pairs its lamOs with the grid node
nearest its own theta (each axis's node from its own parameter, on a refined grid whose axes
differ in size and parameters whose native ranges differ)."""

from __future__ import annotations

import warnings
from functools import cache

import numpy as np
import pytest
from scipy.integrate import cumulative_trapezoid
from test_grid_one_param_edges_s57 import observations, vague_lamos_emulator

import gpmsa
from gpmsa import Calibrator
from gpmsa.calibration.observations import reduce
from gpmsa.fitting.emulator import Emulator

N_GRID = 129


def spied(cal: Calibrator) -> dict:
    """What ``cal._posterior`` is given at its next update: the unit-scale axes and the lamOs
    marginals of the final grid."""
    seen: dict = {}
    inner = cal._posterior

    def spy(axes, free, ok, margs, key, prior):
        seen.update(axes=axes, margs=margs)
        return inner(axes, free, ok, margs, key, prior)

    cal._posterior = spy
    return seen


@pytest.mark.parametrize(("n", "node"), [(2, 51), (2, 52), (3, 52)])
def test_a_refined_grid_keeps_a_gridded_priors_zero_inside_the_peak(n, node):
    """A gridded prior zero at one node next to a peak narrower than a node spacing (sd about
    0.1 spacing): the refined region spans that node, and its grid must keep it (and the lines
    either side, where the prior's linear ramp ends). Dropping them (no `zero_edges`) spread the
    neighbouring refined nodes' density over it, 3e-6 to 4e-5 of the peak where the prior is
    zero. The cdf there is the dense reference's (the Calibrator's own likelihood and prior
    interpolation on the fixed grid plus 20001 nodes over the six cells around it) within 5e-5."""
    emu = vague_lamos_emulator()
    x, y = observations(n)
    cal = Calibrator(emu, method="grid", n_grid=N_GRID)
    prior = np.zeros(N_GRID)
    prior[node] = -np.inf
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        post = cal.update(x, y, prior=prior)
    assert post.info["refined"]
    std = emu.standardizer
    span, low = std.t_max[0] - std.t_min[0], std.t_min[0]
    unit = np.linspace(0.0, 1.0, N_GRID)
    zero = unit[node] * span + low
    gm = post.grids["t"]
    assert gm.nodes[0] < zero < gm.nodes[-1]  # inside the refined region
    assert np.isin(unit[node - 1 : node + 2] * span + low, gm.nodes).all()
    assert np.interp(zero, gm.nodes, gm.density) == 0.0

    u = np.unique(np.concatenate([unit, np.linspace(unit[node - 3], unit[node + 3], 20001)]))
    theta = u[:, None]
    data = reduce(emu, x, y, False)
    logp = cal._combine(cal._marginals(data, theta)) + cal._theta_prior_at(theta, prior)
    cdf = cumulative_trapezoid(np.exp(logp - logp.max()), u * span + low, initial=0.0)
    assert float(gm.cdf(zero)) == pytest.approx(np.interp(zero, u * span + low, cdf / cdf[-1]),
                                                abs=5e-5)  # fmt: skip


@cache
def wide_b_emulator() -> Emulator:
    """y = sin(2 x + 1.5 a) + 0.08 b x, a in [0, 1] and b in [0, 10]: native ranges unlike."""
    rng = np.random.default_rng(7)
    x = rng.uniform(0, 1, 60)
    t = rng.uniform(0, 1, (60, 2)) * [1.0, 10.0]
    y = np.sin(2.0 * x + 1.5 * t[:, 0]) + 0.08 * t[:, 1] * x
    sim = gpmsa.SimData(x=x[:, None], t=t, y=y[:, None], x_names=["x"], t_names=["a", "b"])
    params = {"betaU": [[1.0], [1.5], [0.8]], "lamUz": [1.0], "lamWs": [5000.0],
              "lamWOs": [5000.0]}  # fmt: skip
    return Emulator.from_params(sim, params)


def test_constrained_lamos_draws_follow_their_own_node():
    """Three noisy observations near a = 0.5, b = 5, cut by a + b / 10 <= 1: a refined grid
    (94 x 97 nodes) over which lamOs's conditional moves (its mean log differs by about 0.6
    between the halves of either parameter's draws). In each half the mean log lamOs of the
    draws is the mean, over the draws, of E[log lamOs | the node nearest the draw] (the grid's
    own conditionals) within 0.05 (its sampling error about 0.01); a node index from the wrong
    parameter or axis size put it 1.4 to 4 off."""
    emu = wide_b_emulator()
    x = np.linspace(0.05, 0.95, 3)[:, None]
    y = np.sin(2 * x + 0.75) + 0.4 * x + 0.1 * np.random.default_rng(1).standard_normal(x.shape)
    cal = Calibrator(emu, n_draws=20_000, seed=3, constraint=lambda th: th[0] + th[1] / 10 <= 1.0)
    seen = spied(cal)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        post = cal.update(x, y)
    sizes = [a.size for a in seen["axes"]]
    assert post.info["refined"] and sizes[0] != sizes[1]
    std = emu.standardizer
    native = [a * (std.t_max[k] - std.t_min[k]) + std.t_min[k] for k, a in enumerate(seen["axes"])]
    s = post.samples
    assert np.all(s["a"] + s["b"] / 10 <= 1.0)
    near = [np.abs(native[k][None, :] - s[name][:, None]).argmin(axis=1)
            for k, name in enumerate(("a", "b"))]  # fmt: skip
    (margs,) = seen["margs"]
    expected = np.exp(margs.log_cond(near[0] * sizes[1] + near[1])) @ margs.log_lam
    drawn = np.log(s["lamOs"])
    for name in ("a", "b"):
        low = s[name] < np.median(s[name])
        assert expected[~low].mean() - expected[low].mean() > 0.4  # lamOs moves over the grid
        for half in (low, ~low):
            assert drawn[half].mean() == pytest.approx(expected[half].mean(), abs=0.05)
