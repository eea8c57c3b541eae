"""A fast Metropolis-within-Gibbs sampler of (theta, lamOs) with the emulator fixed.

The same algorithm as the numpy backend (gpmsa.mcmc.sampler: GPM/SA's sweep order, proposals, bounds
and step-size tuning via gpmsa.mcmc.tuning), specialised to the calibration-only model of
``gpmsa.calibration.model``: a theta proposal needs only the predictive of u at the new theta. For
one calibration parameter that predictive (mean and covariance of u as functions of theta, for the
given x_obs) is expanded once in Chebyshev polynomials to round-off accuracy (checked against dense
solves at set-up), so a proposal costs O(degree) instead of O(m^2); otherwise each theta proposal
does dense solves (the x_obs parts computed once; the full predictive's operations, so its values
bit for bit, with few Python-level calls: ~25 us a proposal for 3 observations). The emulator
parameters may be one set (its point estimate) or several (its retained draws): then an index
over the sets is a further Gibbs element with a uniform prior, updated by a Metropolis step
proposing a uniformly chosen set, so that the chain targets the posterior with the likelihood
averaged over the sets.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.polynomial import chebyshev as cheb
from scipy.linalg import solve_triangular

from gpmsa._progress import progress_bar
from gpmsa.calibration.model import FixedGP, lower_solve
from gpmsa.calibration.observations import Observations
from gpmsa.errors import GPMSAError
from gpmsa.mcmc import level_moves, tuning
from gpmsa.mcmc.acceptance import log_uniform
from gpmsa.model.categorical import snap_to_levels
from gpmsa.model.constraints import ThetaConstraint
from gpmsa.model.correlation import correlation_row
from gpmsa.model.priors import Priors


def _eigh_kernel():
    """The kernel ``np.linalg.eigh`` runs (LAPACK ?syevd on the lower triangle), to call without
    its wrapper, or None where this numpy has no such private kernel or it does not give
    ``np.linalg.eigh``'s values bit for bit on a probe (then ``_eigh`` uses the public call)."""
    try:
        from numpy.linalg._umath_linalg import eigh_lo

        probe = np.array([[2.0, 0.5, 0.1], [0.5, 1.0, 0.3], [0.1, 0.3, 3.0]])
        got, want = eigh_lo(probe, signature="d->dd"), np.linalg.eigh(probe)
        same = all(np.array_equal(a, b) for a, b in zip(got, want, strict=True))
    except Exception:  # noqa: BLE001 - any failure of a private API: use the public one
        return None
    return eigh_lo if same else None


_eigh_lo = _eigh_kernel()

THETA_WIDTH = 0.2
CHEB_DEGREES = (16, 32, 64, 128, 256)


def _clenshaw2(pairs: tuple[tuple[float, float], ...], x: float) -> tuple[float, float]:
    """Two Chebyshev series at a scalar x in [-1, 1] in one pure-Python loop (no array overhead).

    ``pairs``: ((a_n, b_n), ..., (a_1, b_1)) in reverse order; the constant terms a_0, b_0 are
    added by the caller. Returns (sum_{k>=1} a_k T_k(x) + ..., same for b) without the constants.
    """
    a1 = a2 = b1 = b2 = 0.0
    x2 = x + x
    for ak, bk in pairs:
        t = ak + x2 * a1 - a2
        a2 = a1
        a1 = t
        t = bk + x2 * b1 - b2
        b2 = b1
        b1 = t
    return x * a1 - a2, x * b1 - b2


def _trim(*coefs: np.ndarray) -> tuple[tuple[float, ...], ...]:
    """Drop trailing coefficients below round-off (relative 1e-17), keeping a common length."""
    n = 2
    for c in coefs:
        keep = np.flatnonzero(np.abs(c) > 1e-17 * np.max(np.abs(c)))
        n = max(n, int(keep[-1]) + 1 if keep.size else 1)
    return tuple(tuple(float(v) for v in c[:n]) for c in coefs)


@dataclass(frozen=True)
class _XPart:
    """What a dense proposal of component c needs that does not depend on theta: R_x between
    x_obs and the design (n, m), Sigma_U at x_obs (n, n), and the design's theta columns with
    their correlation parameters for ``correlation_row``."""

    rx: np.ndarray
    prior: np.ndarray
    t_cols: list[np.ndarray]
    beta_t: list[float]
    cat_t: list[bool]

    @classmethod
    def of(cls, gp: FixedGP, x: np.ndarray, c: int) -> _XPart:
        cat = [False] * gp.q if gp.cat_t is None else [bool(v) for v in gp.cat_t]
        return cls(
            rx=gp.corr_x(x, c), prior=gp.prior_cov(x, c),
            t_cols=[np.ascontiguousarray(gp.t_sim[:, k]) for k in range(gp.q)],
            beta_t=[float(b) for b in gp.betaU[gp.p :, c]], cat_t=cat,
        )  # fmt: skip


class ThetaPredictive:
    """Whitened predictive (e, y) of the reduced data at theta for fixed x_obs.

    ``at(theta)`` returns (e, y2): the eigenvalues of L^-1 S(theta) L^-T (d,) and the squared
    rotated residuals (d,), with Sigma_obs = L L^T, so that
    log p(u | theta, lamOs) = -0.5 sum(log(e + 1/lamOs) + y2 / (e + 1/lamOs)) + const.
    For d == 1 both are floats. With one calibration parameter, the mean (d,) and covariance
    (d, d) of u are Chebyshev series in theta (``cheb``), accurate to ``tol`` relative to their
    scale (checked at 257 points against dense solves); with two and d == 1, 2-D series
    (``cheb2``, checked on a 33 x 33 grid); otherwise each call does dense solves.
    """

    def __init__(
        self, gp: FixedGP, data: Observations, tol: float = 1e-12, expand: bool = True
    ) -> None:
        self.gp = gp
        self.x = data.x
        self.z = data.z
        self.d = data.z.size
        self.L = data.obs_chol
        self._sig = float(data.obs_chol[0, 0])
        self.cheb: tuple[np.ndarray, np.ndarray] | None = None
        self.cheb2: tuple[np.ndarray, np.ndarray] | None = None
        self._x_parts: list[_XPart] | None = None  # `_dense_one`'s, on its first call
        if not expand:  # a categorical theta: no smooth series, dense solves at each level
            pass
        elif gp.q == 1:
            self.cheb = self._expand(tol)
        elif gp.q == 2 and self.d == 1:
            self.cheb2 = self._expand2(tol)
        if self.cheb is not None and self.d == 1:
            cm, cv = _trim(self.cheb[0][:, 0], self.cheb[1][:, 0, 0])
            self._const = (cm[0], cv[0])
            self._pairs = tuple(zip(cm[:0:-1], cv[:0:-1], strict=True))
        elif self.cheb is not None:  # whiten the coefficients once: L^-1 mean_k, L^-1 C_k L^-T
            cm, cv = self.cheb
            k, d = cm.shape
            self._zw = solve_triangular(self.L, self.z, lower=True)
            self._cmw = solve_triangular(self.L, cm.T, lower=True).T
            a = solve_triangular(self.L, cv.transpose(1, 0, 2).reshape(d, k * d), lower=True)
            a = a.reshape(d, k, d).transpose(1, 2, 0)  # (k, d, d): (L^-1 C_k)^T
            b = solve_triangular(self.L, a.transpose(1, 0, 2).reshape(d, k * d), lower=True)
            self._cvw = b.reshape(d, k, d).transpose(1, 0, 2)
            self._orders = np.arange(k)

    def _dense_one(self, theta: list[float]) -> tuple[np.ndarray, np.ndarray]:
        """mean (d,) and covariance (d, d) of u at one unit-scale theta (q floats): ``_dense``'s
        values (the same operations, so the same bits) with the x_obs parts computed once."""
        gp = self.gp
        if gp.coef is not None:  # a GLS mean basis: the general path
            mean, cov = self._dense(np.array([theta], dtype=float))
            return mean[0], cov[0]
        if self._x_parts is None:
            self._x_parts = [_XPart.of(gp, self.x, c) for c in range(gp.p_u)]
        parts = []
        for c, part in enumerate(self._x_parts):
            r = part.rx * correlation_row(theta, part.t_cols, part.beta_t, part.cat_t)
            r /= gp.lamUz[c]  # (n, m): Sigma_UW
            v = lower_solve(gp.chol[c], r.T).T  # (n, m): (L_W^-1 Sigma_UW^T)^T
            parts.append((r @ gp.alpha[c], part.prior - np.einsum("im,jm->ij", v, v)))
        if len(parts) == 1:
            return parts[0]
        n = self.x.shape[0]
        cov = np.zeros((self.d, self.d))
        for c, (_, block) in enumerate(parts):
            cov[c * n : (c + 1) * n, c * n : (c + 1) * n] = block
        return np.concatenate([mean for mean, _ in parts]), cov

    def _dense(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """mean (G, d) and covariance (G, d, d) of u at unit-scale theta (G, q)."""
        mean, cov = self.gp.predict(self.x, theta)
        G = theta.shape[0]
        out = np.zeros((G, self.d, self.d))
        n = self.x.shape[0]
        for c in range(self.gp.p_u):
            out[:, c * n : (c + 1) * n, c * n : (c + 1) * n] = cov[:, c]
        return mean.reshape(G, self.d), out

    def _expand(self, tol: float) -> tuple[np.ndarray, np.ndarray] | None:
        """Chebyshev coefficients (deg + 1, d) and (deg + 1, d, d) on theta in [0, 1], or None."""
        s_test = np.linspace(-1.0, 1.0, 257)
        m_ex, v_ex = self._dense(((s_test + 1.0) / 2.0)[:, None])
        d = self.d
        scale_m = max(1.0, float(np.max(np.abs(m_ex))))
        # |cov_ij| <= sqrt(v_ii v_jj); a variance zero or negative by rounding (a nugget near
        # float64's resolution) gives NaN or inf here, so no series passes: dense solves
        with np.errstate(invalid="ignore", divide="ignore"):
            scale_v = np.sqrt(np.einsum("gii,gjj->gij", v_ex, v_ex))
        for deg in CHEB_DEGREES:
            nodes = np.cos(np.pi * (np.arange(deg + 1) + 0.5) / (deg + 1))
            m, v = self._dense(((nodes + 1.0) / 2.0)[:, None])
            cm = cheb.chebfit(nodes, m, deg)
            cv = cheb.chebfit(nodes, v.reshape(-1, d * d), deg)
            err_m = np.max(np.abs(cheb.chebval(s_test, cm).T - m_ex)) / scale_m
            with np.errstate(invalid="ignore", divide="ignore"):
                diff = np.abs(cheb.chebval(s_test, cv).T.reshape(-1, d, d) - v_ex)
                err_v = np.max(diff / scale_v)
            if err_m <= tol and err_v <= 10 * tol:
                return cm, cv.reshape(deg + 1, d, d)
        return None

    def _expand2(self, tol: float) -> tuple[np.ndarray, np.ndarray] | None:
        """2-D Chebyshev coefficients (deg + 1, deg + 1) of the mean and variance of u (d = 1)
        on theta in [0, 1]^2 (q = 2), or None."""
        s_test = np.linspace(-1.0, 1.0, 33)
        test = np.column_stack([g.ravel() for g in np.meshgrid(s_test, s_test, indexing="ij")])
        m_ex, v_ex = self._dense((test + 1.0) / 2.0)
        m_ex, v_ex = m_ex[:, 0], v_ex[:, 0, 0]
        scale_m = max(1.0, float(np.max(np.abs(m_ex))))
        for deg in CHEB_DEGREES[:3]:
            nodes = np.cos(np.pi * (np.arange(deg + 1) + 0.5) / (deg + 1))
            grid = np.column_stack([g.ravel() for g in np.meshgrid(nodes, nodes, indexing="ij")])
            m, v = self._dense((grid + 1.0) / 2.0)
            coefs = []
            for vals in (m[:, 0], v[:, 0, 0]):
                c = cheb.chebfit(nodes, vals.reshape(deg + 1, deg + 1), deg)  # along theta_1
                coefs.append(cheb.chebfit(nodes, c.T, deg).T)  # then along theta_2
            cm, cv = coefs
            err_m = np.max(np.abs(cheb.chebval2d(test[:, 0], test[:, 1], cm) - m_ex)) / scale_m
            err_v = np.max(np.abs(cheb.chebval2d(test[:, 0], test[:, 1], cv) - v_ex) / v_ex)
            if err_m <= tol and err_v <= 10 * tol:
                return cm, cv
        return None

    def at(self, theta):
        """(e, y2) at unit-scale theta (a sequence of q floats)."""
        if self.cheb2 is not None:
            cm, cv = self.cheb2
            k = np.arange(cm.shape[0])
            t1 = np.cos(k * math.acos(min(1.0, max(-1.0, 2.0 * theta[0] - 1.0))))
            t2 = np.cos(k * math.acos(min(1.0, max(-1.0, 2.0 * theta[1] - 1.0))))
            r = (float(self.z[0]) - float(t1 @ cm @ t2)) / self._sig
            return float(t1 @ cv @ t2) / (self._sig * self._sig), r * r
        if self.cheb is not None and self.d == 1:
            mean, var = _clenshaw2(self._pairs, 2.0 * theta[0] - 1.0)
            r = (float(self.z[0]) - mean - self._const[0]) / self._sig
            return (var + self._const[1]) / (self._sig * self._sig), r * r
        if self.cheb is not None:
            t = np.cos(self._orders * math.acos(min(1.0, max(-1.0, 2.0 * theta[0] - 1.0))))
            zw = self._zw - t @ self._cmw
            b = np.tensordot(t, self._cvw, 1)
        else:
            mean, cov = self._dense_one(theta)
            if self.d == 1:
                r = (float(self.z[0]) - float(mean[0])) / self._sig
                return float(cov[0, 0]) / (self._sig * self._sig), r * r
            zw = lower_solve(self.L, self.z - mean)
            a = lower_solve(self.L, cov)
            b = lower_solve(self.L, a.T)
        e, vecs = _eigh(0.5 * (b + b.T))
        y = vecs.T @ zw
        return np.maximum(e, 0.0), y * y


def _eigh(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``np.linalg.eigh(a)`` of a finite symmetric float64 (d, d): its kernel called directly, so
    the same values without the wrapper's checks and error-state switch (a 3 x 3 in ~2.5 us
    instead of ~8)."""
    if _eigh_lo is None:
        return np.linalg.eigh(a)
    e, vecs = _eigh_lo(a, signature="d->dd")
    if math.isnan(e[0]):  # as np.linalg.eigh's LinAlgError (only a non-finite input gets here)
        raise GPMSAError("the eigendecomposition of the whitened predictive covariance failed")
    return e, vecs


def _loglik(ey, lam: float) -> float:
    """log p(u | theta, lamOs) up to a constant, from the whitened (e, y2)."""
    e, y2 = ey
    if isinstance(e, float):
        v = e + 1.0 / lam
        return -0.5 * (math.log(v) + y2 / v)
    v = e + 1.0 / lam
    return float(-0.5 * np.add.reduce(np.log(v) + y2 / v))  # np.sum without its wrapper


@dataclass(frozen=True)
class ChainResult:
    """Draws of one chain: theta (n, q) unit scale, lamOs (n,), emulator-set index (n,),
    log posterior (n,) up to a constant, acceptance rate and step width per element; the
    joint level moves' offsets (categorical theta position -> ``level_moves.level_offsets``
    (n_levels, n_shifted), unit scale) and the shifted elements' positions (none without a
    categorical theta)."""

    theta: np.ndarray
    lamOs: np.ndarray
    index: np.ndarray
    log_post: np.ndarray
    accept_rate: np.ndarray
    widths: np.ndarray
    level_offsets: dict = field(default_factory=dict)
    level_shifted: tuple = ()


class CalibrationSampler:
    """Metropolis-within-Gibbs over theta (q,), lamOs and (for several emulator parameter sets)
    the set index.

    Args:
        gps: the emulator's GP at one or more parameter sets.
        data: the reduced observations.
        priors: the emulator's priors (theta prior); the lamOs prior is ``data.lamos``.
        log_prior: optional extra log prior of unit-scale theta (q,) -> float.
        init_lamos: start of lamOs (default GPM/SA's max(20, a/b) of its prior); see
            ``gpmsa.calibration.observations.lamos_start``.
        constraint: allowed region of unit-scale theta (zero prior mass outside; None: all).
        init_theta: start of unit-scale theta (q,) (default GPM/SA's 0.5).
        theta_levels: per calibration parameter, its levels on the unit scale if categorical
            (uniform prior over them, proposals to another level drawn uniformly), else None;
            None: every parameter continuous.
        held_theta: position -> unit-scale value of the theta elements held there (never
            proposed; ``calibrate(fixed={"theta": ...})``); None: none.
        held_lamos: lamOs held at this value (never proposed); None: sampled.
    """

    def __init__(
        self,
        gps: list[FixedGP],
        data: Observations,
        priors: Priors,
        log_prior: Callable[[np.ndarray], float] | None = None,
        init_lamos: float | None = None,
        constraint: ThetaConstraint | None = None,
        init_theta: np.ndarray | None = None,
        theta_levels: list[tuple[float, ...] | None] | None = None,
        held_theta: dict[int, float] | None = None,
        held_lamos: float | None = None,
    ) -> None:
        self.q = gps[0].q
        self.levels = [None] * self.q if theta_levels is None else list(theta_levels)
        if len(self.levels) != self.q:
            raise GPMSAError(f"theta_levels has {len(self.levels)} entries for q = {self.q}")
        smooth = all(lv is None for lv in self.levels)
        self.preds = [ThetaPredictive(gp, data, expand=smooth) for gp in gps]
        self.priors = priors
        priors.theta_moments(self.q)  # per-element priors: one per calibration parameter
        self.theta_priors = [priors.theta_prior(k) for k in range(self.q)]  # (mean, sd) each
        self.lamos = data.lamos
        self.lam_power = data.lamos.shape - 1.0 - 0.5 * data.obs.n_null
        self.extra = log_prior
        lo = data.lamos
        self.init_lamos = max(20.0, lo.shape / lo.rate) if init_lamos is None else init_lamos
        self.held_lamos = held_lamos is not None
        if held_lamos is not None:
            self.init_lamos = float(held_lamos)
        self.constraint = constraint
        start = [0.5] * self.q if init_theta is None else [float(v) for v in init_theta]
        held_theta = {} if held_theta is None else dict(held_theta)
        for k, v in held_theta.items():
            start[k] = float(v)
        self.free = [k for k in range(self.q) if k not in held_theta]  # the elements proposed
        self.init_theta = snap_to_levels(start, self.levels).tolist()  # categorical: nearest level
        if constraint is not None:  # named as Problem.with_fixed names a held theta
            what = "calibrate" if not held_theta else "fixed theta (held elements)"
            what = "fixed theta" if len(held_theta) == self.q else what
            constraint.check_start(np.array(self.init_theta), what)

    def _initial(self) -> tuple[list[float], float, int]:
        """GPM/SA's initial (theta, lamOs, set index) of a chain."""
        return self.init_theta, self.init_lamos, 0

    def _held(self, start: tuple) -> tuple[list[float], float, int]:
        """A given start (theta, lamOs, set index) with the held elements at their values."""
        theta, lam, k = start
        theta = [float(v) for v in theta]
        for i in set(range(self.q)) - set(self.free):
            theta[i] = self.init_theta[i]
        return theta, self.init_lamos if self.held_lamos else float(lam), int(k)

    def log_post_at(self, start: tuple[list[float], float, int]) -> float:
        """The log posterior (up to a constant) at a chain's start (theta, lamOs, set index),
        as ``run(start=)`` takes it: -inf where the priors or the constraint give it no mass."""
        theta, lam, k = self._held(start)
        lp = self._log_prior_theta(theta) + self._log_prior_lamos(lam)
        return lp if lp == -math.inf else lp + _loglik(self.preds[k].at(theta), lam)

    def _log_prior_theta(self, theta: list[float]) -> float:
        """Truncated-normal prior of unit-scale theta, element k under its own (mean, sd) (a
        categorical element: uniform over its levels), plus the extra prior; pure Python."""
        lp = 0.0
        for t, lv, (mean, sd) in zip(theta, self.levels, self.theta_priors, strict=True):
            if lv is not None:  # uniform over the levels
                if t not in lv:
                    return -math.inf
                continue
            if not 0.0 < t < 1.0:
                return -math.inf
            z = (t - mean) / sd
            lp -= 0.5 * z * z
        if self.constraint is not None and not self.constraint(np.array(theta)):
            return -math.inf
        if self.extra is not None:
            lp += float(self.extra(np.array(theta)))
        return lp

    def _log_prior_lamos(self, lam: float) -> float:
        """lamOs's log prior, with the reduced data's null term (``ObsProblem.null_term``): the
        only terms in lamOs beyond ``_loglik``."""
        p = self.lamos
        if not p.lower < lam < p.upper:
            return -math.inf
        return self.lam_power * math.log(lam) - p.rate * lam

    def run(
        self,
        n_iter: int,
        rng: np.random.Generator,
        *,
        tune: bool = True,
        tune_rounds: int = tuning.N_BURN,
        tune_levels: int = tuning.N_LEVELS,
        widths: np.ndarray | None = None,
        progress: bool = False,
        start: tuple[list[float], float, int] | None = None,
        proportional: bool | None = None,
    ) -> ChainResult:
        """Tune (optionally, GPM/SA's stepsize), then ``n_iter`` sweeps from GPM/SA's initials.

        ``widths``: (q + 1,) the step widths to start from (None: GPM/SA's). ``start``: the
        chain's (unit theta (q,), lamOs, emulator-set index) instead of the initials (a
        continuation, ``calibrate(init=)``; held elements are set to their values).
        ``proportional``: lamOs steps by GPM/SA's proportional step (None: ``not tune``)."""
        q = self.q
        names = ["theta"] * q + ["lamOs"]
        w = np.array([THETA_WIDTH] * q + [self.init_lamos / 2.0]) if widths is None else widths
        state = _State(self, *(self._initial() if start is None else self._held(start)))
        prop_mh = not tune if proportional is None else proportional
        n_tune = tune_rounds * tune_levels if tune else 0
        with progress_bar(progress, n_iter + n_tune, "calibrate", "it", mininterval=0.1) as bar:
            if tune:
                bar.set_description("calibrate: tuning step widths")
                cands = tuning.level_widths(names, w, tune_levels)
                acc = np.zeros((tune_levels, q + 1))
                levels = [c.tolist() for c in cands]
                for _ in range(tune_rounds):
                    u = rng.random((tune_levels, 2 * (q + 2))).tolist()
                    for lev in range(tune_levels):
                        state.sweep(levels[lev], False, acc[lev], u[lev])
                    bar.update(tune_levels)
                w = tuning.choose_widths(w, cands, acc, tune_rounds)
            state.learn_level_shifts()  # frozen before the draws (gpmsa.mcmc.level_moves)
            bar.set_description("calibrate: sampling")
            widths_l = w.tolist()
            out = []
            accepted = np.zeros(q + 1)
            block = 1000
            for start in range(0, n_iter, block):
                u = rng.random((min(block, n_iter - start), 2 * (q + 2))).tolist()
                for row in u:
                    state.sweep(widths_l, prop_mh, accepted, row)
                    out.append((*state.theta, state.lam, state.k, state.log_post()))
                bar.update(len(u))
        arr = np.array(out)
        shifted = next(iter(state.shifts.values()))[2] if state.shifts else ()
        return ChainResult(
            theta=arr[:, :q], lamOs=arr[:, q], index=arr[:, q + 1].astype(np.int64),
            log_post=arr[:, q + 2], accept_rate=accepted / max(n_iter, 1), widths=w,
            level_offsets=dict(state.offsets), level_shifted=tuple(shifted),
        )  # fmt: skip


class _State:
    """The current (theta, lamOs, set index) of one chain and its sweep (Python floats)."""

    def __init__(self, s: CalibrationSampler, theta: list[float], lam: float, k: int) -> None:
        self.s = s
        self.theta = list(theta)
        self.lam = lam
        self.k = k
        self.ey = s.preds[k].at(self.theta)
        self.ll = _loglik(self.ey, lam)
        self.lp_theta = s._log_prior_theta(self.theta)
        self.lp_lam = s._log_prior_lamos(lam)
        self.shifts: dict[int, tuple] = {}  # categorical element -> its level move's shifts
        self.offsets: dict[int, np.ndarray] = {}  # categorical element -> its level_offsets

    def learn_level_shifts(self) -> None:
        """The joint level moves' shifts of the continuous free theta elements
        (``gpmsa.mcmc.level_moves``), from the conditional modes at each level at the current
        lamOs and set; none without a categorical and a continuous free element."""
        s = self.s
        cat = [i for i in s.free if s.levels[i] is not None and len(s.levels[i]) > 1]
        cont = [j for j in s.free if s.levels[j] is None]
        if not cat or not cont:
            return
        pred, lam = s.preds[self.k], self.lam

        def log_post(theta: np.ndarray) -> float:
            th = theta.tolist()
            lp = s._log_prior_theta(th)
            return lp if lp == -math.inf else lp + _loglik(pred.at(th), lam)

        for i in cat:
            off = level_moves.level_offsets(log_post, np.array(self.theta), i, s.levels[i], cont)
            rows = {v: r for r, v in enumerate(s.levels[i])}
            self.shifts[i] = (rows, level_moves.shift_table(off), cont)
            self.offsets[i] = off

    def log_post(self) -> float:
        """Log posterior up to a constant."""
        return self.ll + self.lp_theta + self.lp_lam

    def sweep(self, widths: list[float], prop_mh: bool, accepted, u: list[float]) -> None:
        """One sweep: each theta element, lamOs, then (several sets) the set index; held elements
        (``held_theta``, ``held_lamos``) are skipped, their random numbers drawn all the same.

        ``u``: 2 (q + 2) uniform numbers (a step and an acceptance draw per element).
        """
        s = self.s
        q = s.q
        pred = s.preds[self.k]
        for i in s.free:
            cand = list(self.theta)
            levels = s.levels[i]
            if levels is None:
                cand[i] += widths[i] * (u[2 * i] - 0.5)
            elif len(levels) < 2:
                continue
            else:  # another level, uniformly: a symmetric proposal
                others = [v for v in levels if v != cand[i]]
                new = others[min(int(u[2 * i] * len(others)), len(others) - 1)]
                if i in self.shifts:  # with the continuous elements (level_moves)
                    rows, table, cont = self.shifts[i]
                    for j, d in zip(cont, table[rows[cand[i]]][rows[new]], strict=True):
                        cand[j] += d
                cand[i] = new
            lp_new = s._log_prior_theta(cand)
            if lp_new == -math.inf:
                continue
            ey = pred.at(cand)
            ll = _loglik(ey, self.lam)
            if log_uniform(u[2 * i + 1]) < ll - self.ll + lp_new - self.lp_theta:
                self.theta, self.ey, self.ll, self.lp_theta = cand, ey, ll, lp_new
                accepted[i] += 1
        if not s.held_lamos:
            x = self.lam
            step = u[2 * q] - 0.5
            corr = 0.0
            if prop_mh:  # GPM/SA's proportional step for an untuned precision, its correction
                w0 = max(1.0, x / 3.0)
                cand_l = x + w0 * 2.0 * step
                w1 = max(1.0, cand_l / 3.0)
                if x > cand_l + w1:
                    cand_l = -1.0
                else:
                    corr = math.log(w0 / w1)
            else:
                cand_l = x + widths[q] * step
            lp_new = s._log_prior_lamos(cand_l) if cand_l > 0.0 else -math.inf
            if lp_new != -math.inf:
                ll = _loglik(self.ey, cand_l)
                if log_uniform(u[2 * q + 1]) < ll - self.ll + lp_new - self.lp_lam + corr:
                    self.lam, self.ll, self.lp_lam = cand_l, ll, lp_new
                    accepted[q] += 1
        if len(s.preds) > 1:
            k = int(u[2 * q + 2] * len(s.preds))
            ey = s.preds[k].at(self.theta)
            ll = _loglik(ey, self.lam)
            if log_uniform(u[2 * q + 3]) < ll - self.ll:
                self.k, self.ey, self.ll = k, ey, ll
