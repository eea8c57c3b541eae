"""The result objects print as one short line (their class, the sizes that matter and, where
cheap, the headline figures), as ``Posterior``, ``Emulator`` and ``Study`` do, never their
arrays (a dataclass's default repr printed thousands of lines)."""

import warnings
from functools import cache

import numpy as np

import gpmsa
from gpmsa.calibration.posterior import GridMarginal
from gpmsa.predictive import calibrated_predict
from gpmsa.studies.sampler import StudyChains

GRID = np.linspace(0.0, 1.0, 7)


@cache
def _case():
    """A functional emulator (20 runs, 7 outputs, p_u = 2), a joint fit with a discrepancy, its
    observations and a calibrate posterior: small, a few seconds."""
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(20, 1)), rng.uniform(size=(20, 1))
    data = gpmsa.SimData(x=x, t=t, y=np.sin(3 * x) + t * GRID, index=GRID, x_names=["x"],
                         t_names=["t"])  # fmt: skip
    xo = np.array([[0.3], [0.6]])
    obs = gpmsa.ObsData(x=xo, y=np.sin(3 * xo) + 0.5 * GRID + 0.01, index=GRID)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # short chains: unconverged
        emu = gpmsa.fit(data, n_iter=60, tune=False, seed=1, n_pc=2)
        joint = gpmsa.fit(data, obs, n_iter=60, tune=False, seed=1, n_pc=2, discrepancy="linear")
        post = gpmsa.calibrate(emu, x_obs=[[0.3]], y_obs=np.sin(0.9) + 0.5 * GRID[None], seed=1,
                               n_samples=300, n_burn=100)  # fmt: skip
    return emu, joint, obs, post


def _check(obj, *parts: str) -> str:
    text = repr(obj)
    assert len(text) < 200, text
    assert "\n" not in text, text
    assert text.startswith(f"{type(obj).__name__}("), text
    for part in parts:
        assert part in text, (part, text)
    assert str(obj) == text
    return text


def test_full_prediction_repr():
    emu, joint, obs, _ = _case()
    x = np.linspace(0.1, 0.9, 40)[:, None]
    pred = gpmsa.full_prediction(joint, obs, x, n_draws=10, n_rlz=3, seed=1)
    _check(pred, "40 points", "7 outputs", "10 draws x 3 realizations", "p_u=2", "p_v=2")


def test_emulator_prediction_repr():
    emu, *_ = _case()
    x, t = np.linspace(0.1, 0.9, 30)[:, None], [[0.2]]
    pred = gpmsa.emulator_prediction(emu, x, t, n_draws=10, n_rlz=4, seed=2)
    _check(pred, "30 points", "7 outputs", "10 draws x 4 realizations")
    point = gpmsa.emulator_prediction(emu, x, t, draws=False, n_rlz=2, seed=2)
    _check(point, "point estimate x 2 realizations")


def test_calibrated_prediction_repr():
    emu, _, _, post = _case()
    pred = calibrated_predict(emu, post, np.linspace(0.1, 0.9, 25)[:, None], n_theta=30)
    _check(pred, "25 points", "7 outputs", "30 mixture components")


def test_cross_validation_repr_gives_rmse_and_coverage():
    emu, *_ = _case()
    cv = gpmsa.cross_validate(emu, n_draws=10)
    text = _check(cv, "20 runs", "7 outputs", "leave-one-out", "10 draws")
    rmse = cv.rmse
    assert f"rmse=[{rmse.min():.3g}, {rmse.max():.3g}]" in text
    assert f"coverage(0.9)={cv.coverage(0.9):.3g}" in text
    _check(gpmsa.cross_validate(emu, folds=4, draws=False, seed=0), "4 folds", "point estimate")


def test_sensitivity_repr_names_each_input():
    emu, *_ = _case()
    sens = gpmsa.sensitivity(emu, n_draws=10)
    total = sens.total_aggregated.mean(axis=0)
    _check(sens, "2 inputs", "0 fixed", "7 outputs", "10 draws",
           f"x={total[0]:.2f}", f"t={total[1]:.2f}")  # fmt: skip


def test_loo_result_repr():
    emu, *_ = _case()
    loo = emu.loo()
    _check(loo, "20 runs", "7 outputs", f"coverage95={loo.coverage95:.3g}")


def test_chains_repr_keeps_short_with_many_parameters():
    names = [f"theta{k}" for k in range(30)]
    chains = gpmsa.Chains(
        draws={n: np.zeros((4, 500)) for n in names}, log_post=np.zeros((4, 500)),
        accept_rate={}, step_widths={},
    )  # fmt: skip
    _check(chains, "4 chains x 500 draws", "theta0", "+24 more")


def test_study_chains_repr():
    c, n = 3, 200
    chains = StudyChains(
        theta=np.zeros((c, n, 2)), mu=np.zeros((c, n, 1)), lam=np.ones((c, n, 1)),
        log_post=np.zeros((c, n)), members=({"lamOs": np.ones((c, n, 1))},) * 4,
        accept_rate=np.zeros((c, 5)), widths=np.ones((c, 5)), names=("a",) * 5, info={},
    )  # fmt: skip
    _check(chains, "3 chains x 200 draws", "2 study elements", "1 groups", "4 models")


def test_grid_marginal_repr():
    nodes = np.linspace(0.0, 2.0, 513)
    gm = GridMarginal.from_log_density(nodes, -0.5 * ((nodes - 1.0) / 0.2) ** 2)
    _check(gm, "513 nodes on [0, 2]", f"mean={gm.mean():.4g}", f"sd={gm.sd():.3g}")


def test_calibrator_posterior_grids_print_short():
    """A Calibrator's posterior holds GridMarginals: printing its grids no longer prints the
    nodes."""
    emu, *_ = _case()
    post = gpmsa.Calibrator(emu).update([[0.3]], np.sin(0.9) + 0.5 * GRID[None])
    text = repr(post.grids)
    assert len(text) < 200 and "GridMarginal(" in text, text
