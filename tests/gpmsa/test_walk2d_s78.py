"""A SEPIA Neddermeyer-style port over a (time, angle) index: what a user does after the fit.

- A joint fit's own draws as ``posterior=`` (``calibration_posterior(emu)``) take its kept
  per-experiment bases by default, as the fit's own prediction does (it was refused: "pass the
  list again").
- Predicting on a grid that is no experiment's: the refusal names ``grid_discrepancy=`` and
  ``experiment=``.
- ``plots.emulator_fit``'s ExtrapolationWarning names the user's line, not the library's.
- A ``Calibrator`` on the grid refuses ``mcmc_options={"discrepancy": ...}`` (it was ignored:
  a posterior without the discrepancy asked for).
- ``plots.main_effect_curves`` names the output element's point on the index.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa import GPMSAError

TIMES = np.linspace(0.1, 1.0, 4)
ANGLES = np.linspace(0.0, np.pi / 2, 3)
POINTS = np.array([(a, b) for a in TIMES for b in ANGLES])  # (12, 2)


def _f(x: float, th: float, pts: np.ndarray) -> np.ndarray:
    t, a = pts[:, 0], pts[:, 1]
    return 1.0 + 0.3 * x - th * t * (1 + 0.4 * np.cos(2 * a)) + 0.2 * np.sin(a) * t


def _kernels(pts: np.ndarray) -> np.ndarray:
    """SEPIA's Neddermeyer discrepancy basis: Gaussian kernels over (time, angle)."""
    c = np.array([(0.2, 0.3), (0.8, 1.2)])
    dt = (pts[:, None, 0] - c[None, :, 0]) / 0.3
    da = (pts[:, None, 1] - c[None, :, 1]) / 0.8
    d2 = dt**2 + da**2
    return np.exp(-0.5 * d2)


def _sim(m: int = 10, seed: int = 0) -> gpmsa.SimData:
    rng = np.random.default_rng(seed)
    x, t = rng.uniform(size=(m, 1)), rng.uniform(0.2, 1.0, size=(m, 1))
    y = np.array([_f(x[i, 0], t[i, 0], POINTS) for i in range(m)])
    return gpmsa.SimData(x, t, y, index=POINTS, x_names=["x"], t_names=["a"],
                         index_names=["time", "angle"], index_units=["s", "rad"])  # fmt: skip


def _obs() -> tuple[gpmsa.ObsData, list[np.ndarray]]:
    rng = np.random.default_rng(1)
    grids = [np.column_stack([rng.uniform(0.1, 1.0, n), rng.uniform(0, np.pi / 2, n)])
             for n in (5, 7)]  # fmt: skip
    xo = np.array([[0.3], [0.7]])
    ys = [_f(xo[j, 0], 0.6, g) + 0.01 * rng.standard_normal(len(g)) for j, g in enumerate(grids)]
    return gpmsa.ObsData(xo, ys, index=grids), [_kernels(g) for g in grids]


def _params(p_u: int) -> dict:
    return {"betaU": [[2.0] * p_u, [1.0] * p_u], "lamUz": [1.0] * p_u,
            "lamWs": [1e4] * p_u, "lamWOs": [1e4]}  # fmt: skip


@pytest.fixture(scope="module")
def joint():
    obs, D = _obs()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        emu = gpmsa.fit(_sim(), obs, n_iter=40, tune=False, seed=0, n_pc=2, discrepancy=D)
    return emu, obs, D


def test_joint_fit_posterior_takes_its_kept_list(joint, tmp_path):
    emu, obs, D = joint
    post = gpmsa.calibration_posterior(emu)
    x = [[0.5]]
    own = gpmsa.full_prediction(emu, obs, x, experiment=1, seed=0)
    via = gpmsa.full_prediction(emu, obs, x, posterior=post, draws=True, experiment=1, seed=0)
    given = gpmsa.full_prediction(emu, obs, x, posterior=post, draws=True, experiment=1,
                                  discrepancy=D, seed=0)  # fmt: skip
    np.testing.assert_allclose(via.y, given.y, rtol=0, atol=1e-12)
    for what in ("eta", "delta", "y"):
        np.testing.assert_allclose(via.mean(what), own.mean(what), rtol=0, atol=1e-10)
        np.testing.assert_allclose(via.var(what), own.var(what), rtol=0, atol=1e-10)
    assert np.abs(via.mean("delta")).max() > 0  # the discrepancy is predicted, not dropped
    # on other points with the basis functions there, and after a file round trip
    g = np.array([[0.5, 0.4], [0.9, 1.0], [0.2, 0.1]])
    path = tmp_path / "e.gpmsa"
    emu.save(path)
    back = gpmsa.load(path)
    a = gpmsa.full_prediction(back, obs, x, posterior=gpmsa.calibration_posterior(back),
                              grid=g, grid_discrepancy=_kernels(g), seed=0)  # fmt: skip
    b = gpmsa.full_prediction(emu, obs, x, posterior=post, grid=g, grid_discrepancy=_kernels(g),
                              discrepancy=D, seed=0)  # fmt: skip
    np.testing.assert_allclose(a.mean("delta"), b.mean("delta"), rtol=0, atol=1e-12)
    assert np.abs(a.mean("delta")).max() > 0


def test_calibrate_posterior_still_needs_its_list(joint):
    emu, obs, D = joint
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        other = [d[:, ::-1] * np.array([1.0, 0.5]) for d in D]  # another basis
        post = gpmsa.calibrate(emu, obs, n_samples=60, n_burn=20, tune=False, seed=0,
                               discrepancy=other)  # fmt: skip
    with pytest.raises(GPMSAError, match="pass the list again as discrepancy="):
        gpmsa.full_prediction(emu, obs, [[0.5]], posterior=post, experiment=0)
    pred = gpmsa.full_prediction(emu, obs, [[0.5]], posterior=post, experiment=0,
                                 discrepancy=other, seed=0)  # fmt: skip
    assert pred.mean("y").shape == (1, 5)


def test_other_grid_refusal_names_grid_discrepancy(joint):
    emu, obs, _ = joint
    g = np.array([[0.5, 0.4], [0.9, 1.0]])
    with pytest.raises(GPMSAError, match=r"experiment=j.*grid_discrepancy="):
        gpmsa.full_prediction(emu, obs, [[0.5]], grid=g)
    pred = gpmsa.full_prediction(emu, obs, [[0.5]], grid=g, grid_discrepancy=_kernels(g), seed=0)
    assert pred.mean("delta").shape == (1, 2)


def test_emulator_fit_warning_names_the_users_line():
    sim = _sim()
    emu = gpmsa.Emulator.from_params(sim, _params(2), n_pc=2)
    held = _sim(m=6, seed=3)
    x = held.x.copy()
    x[0, 0] = emu.standardizer.x_max[0] + 0.02  # just outside the domain: a warning
    held = gpmsa.SimData(x, held.t, held.y, index=POINTS, x_names=["x"], t_names=["a"])
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fig = gpmsa.plots.emulator_fit(emu, held, draws=False)
    hits = [w for w in caught if issubclass(w.category, gpmsa.ExtrapolationWarning)]
    assert len(hits) == 1
    assert hits[0].filename == __file__
    assert fig is not None
    with warnings.catch_warnings(record=True) as caught:  # predict itself: as before
        warnings.simplefilter("always")
        emu.predict(x[:1], held.t[:1])
    assert [w.filename for w in caught] == [__file__]


def test_grid_calibrator_refuses_a_discrepancy():
    emu = gpmsa.Emulator.from_params(_sim(), _params(2), n_pc=2)
    obs, D = _obs()
    for opts in ({"discrepancy": "constant"}, {"discrepancy": D}, {"discrepancy_groups": [0]}):
        with pytest.raises(GPMSAError, match=r"exact grid.*method='mcmc'"):
            gpmsa.Calibrator(emu, mcmc_options=opts)
    with pytest.raises(GPMSAError, match=r"exact grid, which") as told:  # asked for: no aside
        gpmsa.Calibrator(emu, method="grid", mcmc_options={"discrepancy_groups": [0]})
    assert "discrepancy model's option" in str(told.value)
    assert gpmsa.Calibrator(emu, mcmc_options={"discrepancy": None}).method == "grid"
    cal = gpmsa.Calibrator(emu, method="mcmc", seed=0,
                           mcmc_options={"discrepancy": D, "n_samples": 60, "n_burn": 20,
                                         "tune": False})  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        post = cal.update(obs)
    assert "lamVz" in post.names


def test_main_effect_title_names_the_point():
    emu = gpmsa.Emulator.from_params(_sim(), _params(2), n_pc=2)
    sens = gpmsa.sensitivity(emu, draws=False, main_effect_grid=3)
    fig = gpmsa.plots.main_effect_curves(sens, output=4)
    title = fig._suptitle.get_text()
    t, a = POINTS[4]
    assert f"at output 4, time = {t:.4g} s, angle = {a:.4g} rad" in title
