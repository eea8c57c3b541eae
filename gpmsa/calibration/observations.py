"""Checks and GPM/SA reduction of observations for calibration with a fixed emulator."""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from functools import cache

import numpy as np
from threadpoolctl import ThreadpoolController

from gpmsa.calibration.model import FixedGP, LamOsPrior
from gpmsa.errors import GPMSAError
from gpmsa.model.data import ObsData, check_finite
from gpmsa.model.problem import SIGOBS_RIDGE, ObsProblem, reduce_obs

EMULATOR_ATTRS = ("standardizer", "x_unit", "t_unit", "K", "w", "lam_sim", "params", "priors")
EMULATOR_PARAMS = ("betaU", "lamUz", "lamWs", "lamWOs")
EMULATOR_PARAM_MODES = ("point", "draws")
MAX_STD_OBS = 1e6
"""Reduced observations farther than this from the simulation mean (in its sds) are refused."""


@dataclass(frozen=True, eq=False)
class Observations:
    """One calibration's data, reduced: x (n, p) unit; z (d,) stacked u (component-major,
    d = n p_u);
    obs_chol (d, d) lower Cholesky factor of Sigma_obs; lamos the data-corrected lamOs prior;
    obs the ObsProblem for the samplers."""

    x: np.ndarray
    z: np.ndarray
    obs_chol: np.ndarray
    lamos: LamOsPrior
    obs: ObsProblem
    os_corr: tuple[float, float]


def check_emulator(emulator) -> None:
    """Raise GPMSAError unless ``emulator`` has what calibration needs."""
    missing = [a for a in EMULATOR_ATTRS if not hasattr(emulator, a)]
    if missing:
        raise GPMSAError(f"emulator lacks {missing}: calibration needs a gpmsa.Emulator")
    absent = [k for k in EMULATOR_PARAMS if k not in emulator.params]
    if absent:
        raise GPMSAError(f"emulator.params lacks {absent}; it needs {EMULATOR_PARAMS}")
    if emulator.t_unit.shape[1] < 1:
        raise GPMSAError("the emulator has no calibration parameter (t has 0 columns)")


def emulator_param_sets(emulator, mode: str, n_sets: int) -> list[dict]:
    """The emulator parameter sets the calibration conditions on (point, or evenly spaced draws)."""
    if mode not in EMULATOR_PARAM_MODES:
        raise GPMSAError(f"emulator_params must be one of {EMULATOR_PARAM_MODES}, got {mode!r}")
    if mode == "point":
        return [emulator.params]
    draws = getattr(emulator, "draws", None) or {}
    n = len(next(iter(draws.values()))) if draws else 0
    if n == 0:
        raise GPMSAError("emulator_params='draws' needs retained draws; this emulator has none")
    if not (isinstance(n_sets, int | np.integer) and n_sets >= 1):
        raise GPMSAError(f"n_emulator_draws must be an integer >= 1, got {n_sets}")
    idx = np.unique(np.linspace(0, n - 1, min(int(n_sets), n)).astype(int))
    return [{k: np.asarray(draws[k][i]) for k in EMULATOR_PARAMS} for i in idx]


@cache
def blas_controller() -> ThreadpoolController:
    """The process's BLAS libraries (scanned once: a scan costs about a millisecond)."""
    return ThreadpoolController()


def fixed_gp(emulator, params: dict | None = None) -> FixedGP:
    """The emulator's GP at ``params`` (default: its point estimate)."""
    prm = emulator.params if params is None else params
    return FixedGP(
        emulator.x_unit, emulator.t_unit, emulator.w, emulator.lam_sim,
        prm["betaU"], prm["lamUz"], prm["lamWs"], prm["lamWOs"],
    )  # fmt: skip


def _as_rows(value, name: str, ncols: int) -> np.ndarray:
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise GPMSAError(f"{name} must be numeric, got {type(value).__name__}") from exc
    if arr.ndim == 0 or (arr.ndim == 1 and arr.size == ncols):
        arr = arr.reshape(1, -1)
    elif arr.ndim == 1 and ncols == 1:
        arr = arr[:, None]
    if arr.ndim != 2 or arr.shape[1] != ncols or arr.shape[0] == 0:
        raise GPMSAError(f"{name} must have shape (n, {ncols}), got {np.shape(value)}")
    check_finite(arr, name)
    return arr


def check_x(emulator, x_obs, extrapolate: bool) -> tuple[np.ndarray, np.ndarray]:
    """x_obs native (n, p) and unit scale; outside the emulator's x domain: GPMSAError, or with
    ``extrapolate=True`` a warning."""
    p = emulator.x_unit.shape[1]
    x = _as_rows(x_obs, "x_obs", p)
    xu = emulator.standardizer.x_to_unit(x)
    out = (xu < 0.0) | (xu > 1.0)
    if out.any():
        j, k = (int(i) for i in np.argwhere(out)[0])
        name = emulator.x_names[k]
        lo, hi = emulator.domain[name]
        msg = f"x_obs {name}={x[j, k]:.6g} lies outside the emulator's domain [{lo:.6g}, {hi:.6g}]"
        if not extrapolate:
            raise GPMSAError(msg + "; pass extrapolate=True to allow it")
        warnings.warn(msg + "; the emulator extrapolates", stacklevel=3)
    return x, xu


def reduce(emulator, x_obs, y_obs, extrapolate: bool = False) -> Observations:
    """Check and reduce (x_obs, y_obs) for the no-discrepancy model of ``emulator``.

    y_obs: (n, l_sim) on the emulator's output grid (a scalar output takes (n, 1) or (n,)).
    """
    x, xu = check_x(emulator, x_obs, extrapolate)
    n = x.shape[0]
    std, K = emulator.standardizer, emulator.K
    l_sim = K.shape[0]
    y = (
        _as_rows(y_obs, "y_obs", l_sim)
        if not (l_sim == 1 and np.size(y_obs) == n)
        else (_as_rows(np.reshape(y_obs, (n, 1)), "y_obs", 1))
    )
    if y.shape[0] != n:
        raise GPMSAError(f"y_obs must have one row per x_obs row ({n}), got {y.shape[0]}")
    base = emulator.priors.lamOs
    if l_sim == 1:  # GPM/SA's scalar-output reduction, as gpmsa.model.problem.reduce_obs
        u = (y - std.y_mean) / std.y_sd
        sig = np.eye(n) / (1.0 + SIGOBS_RIDGE)
        obs = ObsProblem(xu, u, np.zeros((n, 0)), sig, True, (np.ones((1, 1)),) * n, None)
        corr = (0.0, 0.0)
    else:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            obs, corr = reduce_obs(ObsData(x, y), std, K, None, emulator.x_names)
    z = obs.z
    far = np.abs(z) > MAX_STD_OBS
    if far.any():
        raise GPMSAError(
            f"y_obs lies {np.max(np.abs(z)):.3g} standard deviations of the simulation outputs "
            f"from their mean; allowed at most {MAX_STD_OBS:g} (wrong units?)"
        )
    lamos = LamOsPrior(base.a + corr[0], base.b + corr[1], base.lower, base.upper)
    sig = obs.sig_obs
    chol = np.sqrt(sig) if sig.shape == (1, 1) else np.linalg.cholesky(sig)
    return Observations(xu, z, chol, lamos, obs, corr)
