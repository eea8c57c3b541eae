"""Invariances a correct implementation keeps: the order of experiments, of x columns given by
name, of each experiment's index points, and the index columns of an ObsData given as a
table by name (read by the simulation index's names, as SimData reads its own index)."""

from functools import cache

import numpy as np
import pandas as pd
import pytest

import gpmsa
from gpmsa.errors import GPMSAError
from gpmsa.fitting.emulator import Emulator


@cache
def _index_emulator() -> Emulator:
    """A functional output on a (time, angle) index of 4 x 3 points over the unit square."""
    rng = np.random.default_rng(9)
    x, t = rng.uniform(0, 1, 30), rng.uniform(0, 1, 30)
    tg, ag = np.meshgrid(np.linspace(0, 1, 4), np.linspace(0, 1, 3), indexing="ij")
    pts = np.column_stack([tg.ravel(), ag.ravel()])
    y = (1 + t[:, None]) * np.sin(2 * pts[None, :, 0] * (0.5 + x[:, None])) + t[:, None] * pts[
        None, :, 1
    ]
    index = pd.DataFrame(pts, columns=["time", "angle"])
    sim = gpmsa.SimData(x=x[:, None], t=t[:, None], y=y, index=index, x_names=["x"],
                        t_names=["t"])  # fmt: skip
    params = {"betaU": [[1.0, 1.0], [1.0, 1.0]], "lamUz": [1.0, 1.0], "lamWs": [5e3, 5e3],
              "lamWOs": [5e3]}  # fmt: skip
    return Emulator.from_params(sim, params, n_pc=2)


POINTS = np.array([[0.1, 0.7], [0.5, 0.2], [0.9, 0.4]])  # (time, angle), off the diagonal
VALUES = 1.4 * np.sin(1.8 * POINTS[:, 0]) + 0.4 * POINTS[:, 1]


def _loglik(obs) -> np.ndarray:
    return gpmsa.Calibrator(_index_emulator(), seed=0).log_likelihood_grid(obs)[1]


def test_an_index_table_is_read_by_the_simulation_index_names_in_any_column_order():
    arrays = _loglik(gpmsa.ObsData([[0.4]], [VALUES], index=[POINTS]))
    swapped = pd.DataFrame(POINTS[:, ::-1], columns=["angle", "time"])
    named = _loglik(gpmsa.ObsData([[0.4]], [VALUES], index=[swapped]))
    np.testing.assert_array_equal(named, arrays)  # read by position before: 15.7 nats off


def test_one_index_table_for_every_experiment_is_taken_as_its_array_is():
    table = pd.DataFrame(POINTS[:, ::-1], columns=["angle", "time"])
    arrays = _loglik(gpmsa.ObsData([[0.4], [0.6]], [VALUES, VALUES], index=POINTS))
    named = _loglik(gpmsa.ObsData([[0.4], [0.6]], [VALUES, VALUES], index=table))  # refused
    np.testing.assert_array_equal(named, arrays)


def test_an_index_table_of_other_names_is_refused_naming_them():
    table = pd.DataFrame(POINTS, columns=["angle", "speed"])
    with pytest.raises(GPMSAError, match=r"index\[0\] has the columns \['angle', 'speed'\]"):
        _loglik(gpmsa.ObsData([[0.4]], [VALUES], index=[table]))


def test_full_prediction_reads_the_index_and_grid_tables_by_name():
    emu = _index_emulator()
    obs = gpmsa.ObsData([[0.4]], [VALUES], index=[POINTS])
    swapped = pd.DataFrame(POINTS[:, ::-1], columns=["angle", "time"])
    named = gpmsa.ObsData([[0.4]], [VALUES], index=[swapped])
    post = gpmsa.Calibrator(emu, seed=0).update(obs)
    grid = np.array([[0.2, 0.3], [0.6, 0.9]])
    a = gpmsa.full_prediction(emu, obs, [[0.5]], posterior=post, grid=grid, n_draws=20, seed=1)
    b = gpmsa.full_prediction(
        emu, named, [[0.5]], posterior=post, seed=1, n_draws=20,
        grid=pd.DataFrame(grid[:, ::-1], columns=["angle", "time"]),
    )  # fmt: skip
    np.testing.assert_array_equal(b.mu, a.mu)  # the layout the posterior recorded: the same
    np.testing.assert_array_equal(b.eta, a.eta)


def test_experiments_points_and_x_columns_in_another_order_give_the_same_likelihood():
    """Reordering experiments, each experiment's index points (with its values and
    precisions), and x columns given by name: the grid log-likelihood to round-off."""
    rng = np.random.default_rng(5)
    m, grid = 40, np.linspace(0, 1, 10)
    x, t = rng.uniform(0, 1, (m, 2)), rng.uniform(0, 1, m)
    y = (1 + t[:, None]) * np.sin(np.pi * grid * (0.5 + x[:, :1])) + 0.5 * x[:, 1:] * grid
    sim = gpmsa.SimData(x=x, t=t[:, None], y=y, index=grid, x_names=["a", "b"], t_names=["t"])
    params = {"betaU": np.ones((3, 2)), "lamUz": [1.0, 1.0], "lamWs": [5e3, 5e3], "lamWOs": [5e3]}
    cal = gpmsa.Calibrator(Emulator.from_params(sim, params, n_pc=2), seed=0)
    xo = rng.uniform(0.1, 0.9, (3, 2))
    yo = 1.4 * np.sin(np.pi * grid * (0.5 + xo[:, :1])) + 0.5 * xo[:, 1:] * grid
    sub = [np.array([0, 2, 3, 5, 9]), np.array([1, 4, 6]), np.array([0, 1, 2, 7, 8])]
    prec = [np.linspace(50.0, 200.0, s.size) for s in sub]
    ref = cal.log_likelihood_grid(gpmsa.ObsData(
        xo, [yo[j][s] for j, s in enumerate(sub)], index=[grid[s] for s in sub], precision=prec
    ))[1]  # fmt: skip
    order, shuffles = [2, 0, 1], [rng.permutation(s.size) for s in sub]
    moved = gpmsa.ObsData(
        pd.DataFrame(xo[order], columns=["a", "b"])[["b", "a"]],
        [yo[j][sub[j][shuffles[j]]] for j in order],
        index=[grid[sub[j][shuffles[j]]] for j in order],
        precision=[prec[j][shuffles[j]] for j in order],
    )  # fmt: skip
    np.testing.assert_allclose(cal.log_likelihood_grid(moved)[1], ref, rtol=1e-12)
