"""Messages naming an observation's point of the output index, or the range of a one-column
index, show the index's column names where the simulation data gave them
(``SimData(index_names=)``): "(time 1.2, angle 0)" rather than "(1.2, 0)"; without names, as
before."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import gpmsa

TIME, ANGLE = np.linspace(0.0, 1.0, 4), np.linspace(0.0, 2.0, 5)
POINTS = np.column_stack([np.repeat(TIME, 5), np.tile(ANGLE, 4)])  # (20, 2)
GRID = np.linspace(0.0, 1.0, 8)
PARAMS = {"betaU": [[1, 1], [1, 1]], "lamUz": [1, 1], "lamWs": [1e3] * 2, "lamWOs": [1e3]}
X_OBS = [[0.3], [0.7]]
pytestmark = pytest.mark.filterwarnings("ignore::gpmsa.ConvergenceWarning")


def _sim(index, names=None) -> gpmsa.SimData:
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(12, 1)), rng.uniform(size=(12, 1))
    cols = index.reshape(len(index), -1)
    y = np.sin(np.pi * x * cols[:, 0]) * (1 + t) + t * cols[:, -1] ** 2
    return gpmsa.SimData(x=x, t=t, y=y, index=index, index_names=names)


def _outside(points: bool) -> gpmsa.ObsData:
    """Two experiments, the second's row 1 outside the simulation index."""
    if points:
        index = [POINTS[[0, 7, 12]], np.array([[0.5, 1.0], [1.2, 0.0], [0.1, 0.1]])]
    else:
        index = [GRID[[1, 3]], np.array([0.2, 1.2])]
    return gpmsa.ObsData(X_OBS, [np.ones(len(g)) for g in index], index=index)


NAMED = {
    True: r"1 has the point \(time 1.2, angle 0\) \(row 1\)",
    False: r"1 \(time\) reaches \[0.2, 1.2\]",
}
PLAIN = {True: r"1 has the point \(1.2, 0\) \(row 1\)", False: r"1 reaches \[0.2, 1.2\]"}


@pytest.fixture(scope="module", params=[True, False], ids=["points", "grid"])
def case(request):
    points = request.param
    index = POINTS if points else GRID
    names = ("time", "angle") if points else ("time",)
    named = gpmsa.Emulator.from_params(_sim(index, names), PARAMS, n_pc=2)
    plain = gpmsa.Emulator.from_params(_sim(index), PARAMS, n_pc=2)
    return points, named, plain


def test_fit_names_the_columns(case):
    points, named, plain = case
    with pytest.raises(gpmsa.GPMSAError, match=r"experiment " + NAMED[points]):
        gpmsa.fit(_sim(named.index, named.index_names), _outside(points), n_iter=5, n_pc=2)
    with pytest.raises(gpmsa.GPMSAError, match=r"experiment " + PLAIN[points]):
        gpmsa.fit(_sim(plain.index), _outside(points), n_iter=5, n_pc=2)


@pytest.mark.parametrize(
    "run",
    [
        lambda emu, obs: gpmsa.calibrate(emu, obs, n_samples=20, n_burn=5),
        lambda emu, obs: gpmsa.calibrate(emu, obs, n_samples=20, n_burn=5,
                                         discrepancy="constant"),
        lambda emu, obs: gpmsa.Calibrator(emu, method="mcmc").update(obs),
    ],
    ids=["calibrate", "discrepancy", "calibrator"],
)  # fmt: skip
def test_calibration_names_the_columns(case, run):
    points, named, plain = case
    with pytest.raises(gpmsa.GPMSAError, match=r"experiment " + NAMED[points]):
        run(named, _outside(points))
    with pytest.raises(gpmsa.GPMSAError, match=r"experiment " + PLAIN[points]):
        run(plain, _outside(points))


def test_full_prediction_names_the_columns(case):
    points, named, plain = case
    inside = gpmsa.ObsData(X_OBS, [np.ones(2)] * 2, index=[named.index[[1, 3]]] * 2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        post = gpmsa.calibrate(named, inside, n_samples=20, n_burn=5, seed=1)
        post_plain = gpmsa.calibrate(plain, inside, n_samples=20, n_burn=5, seed=1)
    grid = np.array([[0.5, 1.0], [1.2, 0.0]]) if points else np.array([0.2, 1.2])
    if points:
        named_msg = r"^grid has the point \(time 1.2, angle 0\) \(row 1\)"
        plain_msg = r"^grid has the point \(1.2, 0\) \(row 1\)"
    else:
        named_msg, plain_msg = r"^grid \(time\) must be", r"^grid must be"
    with pytest.raises(gpmsa.GPMSAError, match=named_msg):
        gpmsa.full_prediction(named, inside, [[0.5]], posterior=post, grid=grid)
    with pytest.raises(gpmsa.GPMSAError, match=plain_msg):
        gpmsa.full_prediction(plain, inside, [[0.5]], posterior=post_plain, grid=grid)
