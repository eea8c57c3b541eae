"""Cross-validation of the emulator over its posterior draws: leave-one-out and k-fold.

For one draw of the emulator parameters and basis component j, with P = Sigma_W_j^-1 (with a
mean basis H, the projected precision P = S^-1 - S^-1 H (H^T S^-1 H)^-1 H^T S^-1, S = Sigma_W_j:
the mean's coefficients, flat prior, refitted without the fold, as ``Emulator.loo``) and a fold
F of held-out runs, the weights of F given the other runs are exactly Gaussian with

    cov_F = (P_FF)^-1,   mean_F = w_F - cov_F (P w_j)_F

(the nugget included: a held-out run is a new noisy run); a fold of one run gives the familiar
LOO formulas mean_i = w_i - [P w]_i / P_ii, var_i = 1 / P_ii. Outputs go through K, plus the
residual 1/lamWOs for a functional output, as ``Emulator.loo``. Over the retained draws the
predictive is the mixture of these Gaussians: its mean, its variance (law of total variance) and
the probability integral transform (PIT) of each held-out value, pit = P(Y <= y_run) under the
mixture, from which interval coverage follows without a Gaussian approximation.

The hyperparameters are not refitted per fold and the basis K keeps every run (the usual GPM/SA
practice); the check is of the GP's interpolation given its posterior, not of the whole fit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import cho_solve
from scipy.special import ndtr

from gpmsa._fp_state import underflow_as_zero
from gpmsa._progress import progress_bar
from gpmsa._threads import one_thread
from gpmsa.errors import GPMSAError
from gpmsa.fitting.emulator import output_variance, span_text
from gpmsa.limits import check_memory
from gpmsa.model.data import check_flag, check_level
from gpmsa.predictive._common import (
    draws_text,
    gp_factors,
    gpmsa_model_only,
    param_sets,
    rng_of,
)


@dataclass(frozen=True, eq=False)
class CrossValidation:
    """Held-out predictions of the simulation runs, averaged over posterior draws.

    Attributes:
        folds: (m,) the fold of each run (LOO: 0..m-1).
        draw_index: (S,) the emulator draws used (-1: the point estimate).
        y: (m, l_sim) the runs' outputs, native units.
        mean, var: (m, l_sim) predictive mean and variance of each held-out run, native units.
        mean_w, var_w: (m, p_u) the same for the basis weights (standardised scale), against
            ``w`` (m, p_u) the runs' weights.
        pit: (m, l_sim) P(Y <= y) under the predictive mixture (uniform when calibrated).
    """

    folds: np.ndarray
    draw_index: np.ndarray
    y: np.ndarray
    mean: np.ndarray
    var: np.ndarray
    w: np.ndarray
    mean_w: np.ndarray
    var_w: np.ndarray
    pit: np.ndarray

    @property
    def z(self) -> np.ndarray:
        """(m, l_sim) standardised residuals (y - mean) / sqrt(var)."""
        return (self.y - self.mean) / np.sqrt(self.var)

    @property
    def rmse(self) -> np.ndarray:
        """(l_sim,) root mean square error of the held-out means, native units."""
        return np.sqrt(np.mean((self.y - self.mean) ** 2, axis=0))

    def coverage(self, level: float = 0.9) -> float:
        """Share of held-out values inside their central predictive interval of ``level``."""
        level = check_level(level)
        return float(np.mean(np.abs(self.pit - 0.5) <= level / 2))

    def __repr__(self) -> str:
        m, l_sim = np.shape(self.y)[:2] if np.ndim(self.y) == 2 else (0, 0)
        n_folds = np.unique(self.folds).size
        folds = "leave-one-out" if n_folds == m else f"{n_folds} folds"
        draws, rmse = draws_text(self.draw_index), span_text(self.rmse)
        return (f"CrossValidation({m} runs x {l_sim} outputs, {folds}, {draws}, rmse={rmse}, "
                f"coverage(0.9)={self.coverage(0.9):.3g})")  # fmt: skip


def _fold_labels(folds, m: int, seed) -> np.ndarray:
    rng = rng_of(seed)  # checked whatever the folds (a bad seed is refused, used or not)
    if folds is None:
        return np.arange(m)
    if isinstance(folds, int | np.integer) and not isinstance(folds, bool):
        k = int(folds)
        if not 2 <= k <= m:
            raise GPMSAError(f"folds must be an integer in [2, m] = [2, {m}], got {k}")
        return rng.permutation(m) % k
    labels = np.asarray(folds)
    if labels.ndim == 0:  # a single value that is no integer (2.0, "3", True)
        raise GPMSAError(
            f"folds must be None (leave-one-out), an integer k in [2, {m}] or one label per "
            f"run, got {folds!r}"
        )
    if labels.shape != (m,):
        raise GPMSAError(
            f"folds must be None (leave-one-out), an integer k or one label per run (shape "
            f"({m},)), got shape {labels.shape}"
        )
    bad = [v for v in labels.tolist() if v is None or (isinstance(v, float) and v != v)]
    if bad:
        raise GPMSAError(f"folds: every run needs a label (None and NaN are not labels), got "
                         f"{bad[0]!r}")  # fmt: skip
    try:
        _, inv = np.unique(labels, return_inverse=True)
    except TypeError as exc:  # labels numpy cannot order (e.g. numbers mixed with strings)
        raise GPMSAError(
            f"folds: the labels must be of one kind (all numbers or all strings), "
            f"got {sorted({type(v).__name__ for v in labels.tolist()})}"
        ) from exc
    if inv.max() == 0:
        raise GPMSAError("folds must hold at least two different labels")
    return inv.reshape(m)


def _check_identified(H: np.ndarray, labels: np.ndarray, groups: list[np.ndarray]) -> None:
    """GPMSAError when the runs left after holding out a fold do not identify the mean basis's
    coefficients (H (m, k) on them of rank below k): that fold has no predictive."""
    for g, F in enumerate(groups):
        kept = H[labels != g]
        rank = np.linalg.matrix_rank(kept)
        if rank < H.shape[1]:
            raise GPMSAError(
                f"cross_validate: without fold {g} ({F.size} runs) the other runs leave the mean "
                f"basis's {H.shape[1]} columns of rank {rank}, so its coefficients are not "
                "identified; use smaller folds"
            )


@underflow_as_zero
def cross_validate(
    emulator,
    *,
    folds=None,
    draws: bool = True,
    n_draws: int | None = None,
    seed=None,
    progress: bool = False,
) -> CrossValidation:
    """Leave-one-out (default) or k-fold predictions of the runs, averaged over posterior draws.

    Args:
        emulator: a fitted gpmsa.Emulator.
        folds: None (leave one run out at a time), an integer k (k random folds of near-equal
            size, drawn with ``seed``), or (m,) labels (runs with the same label are held out
            together, e.g. the runs of one design point).
        draws: average over the retained posterior draws (True) or use the point estimate
            (then leave-one-out equals ``Emulator.loo()``).
        n_draws: at most this many draws, evenly spaced (None: all retained draws).
        seed: for the random folds.
        progress: show a tqdm bar over the draws on stderr ("cross_validate"; each draw
            factors the runs' covariance once per component: minutes for hundreds of runs
            and draws); none at the point estimate (``draws=False``).

    Returns:
        CrossValidation.

    Example:
        >>> import numpy as np, gpmsa
        >>> rng = np.random.default_rng(0)
        >>> x, t = rng.uniform(size=(30, 1)), rng.uniform(size=(30, 1))
        >>> data = gpmsa.SimData(x=x, t=t, y=np.sin(3 * x) + t, x_names=["x"], t_names=["t"])
        >>> emu = gpmsa.fit(data, n_iter=60, tune=False, seed=1)
        >>> cv = gpmsa.cross_validate(emu, n_draws=20)
        >>> cv.mean.shape, cv.pit.shape
        ((30, 1), (30, 1))
        >>> bool(np.allclose(gpmsa.cross_validate(emu, draws=False).mean, emu.loo().mean))
        True
    """
    gpmsa_model_only(emulator, "cross_validate")
    draws, progress = check_flag(draws, "draws"), check_flag(progress, "progress")
    m, p_u, l_sim = emulator.m, emulator.p_u, emulator.l_sim
    labels = _fold_labels(folds, m, seed)
    groups = [np.flatnonzero(labels == g) for g in range(labels.max() + 1)]
    H = None if emulator.mean_basis is None else emulator.mean_basis.matrix(emulator.zt)
    if H is not None:
        _check_identified(H, labels, groups)
    idx, sets = param_sets(emulator, draws, n_draws, "cross_validate")
    check_memory(  # per draw: each component's Cholesky factor, the precision, their work copies
        8.0 * (p_u + 3) * m * m, f"cross_validate: {p_u} covariance factors of {m} x {m} runs"
    )
    std = emulator.standardizer
    y_std = std.y_to_std(emulator.y)
    S = len(sets)
    acc = {k: np.zeros((m, l_sim)) for k in ("m", "m2", "v", "pit")}
    acc_w = {k: np.zeros((m, p_u)) for k in ("m", "m2", "v")}
    with one_thread(), progress_bar(progress and draws, S, "cross_validate") as bar:
        for prm in sets:
            mw = np.empty((m, p_u))
            vw = np.empty((m, p_u))
            for j, (L, alpha, gls) in enumerate(gp_factors(emulator, prm)):
                P = cho_solve((L, True), np.eye(m))
                if gls is not None:  # the projected precision: the GLS mean refitted per fold
                    B = cho_solve((L, True), H)
                    P -= B @ cho_solve(gls.Q, B.T)
                for F in groups:
                    if F.size == 1:
                        c = 1.0 / P[F[0], F[0]]
                        mw[F, j] = emulator.w[F, j] - c * alpha[F]
                        vw[F, j] = c
                    else:
                        C = np.linalg.inv(P[np.ix_(F, F)])
                        mw[F, j] = emulator.w[F, j] - C @ alpha[F]
                        vw[F, j] = np.diag(C)
            my = mw @ emulator.K.T
            vy = output_variance(vw, emulator.K, emulator.lam_sim, prm["lamWOs"][0])
            acc["m"] += my
            acc["m2"] += my**2
            acc["v"] += vy
            acc["pit"] += ndtr((y_std - my) / np.sqrt(vy))
            acc_w["m"] += mw
            acc_w["m2"] += mw**2
            acc_w["v"] += vw
            bar.update(1)

    def moments(a):
        mean = a["m"] / S
        return mean, a["v"] / S + np.maximum(a["m2"] / S - mean**2, 0.0)

    mean, var = moments(acc)
    mean_w, var_w = moments(acc_w)
    return CrossValidation(
        folds=labels, draw_index=idx, y=emulator.y.copy(),
        mean=std.y_from_std(mean), var=std.var_from_std(var), w=emulator.w.copy(),
        mean_w=mean_w, var_w=var_w, pit=acc["pit"] / S,
    )  # fmt: skip
