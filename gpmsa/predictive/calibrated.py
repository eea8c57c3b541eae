"""Calibrated prediction: the emulator's predictive at new x, averaged over a posterior."""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from scipy.special import ndtr, ndtri

from gpmsa._fp_state import underflow_as_zero
from gpmsa._progress import progress_bar
from gpmsa._threads import one_thread
from gpmsa.calibration.observations import EMULATOR_ATTRS, check_x
from gpmsa.calibration.posterior import Posterior
from gpmsa.errors import GPMSAError
from gpmsa.model.data import (
    as_float,
    as_real,
    check_count,
    check_finite,
    check_flag,
    check_level,
    evenly_spaced,
)
from gpmsa.model.discrepancy import has_draws
from gpmsa.predictive._common import (
    EMULATOR_PARAMS,
    check_posterior_emulator,
    lacks_text,
    paired_draws,
    posterior_lamos,
    posterior_theta,
)


@dataclass(frozen=True, eq=False)
class CalibratedPrediction:
    """Predictive distribution of the output at x (native units): a Gaussian mixture per point.

    Attributes:
        x: (N, p) the inputs.
        mean: (N, l_sim) predictive mean; var: (N, l_sim) predictive variance (law of total
            variance over the mixture).
        comp_mean, comp_var: (K, N, l_sim) the mixture's components (one per theta node or draw);
        weights: (K,) their weights (sum 1).
    """

    x: np.ndarray
    mean: np.ndarray
    var: np.ndarray
    comp_mean: np.ndarray
    comp_var: np.ndarray
    weights: np.ndarray

    @property
    def sd(self) -> np.ndarray:
        """Predictive standard deviation (N, l_sim)."""
        return np.sqrt(self.var)

    def cdf(self, y: np.ndarray) -> np.ndarray:
        """P(Y <= y) per point, y (N, l_sim) (or broadcastable)."""
        y = as_float(y, "y")
        check_finite(y, "y")
        shape = self.comp_mean.shape[1:]
        try:
            fits = np.broadcast_shapes(y.shape, shape) == shape
        except ValueError:
            fits = False
        if not fits:
            raise GPMSAError(f"y must have shape {shape} (N points x l_sim), or broadcast to it, "
                             f"got {y.shape}")  # fmt: skip
        z = (y[None] - self.comp_mean) / np.sqrt(self.comp_var)
        return np.tensordot(self.weights, ndtr(z), axes=1)

    def quantile(self, q: float) -> np.ndarray:
        """Predictive quantile (N, l_sim) at one probability q in (0, 1) (bisection on the CDF
        between the components' own q-quantiles, which bracket the mixture's at any q; a list
        or an array of several q is refused: call once per q)."""
        q = as_real(q, "q")
        if not 0.0 < q < 1.0:
            raise GPMSAError(f"q must lie in (0, 1), got {q}")
        own = self.comp_mean + np.sqrt(self.comp_var) * ndtri(q)  # below all: F < q; above: F >= q
        lo, hi = np.min(own, axis=0), np.max(own, axis=0)
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            below = self.cdf(mid) < q
            lo = np.where(below, mid, lo)
            hi = np.where(below, hi, mid)
        return 0.5 * (lo + hi)

    def interval(self, level: float = 0.9) -> tuple[np.ndarray, np.ndarray]:
        """Central predictive interval of probability ``level``: (lower, upper), (N, l_sim) each."""
        level = check_level(level)
        return self.quantile((1.0 - level) / 2.0), self.quantile((1.0 + level) / 2.0)

    def __repr__(self) -> str:
        n, l_sim = np.shape(self.mean)[:2] if np.ndim(self.mean) == 2 else (0, 0)
        return (f"CalibratedPrediction({n} points x {l_sim} outputs, "
                f"{np.size(self.weights)} mixture components)")  # fmt: skip


@underflow_as_zero
def calibrated_predict(
    emulator,
    posterior: Posterior,
    x_new=None,
    *,
    noise: bool = False,
    resid: bool = True,
    draws: bool = False,
    n_theta: int = 200,
    extrapolate: bool = False,
    progress: bool = False,
) -> CalibratedPrediction:
    """The output's predictive at ``x_new`` with theta (and lamOs) from ``posterior``.

    Each mixture component is the emulator's Gaussian predictive (``Emulator.predict``, point
    estimate) at (x_new, theta_k). For a grid posterior of one parameter the components are the
    grid nodes carrying mass, weighted by the exact posterior (trapezoid weights); otherwise up to
    ``n_theta`` evenly spaced posterior draws, equally weighted. ``draws=True``: each draw's
    component at the emulator parameters drawn with that theta (GPM/SA's gPred 'wpred' after a
    joint fit, SEPIA's predictions from ``samples``), so the spread includes theirs.

    Args:
        emulator: the gpmsa.Emulator the posterior was computed with.
        posterior: a Posterior from ``calibrate`` or ``Calibrator.update``; one that recorded
            another emulator (info "emulator_sha256", ``Emulator.model_sha256``) is refused
            (GPMSAError).
        x_new: (N, p) known inputs, native units; None (one point) for an emulator without
            known inputs (p = 0).
        noise: add the observation error 1/lamOs (standardised units): the predictive of a new
            observation rather than of the simulator output. On a one-parameter grid posterior
            each node adds the exact E[1/lamOs | data, theta]; otherwise each draw its own lamOs.
            A posterior with discrepancy draws (lamVz) is refused (GPMSAError): a new
            observation then includes the discrepancy, which ``gpmsa.full_prediction`` adds.
        resid: include the emulator's nugget and residual variance (see ``Emulator.predict``).
        draws: pair each theta draw with its own draw of the emulator parameters (betaU,
            lamUz, lamWs, lamWOs) instead of the point estimate: where the posterior holds them
            jointly, ``calibration_posterior`` of a joint fit (the fit's draw i with theta's
            draw i) or ``gpmsa.calibrate(..., emulator_params="draws")`` and
            ``Calibrator(..., emulator_params="draws")`` (their ``info["emulator_draws"]``);
            another posterior (calibrated at the point estimate, ``calibrate_study``'s, one
            made by hand) is refused (GPMSAError saying why).
        n_theta: at most this many posterior draws when draws are used.
        extrapolate: allow x_new outside the emulator's x domain, however far (with a
            warning naming x_new), as ``gpmsa.calibrate`` allows x_obs; False: within
            ``EXTRAPOLATION_MARGIN`` (10 %) of a column's width a warning, as
            ``Emulator.predict``, beyond it a GPMSAError naming the column.
        progress: with ``draws=True``, show a tqdm bar over the emulator draws on stderr
            ("calibrated_predict"; each is factored once). The point estimate's one
            vectorised prediction shows none.

    Returns:
        CalibratedPrediction (native units).
    """
    missing = [a for a in EMULATOR_ATTRS if not hasattr(emulator, a)]
    if missing:  # as gpmsa.calibrate: a stand-in with these attributes is taken
        raise GPMSAError(f"emulator lacks {missing}: calibrated_predict needs a gpmsa.Emulator, "
                         f"got {type(emulator).__name__}")  # fmt: skip
    noise, resid = check_flag(noise, "noise"), check_flag(resid, "resid")
    draws = check_flag(draws, "draws")
    extrapolate = check_flag(extrapolate, "extrapolate")
    progress = check_flag(progress, "progress")
    x, _ = check_x(emulator, x_new, extrapolate, "x_new")
    if not isinstance(posterior, Posterior):
        raise GPMSAError(f"posterior must be a gpmsa.Posterior, got {type(posterior).__name__}")
    check_posterior_emulator(emulator, posterior)
    names = tuple(emulator.t_names)
    missing = [n for n in names if n not in posterior.names]
    if missing:
        raise GPMSAError(lacks_text(missing, posterior.names))
    n_theta = check_count(n_theta, "n_theta")
    if noise and has_draws(posterior.names):
        raise GPMSAError(
            "noise=True: this posterior has discrepancy draws (lamVz), and a new observation "
            "includes the discrepancy, which calibrated_predict omits; use gpmsa.full_prediction("
            "emulator, obs, x, posterior=posterior, discrepancy=...) and its 'y', or noise=False "
            "for the simulator output at the calibrated theta"
        )
    paired = paired_draws(emulator, posterior, "calibrated_predict") if draws else None
    lam = None
    inv_lam = posterior.info.get("expected_inv_lamOs")
    on_grid = len(names) == 1 and names[0] in posterior.grids and paired is None
    if on_grid and (inv_lam is not None or not noise):
        g = posterior.grids[names[0]]
        w = g.weights * g.density
        live = w > 1e-12 * w.max()
        theta = g.nodes[live][:, None]
        weights = w[live] / w[live].sum()
        if noise:  # exact: E[1/lamOs | data, theta] at each node
            lam = 1.0 / np.asarray(inv_lam)[live]
    else:
        n = np.size(posterior.samples[names[0]])
        idx = evenly_spaced(n, n_theta)
        theta = np.column_stack([np.asarray(posterior.samples[k])[idx] for k in names])
        weights = np.full(idx.size, 1.0 / idx.size)
        if noise:
            lam = posterior_lamos(posterior, idx)
    posterior_theta(emulator, theta)
    K, N = theta.shape[0], x.shape[0]
    xs = np.tile(x, (K, 1))
    ts = np.repeat(theta, N, axis=0)
    with warnings.catch_warnings():  # x_new and theta were checked (and warned about) above
        warnings.simplefilter("ignore")
        if paired is None:
            mean, var = emulator._predict_point(xs, ts, resid, extrapolate=extrapolate)
        else:
            mean, var = _paired_predict(emulator, xs, ts, np.repeat(paired[idx], N), resid,
                                        extrapolate, progress)  # fmt: skip
    l_sim = mean.shape[1]
    mean = mean.reshape(K, N, l_sim)
    var = var.reshape(K, N, l_sim)
    if lam is not None:
        var = var + emulator.standardizer.var_from_std((1.0 / lam)[:, None, None])
    m = np.tensordot(weights, mean, axes=1)
    v = np.tensordot(weights, var + (mean - m[None]) ** 2, axes=1)
    return CalibratedPrediction(x, m, v, mean, var, weights)


def _paired_predict(
    emulator, xs, ts, draw_of: np.ndarray, resid: bool, extrapolate: bool, progress: bool = False
):  # fmt: skip
    """Native predictive mean and variance (n, l_sim) at native (xs, ts) (n rows), row i at the
    emulator's retained draw ``draw_of[i]`` (``Emulator.predict``'s single-draw predictive);
    ``progress``: a bar over the distinct draws."""
    emulator._check_predict_memory(xs, ts)
    z = emulator._inputs(xs, ts, extrapolate=extrapolate)
    mean = np.empty((z.shape[0], emulator.l_sim))
    var = np.empty_like(mean)
    distinct = np.unique(draw_of)
    # many small solves: one thread
    with one_thread(), progress_bar(progress, distinct.size, "calibrated_predict") as bar:
        for d in distinct:
            rows = draw_of == d
            prm = {k: np.asarray(emulator.draws[k][d]) for k in EMULATOR_PARAMS}
            fac = emulator._predict_factors(prm)
            mean[rows], var[rows] = emulator._predict_std(z[rows], prm, fac, resid)
            bar.update(1)
    s = emulator.standardizer
    return s.y_from_std(mean), s.var_from_std(var)
