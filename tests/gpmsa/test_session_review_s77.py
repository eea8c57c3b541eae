"""Where the output index of several columns meets the calibration's continuation and the
prediction grid: a continuation refused for another discrepancy basis names the digests by
their first 12 characters, as its other digests; a prediction grid outside the simulation
points' hull is refused as a grid, not as observations."""

from __future__ import annotations

import numpy as np
import pytest

import gpmsa

TIME, ANGLE = np.linspace(0.0, 1.0, 4), np.linspace(0.0, 2.0, 5)
POINTS = np.column_stack([np.repeat(TIME, 5), np.tile(ANGLE, 4)])  # (20, 2): (time, angle)
ROWS = (np.array([0, 3, 7, 12, 19]), np.array([2, 5, 11]))
X_OBS = np.array([0.3, 0.7])
pytestmark = pytest.mark.filterwarnings("ignore::gpmsa.ConvergenceWarning")


def _f(x: float, t: float, pts: np.ndarray) -> np.ndarray:
    return np.sin(np.pi * pts[:, 0] * (0.5 + x)) * (1 + t) + 0.3 * pts[:, 1] * t


def _emulator() -> gpmsa.Emulator:
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=12), rng.uniform(size=12)
    y = np.array([_f(a, b, POINTS) for a, b in zip(x, t, strict=True)])
    sim = gpmsa.SimData(x[:, None], t[:, None], y, index=POINTS, index_names=["time", "angle"])
    return gpmsa.fit(sim, n_iter=20, tune=False, seed=4, n_pc=2)


def _obs() -> gpmsa.ObsData:
    ys = [_f(x, 0.4, POINTS[r]) for x, r in zip(X_OBS, ROWS, strict=True)]
    return gpmsa.ObsData(X_OBS[:, None], ys, index=[POINTS[r] for r in ROWS])


def _kernels(pts: np.ndarray) -> np.ndarray:
    centres = np.array([[0.2, 0.5], [0.8, 1.5]])
    return 3.0 * np.exp(-0.5 * np.sum((pts[:, None, :] - centres[None]) ** 2, axis=2) / 0.25)


def test_a_continuation_with_another_discrepancy_basis_names_short_digests():
    emu, obs = _emulator(), _obs()
    disc = [_kernels(POINTS[r]) for r in ROWS]
    post = gpmsa.calibrate(emu, obs, discrepancy=disc, n_samples=12, n_burn=2, seed=2)
    # the same basis at another scale is the same normalised basis: it continues
    again = gpmsa.calibrate(emu, obs, discrepancy=[2 * d for d in disc], n_samples=5, seed=3,
                            init=post)  # fmt: skip
    assert again.chains["t0"].shape == (1, 5)
    with pytest.raises(gpmsa.GPMSAError, match="other discrepancy basis or groups") as err:
        gpmsa.calibrate(emu, obs, discrepancy=[d[:, :1] for d in disc], n_samples=5, seed=3,
                        init=post)  # fmt: skip
    digests = [post.info["discrepancy_sha256"]]
    assert digests[0][:12] in str(err.value)
    assert digests[0] not in str(err.value)  # not its 64 characters


def test_a_prediction_grid_outside_the_points_is_refused_as_a_grid():
    emu, obs = _emulator(), _obs()
    post = gpmsa.calibrate(emu, obs, n_samples=12, n_burn=2, seed=2)
    with pytest.raises(gpmsa.GPMSAError, match=r"\(time 1.2, angle 0\)") as err:
        gpmsa.full_prediction(emu, obs, [[0.4]], posterior=post, grid=[[1.2, 0.0]], seed=1)
    assert "observations" not in str(err.value)
    with pytest.raises(gpmsa.GPMSAError, match="grid has shape") as err:
        gpmsa.full_prediction(emu, obs, [[0.4]], posterior=post, grid=np.zeros((2, 3)), seed=1)
    assert "observations" not in str(err.value)
