"""Emulator predictions as draws: realizations of the simulator output per posterior draw.

This is SEPIA's ``SepiaEmulatorPrediction`` (GPM/SA's ``gPredict`` in 'wpred' mode): for each
retained draw of the emulator parameters (betaU, lamUz, lamWs, lamWOs) the basis weights at new
inputs z = (x, t) are Gaussian given the simulation runs' weights w,

    w_j(z) | w ~ N(r_j(z)^T Sigma_W_j^-1 w_j,  1/lamUz_j - r_j(z)^T Sigma_W_j^-1 r_j(z)),
    r_j(z) = R(z, zt; betaU_j) / lamUz_j,

and the output is y = y_mean + y_sd (K w + e) on the simulation grid. With ``resid=True`` (the
default, as ``Emulator.predict``) a new run's nugget 1/lamWs_j joins each weight's variance and the
residual e ~ N(0, 1/lamWOs) each output element; ``resid=False`` gives the smooth emulator.
Categorical inputs take their kernel in R; with a mean basis h the weights' mean adds the GLS
trend h(z)^T c_j and their covariance the coefficients' g^T (H^T Sigma_W_j^-1 H)^-1 g, as
``Emulator.predict`` (docs/categorical-and-constraints.md).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from gpmsa._fp_state import underflow_as_zero
from gpmsa._progress import progress_bar
from gpmsa._threads import one_thread
from gpmsa.errors import GPMSAError
from gpmsa.limits import check_memory
from gpmsa.model.data import check_count, check_flag, check_level, check_same_rows
from gpmsa.predictive._common import (
    draws_text,
    gp_factors,
    gpmsa_model_only,
    mvn_factor,
    param_sets,
    realization_interval,
    realization_quantile,
    rng_of,
    unit_inputs,
    w_conditional,
)


@dataclass(frozen=True, eq=False)
class EmulatorPrediction:
    """Draws of the simulator output at new inputs (SEPIA's emulator prediction).

    Attributes:
        x: (N, p), t: (N, q) the inputs, native units.
        draw_index: (S,) the emulator's retained draws used, in order (-1: its point estimate).
        mu_w: (S, N, p_u) per draw, the conditional mean of the basis weights (standardised).
        var_w: (S, N, p_u) per draw, their variance (the nugget 1/lamWs included when ``resid``).
        w: (S * n_rlz, N, p_u) realizations of the weights; row s * n_rlz + r is realization r
            of draw s (``draw_of`` maps rows to draws).
        y: (S * n_rlz, N, l_sim) the same realizations as outputs, native units (with the
            residual 1/lamWOs when ``resid``).
        resid: whether nugget and residual are included.
        K: (l_sim, p_u) the basis; y_mean (l_sim,), y_sd: the output standardisation (a
            float; scaled columnwise, (l_sim,) each element's sd);
        lamWOs: (S,) the residual precision of each draw; grid: (l_sim,) the output grid
            (or index points (l_sim, d)).
    """

    x: np.ndarray
    t: np.ndarray
    draw_index: np.ndarray
    mu_w: np.ndarray
    var_w: np.ndarray
    w: np.ndarray
    y: np.ndarray
    resid: bool
    K: np.ndarray
    y_mean: np.ndarray
    y_sd: float | np.ndarray
    lamWOs: np.ndarray
    grid: np.ndarray

    @property
    def n_rlz(self) -> int:
        """Realizations per draw."""
        return self.w.shape[0] // self.mu_w.shape[0]

    @property
    def draw_of(self) -> np.ndarray:
        """(S * n_rlz,) the draw (position in ``draw_index``) of each realization."""
        return np.repeat(np.arange(self.mu_w.shape[0]), self.n_rlz)

    def _moments_std(self) -> tuple[np.ndarray, np.ndarray]:
        means = self.mu_w @ self.K.T  # (S, N, l_sim)
        var = self.var_w @ (self.K**2).T
        if self.resid:
            var = var + (1.0 / self.lamWOs)[:, None, None]
        m = means.mean(axis=0)
        return m, var.mean(axis=0) + means.var(axis=0)

    def mean(self) -> np.ndarray:
        """(N, l_sim) predictive mean, native units: exact moment of the mixture over draws."""
        return self._moments_std()[0] * self.y_sd + self.y_mean

    def var(self) -> np.ndarray:
        """(N, l_sim) predictive variance, native units^2 (law of total variance over draws)."""
        return self._moments_std()[1] * self.y_sd**2

    def quantile(self, q: float | np.ndarray | Sequence[float]) -> np.ndarray:
        """Predictive quantile(s) of the output, native units, at probability q in [0, 1] (a
        number, or an array of them): the empirical quantiles of the S * n_rlz realizations
        ``y`` (numpy's linear rule, so Monte-Carlo estimates), shape (N, l_sim) for a number and
        ``np.shape(q) + (N, l_sim)`` for an array; ``interval(level)`` gives those at
        (1 -+ level) / 2. GPMSAError naming q for one outside [0, 1], NaN or not a number."""
        return realization_quantile(self.y, q)

    def interval(self, level: float = 0.9) -> tuple[np.ndarray, np.ndarray]:
        """Central interval (N, l_sim) of probability ``level`` from the realizations' quantiles
        (`quantile` at (1 -+ level) / 2; a warning when there are too few for its tails:
        `realization_interval`)."""
        level = check_level(level)
        return realization_interval(self.y, level, "emulator_prediction's n_draws or n_rlz")

    def __repr__(self) -> str:
        s = np.shape(self.mu_w)[0]
        rlz = np.shape(self.w)[0] // s if s else 0
        return (f"EmulatorPrediction({np.shape(self.x)[0]} points x {np.shape(self.grid)[0]} "
                f"outputs, {draws_text(self.draw_index)} x {rlz} realizations, "
                f"resid={self.resid})")  # fmt: skip


@underflow_as_zero
def emulator_prediction(
    emulator,
    x,
    t,
    *,
    draws: bool = True,
    n_draws: int | None = None,
    n_rlz: int = 1,
    resid: bool = True,
    joint: bool = False,
    seed=None,
    extrapolate: bool = False,
    progress: bool = False,
) -> EmulatorPrediction:
    """Realizations of the simulator output at (x, t), one set per emulator posterior draw.

    Args:
        emulator: a fitted gpmsa.Emulator.
        x: (N, p) known inputs; t: (N, q) calibration parameters; native units (a single row of
            either broadcasts). Outside the training range: a warning; more than
            ``EXTRAPOLATION_MARGIN`` (10 %) of the range outside: GPMSAError naming x or t, the
            column, its values and the domain (``extrapolate=True``: the warning). A
            categorical input takes its training levels only (another: GPMSAError, as
            ``predict``).
        draws: use the retained posterior draws (True, the default) or only the point estimate.
        n_draws: at most this many draws, evenly spaced (None: all retained draws).
        n_rlz: realizations per draw.
        resid: include a new run's nugget and residual variance (as ``Emulator.predict``).
        joint: draw each realization jointly over the N points (their GP covariance);
            ``False`` draws each point independently from its marginal (cheaper; the same
            marginal distribution).
        seed: int, numpy Generator or None.
        extrapolate: allow x and t outside the emulator's domain by more than
            ``EXTRAPOLATION_MARGIN`` of a column's width (with an ExtrapolationWarning), as
            ``Emulator.predict(extrapolate=True)``.
        progress: show a tqdm bar over the draws on stderr ("emulator_prediction"); none at
            the point estimate (``draws=False``).

    Returns:
        EmulatorPrediction; its ``mean()`` and ``var()`` equal ``Emulator.predict(x, t,
        draws=True)`` for the same draws.

    Example:
        >>> import numpy as np, gpmsa
        >>> rng = np.random.default_rng(0)
        >>> x, t = rng.uniform(size=(30, 1)), rng.uniform(size=(30, 1))
        >>> data = gpmsa.SimData(x=x, t=t, y=np.sin(3 * x) + t, x_names=["x"], t_names=["t"])
        >>> emu = gpmsa.fit(data, n_iter=60, tune=False, seed=1)
        >>> x_new, t_new = [[0.5], [0.7]], [[0.2], [0.2]]
        >>> pred = gpmsa.emulator_prediction(emu, x_new, t_new, n_rlz=5, seed=2)
        >>> pred.y.shape   # (draws x realizations, points, outputs)
        (240, 2, 1)
        >>> bool(np.allclose(pred.mean(), emu.predict(x_new, t_new, draws=True)[0]))
        True
    """
    gpmsa_model_only(emulator, "emulator_prediction")
    draws, resid = check_flag(draws, "draws"), check_flag(resid, "resid")
    joint, extrapolate = check_flag(joint, "joint"), check_flag(extrapolate, "extrapolate")
    progress = check_flag(progress, "progress")
    n_rlz = check_count(n_rlz, "n_rlz")
    rng = rng_of(seed)
    s = emulator.standardizer
    check_same_rows({"x": x, "t": t}, {"x": emulator.x_names, "t": emulator.t_names})
    levels, p = tuple(emulator.levels), emulator.p
    x_nat, xu = unit_inputs(x, emulator.x_names, s.x_min, s.x_max, "x", levels[:p], extrapolate)
    t_nat, tu = unit_inputs(t, emulator.t_names, s.t_min, s.t_max, "t", levels[p:], extrapolate)
    if x_nat.shape[0] != t_nat.shape[0]:
        if x_nat.shape[0] == 1:
            x_nat, xu = (np.repeat(a, t_nat.shape[0], axis=0) for a in (x_nat, xu))
        elif t_nat.shape[0] == 1:
            t_nat, tu = (np.repeat(a, x_nat.shape[0], axis=0) for a in (t_nat, tu))
        else:
            raise GPMSAError(
                f"x and t need the same number of rows (or one of them a single row), got "
                f"x {x_nat.shape} and t {t_nat.shape}"
            )
    z = np.hstack([xu, tu])
    idx, sets = param_sets(emulator, draws, n_draws, "emulator_prediction")
    S, N, p_u, l_sim = len(sets), z.shape[0], emulator.p_u, emulator.l_sim
    check_memory(  # the realizations (w, y and its noise), and per set the GP's matrices
        8.0 * (S * n_rlz * N * (p_u + 3 * l_sim) + 3 * N * emulator.m
               + (4.0 * p_u * N * N if joint else 0.0)),
        f"emulator_prediction(n_rlz={n_rlz}, joint={joint}) at {N} points x {S} draws",
    )  # fmt: skip
    mu = np.empty((S, N, p_u))
    var = np.empty((S, N, p_u))
    w = np.empty((S, n_rlz, N, p_u))
    with one_thread(), progress_bar(progress and draws, S, "emulator_prediction") as bar:
        for i, prm in enumerate(sets):
            m_i, spread = w_conditional(emulator, prm, gp_factors(emulator, prm), z, joint)
            nugget = 1.0 / prm["lamWs"] if resid else np.zeros(p_u)
            mu[i] = m_i
            if joint:
                var[i] = np.diagonal(spread, axis1=1, axis2=2).T + nugget
                for j in range(p_u):
                    A = mvn_factor(spread[j] + nugget[j] * np.eye(N))
                    w[i, :, :, j] = m_i[:, j] + rng.standard_normal((n_rlz, N)) @ A.T
            else:
                var[i] = spread + nugget
                w[i] = m_i + np.sqrt(var[i]) * rng.standard_normal((n_rlz, N, p_u))
            bar.update(1)
    lamWOs = np.array([float(prm["lamWOs"][0]) for prm in sets])
    y_std = w @ emulator.K.T
    if resid:
        y_std += rng.standard_normal(y_std.shape) / np.sqrt(lamWOs)[:, None, None, None]
    y = y_std * s.y_sd + s.y_mean
    return EmulatorPrediction(
        x=x_nat, t=t_nat, draw_index=idx, mu_w=mu, var_w=var,
        w=w.reshape(S * n_rlz, N, p_u), y=y.reshape(S * n_rlz, N, l_sim), resid=resid,
        K=emulator.K, y_mean=s.y_mean, y_sd=s.y_sd, lamWOs=lamWOs, grid=s.grid,
    )  # fmt: skip
