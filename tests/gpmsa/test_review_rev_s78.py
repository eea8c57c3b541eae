"""A Calibrator's grid work done in place (triangular solves on their right-hand sides, the lamOs
integrand in blocks of nodes) leaves every array it is given or keeps: a Calibrator updated on
other observations in between gives a fresh one's posterior bit for bit (two parameters, the
emulator's draws, one parameter's prepared refined grid, a multivariate output, a categorical
parameter with and without a continuous one; one datum and several), and the blocks give the
one pass's numbers bit for bit, one node a block and blocks that do not divide the nodes."""

from __future__ import annotations

import functools
import warnings

import numpy as np
import pytest
from _calib_cases import road_emulator, two_param_emulator, vector_emulator, with_draws

import gpmsa
from gpmsa import Calibrator
from gpmsa.calibration import model
from gpmsa.calibration.model import GridPredictor, chebyshev_plan, lamos_marginal
from gpmsa.calibration.observations import fixed_gp, reduce, theta_probe

X5 = np.linspace(0.05, 0.95, 5)[:, None]
PARAMS = {"lamUz": [1.0], "lamWs": [1e3], "lamWOs": [1e3]}


@functools.cache
def _levels(continuous: bool) -> gpmsa.Emulator:
    """A categorical parameter (levels 0, 1, 2), with a continuous one or alone."""
    rng = np.random.default_rng(0)
    x, t0, t1 = rng.random(45), np.arange(45) % 3, rng.random(45)
    y = x + np.array([0.0, 1.0, -0.7])[t0] + (0.3 * t1 if continuous else 0.0)
    t = np.column_stack([t0, t1]) if continuous else t0
    sim = gpmsa.SimData(x, t, y, t_categorical=[0])
    return gpmsa.Emulator.from_params(sim, {"betaU": [[1.0]] * (3 if continuous else 2),
                                            **PARAMS})  # fmt: skip


def _case(name: str):
    """(make a Calibrator, observations A, observations B)."""
    a = (X5, np.sin(2.0 * X5 + 0.45) + 0.48 * X5)
    if name == "two":
        return lambda: Calibrator(two_param_emulator()), a, (X5[:1], a[1][:1] + 0.2)
    if name == "draws":
        emu = with_draws(two_param_emulator(), n=2)
        return (functools.partial(Calibrator, emu, emulator_params="draws", n_grid=33),
                (X5[::2], a[1][::2]), (X5[1:3], a[1][1:3] - 0.1))  # fmt: skip
    if name == "road":  # one parameter: the refined axis's prepared predictors
        v = np.linspace(0.6, 1.9, 40)[:, None]
        y = 0.02 * 410 * v**1.6 * (1 + 0.005 * np.random.default_rng(0).standard_normal(v.shape))
        one = ([[1.689463276395526]], [[9.467654926608041]])  # refined on the prepared axis
        return lambda: Calibrator(road_emulator()), (v, y), one
    if name == "vector":  # p_u = 2: d = 2 n
        x = np.array([[0.3], [0.7]])
        y = 1.4 * np.sin(np.pi * np.linspace(0, 1, 8)[None, :] * (0.5 + x)) + 0.12
        return lambda: Calibrator(vector_emulator(), n_grid=33), (x, y), (x[:1], y[:1] + 0.3)
    emu = _levels(name == "level_continuous")
    y = X5 + 1.0 + (0.15 if name == "level_continuous" else 0.0)
    return lambda: Calibrator(emu, n_grid=33), (X5, y), (X5[:1], y[:1] - 1.5)


def _numbers(cal: Calibrator, x, y) -> list[np.ndarray]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # (coarse grids, observations outside)
        post = cal.update(x, y)
        loglik = cal.log_likelihood_grid(x, y)[1]
    grids = [np.asarray(post.grids[k].density) for k in sorted(post.grids)]
    return [loglik, np.asarray(post.info["outside_sds"]), np.asarray(post.info["n_nodes"]), *grids]


@pytest.mark.parametrize("name", ["two", "draws", "road", "vector", "level_continuous", "level"])
def test_a_calibrator_reused_gives_a_fresh_ones_posterior_bit_for_bit(name):
    make, a, b = _case(name)
    reused = make()
    first = _numbers(reused, *a)
    other = _numbers(reused, *b)
    again = _numbers(reused, *a)
    if name == "road":  # the second observation's refinement read the prepared predictors
        assert other[2] == reused._refined[0].size
    for got, want in [(first, _numbers(make(), *a)), (again, first), (other, _numbers(make(), *b))]:
        assert len(got) == len(want)
        for g, w in zip(got, want, strict=True):
            np.testing.assert_array_equal(g, w)


@pytest.mark.parametrize("chunk", [1, 997])
def test_the_lamos_integrand_in_blocks_is_the_one_pass_bit_for_bit(monkeypatch, chunk):
    """One theta node a block (S x d > _CHUNK) and blocks that leave a remainder: the
    log-likelihood on the grid and the posterior are those of one block, to the bit."""
    make, a, _ = _case("two")
    whole = _numbers(make(), *a)
    monkeypatch.setattr(model, "_CHUNK", chunk)
    for g, w in zip(_numbers(make(), *a), whole, strict=True):
        np.testing.assert_array_equal(g, w)


def test_the_in_place_solves_leave_their_inputs():
    """FixedGP.predict, GridPredictor (its Chebyshev products) and lamos_marginal (the
    whitening) leave the GP's factors, the kept products and the predictive they are given."""
    emu = two_param_emulator()
    data = reduce(emu, X5, np.sin(2.0 * X5 + 0.45) + 0.48 * X5, False)
    gp = fixed_gp(emu)
    kept = [gp.alpha[0].copy(), gp.chol[0].copy()]
    theta = theta_probe(2)[::7]
    mean, cov = gp.predict(data.x, theta)
    mean2, cov2 = gp.predict(data.x, theta)
    np.testing.assert_array_equal(mean, mean2)
    np.testing.assert_array_equal(cov, cov2)
    pred = GridPredictor(gp, theta, chebyshev_plan(gp))
    H = [h.copy() for h in pred.H]
    pred.predict(data.x)
    for h, h0 in zip(pred.H, H, strict=True):
        np.testing.assert_array_equal(h, h0)
    G, d = mean.shape[0], data.z.size
    m, c = mean.reshape(G, d), cov.reshape(G, d, d)  # (p_u = 1: component-major is as is)
    m0, c0 = m.copy(), c.copy()
    lamos_marginal(m, c, data.z, data.obs_chol, data.lamos)
    np.testing.assert_array_equal(m, m0)
    np.testing.assert_array_equal(c, c0)
    np.testing.assert_array_equal(gp.alpha[0], kept[0])
    np.testing.assert_array_equal(gp.chol[0], kept[1])
