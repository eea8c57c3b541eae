"""The calibration-only GPM/SA model: the emulator's GP with its parameters held fixed.

With the emulator parameters fixed, the first likelihood term N(w; 0, Sigma_W) is constant in theta
and the calibration needs only the second: the predictive of the observation's basis weights u at
(x_obs, theta) given the simulation weights w,

    u | w, theta ~ N(mu(theta), S(theta) + Sigma_obs / lamOs),
    mu(theta) = Sigma_UW Sigma_W^-1 w,   S(theta) = Sigma_U - Sigma_UW Sigma_W^-1 Sigma_UW^T,

block-diagonal over the p_u basis components (Higdon et al. 2008; GPM/SA's no-discrepancy model).
Everything here works on plain arrays in unit (x, theta) and standardised (u) units; the Cholesky of
Sigma_W and alpha = Sigma_W^-1 w are computed once.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.polynomial import chebyshev as cheb
from scipy.linalg import cho_solve, cholesky, lapack, solve_triangular
from scipy.special import gammainc, gammainccinv, gammaln

from gpmsa._fp_state import underflow_as_zero
from gpmsa.errors import GPMSAError
from gpmsa.limits import check_memory
from gpmsa.model.correlation import correlation
from gpmsa.model.mean_basis import GLS, MeanBasis
from gpmsa.model.nugget import not_positive_definite

_LOG_2PI = float(np.log(2.0 * np.pi))
_LOG_2 = float(np.log(2.0))
COARSE_STRIDE = 8
TRUNCATED_REFINE = 8
_CHUNK = 1 << 16
"""Elements (theta nodes x log-lamOs nodes x data) of `_log_integrand`'s work arrays per block
of theta nodes: blocks that stay in cache (7,161 nodes x 60 x 40 data: 105 ms instead of 240 in
one pass); each node's row is computed as in one pass, to the bit."""


class FixedGP:
    """The emulator's GP over (x, t) with fixed betaU, lamUz, lamWs, lamWOs.

    Args (unit/standardised units):
        x_sim: (m, p) known inputs of the simulation design on [0, 1].
        t_sim: (m, q) calibration parameters of the design on [0, 1].
        w: (m, p_u) simulation basis weights.
        lam_sim: (p_u,) diag(K^T K).
        betaU: (p + q, p_u) correlation parameters (x rows first).
        lamUz: (p_u,) GP precisions; lamWs: (p_u,) nugget precisions; lamWOs: scalar.
        categorical: boolean mask (p + q,) of categorical inputs (None: none).
        mean_basis: the weights' mean basis (None: zero mean); its coefficients are the GLS
            estimates at these parameters (``coef`` (p_u, k)), ``alpha`` = Sigma_W^-1 (w - H c).
    """

    def __init__(
        self,
        x_sim: np.ndarray,
        t_sim: np.ndarray,
        w: np.ndarray,
        lam_sim: np.ndarray,
        betaU: np.ndarray,
        lamUz: np.ndarray,
        lamWs: np.ndarray,
        lamWOs: float,
        categorical: np.ndarray | None = None,
        mean_basis: MeanBasis | None = None,
    ) -> None:
        self.x_sim = np.asarray(x_sim, dtype=float)
        self.t_sim = np.asarray(t_sim, dtype=float)
        self.p = self.x_sim.shape[1]
        self.q = self.t_sim.shape[1]
        self.m = self.x_sim.shape[0]
        w = np.asarray(w, dtype=float).reshape(self.m, -1)
        self.p_u = w.shape[1]
        self.betaU = np.asarray(betaU, dtype=float).reshape(self.p + self.q, self.p_u)
        self.lamUz = np.asarray(lamUz, dtype=float).ravel()
        self.lamWs = np.asarray(lamWs, dtype=float).ravel()
        lam_sim = np.asarray(lam_sim, dtype=float).ravel()
        lamWOs = float(np.asarray(lamWOs).ravel()[0])
        z = np.hstack([self.x_sim, self.t_sim])
        self.cat = categorical
        self.cat_x = None if categorical is None else categorical[: self.p]
        self.cat_t = None if categorical is None else categorical[self.p :]
        self.mean_basis = mean_basis
        H = None if mean_basis is None else mean_basis.matrix(z)
        self.coef = None
        check_memory(
            8.0 * self.m * self.m * (self.p_u + 2 + self.p + self.q),
            f"the emulator's GP ({self.m} runs, {self.p_u} components: an m x m factor each)",
        )
        chol = np.empty((self.p_u, self.m, self.m))
        alpha = np.empty((self.p_u, self.m))
        for c in range(self.p_u):
            sigma = correlation(z, None, self.betaU[:, c], categorical) / self.lamUz[c]
            sigma[np.diag_indices_from(sigma)] += 1.0 / (lam_sim[c] * lamWOs) + 1.0 / self.lamWs[c]
            try:
                chol[c] = cholesky(sigma, lower=True)
            except (np.linalg.LinAlgError, ValueError) as exc:
                prm = {"betaU": self.betaU, "lamUz": self.lamUz, "lamWs": self.lamWs,
                       "lamWOs": lamWOs}  # fmt: skip
                raise GPMSAError(
                    not_positive_definite(c, prm, lam_sim, self.m, "at these emulator parameters")
                ) from exc
            if H is None:
                alpha[c] = cho_solve((chol[c], True), w[:, c])
                continue
            gls = GLS.of(chol[c], w[:, c], H)
            alpha[c] = gls.alpha
            self.coef = np.zeros((self.p_u, H.shape[1])) if self.coef is None else self.coef
            self.coef[c] = gls.coef
        self.chol = chol
        self.alpha = alpha

    def corr_x(self, x: np.ndarray, c: int) -> np.ndarray:
        """R over the x part between points x (n, p) and the design: (n, m)."""
        return correlation(x, self.x_sim, self.betaU[: self.p, c], self.cat_x)

    def corr_t(self, theta: np.ndarray, c: int) -> np.ndarray:
        """R over the t part between points theta (G, q) and the design: (G, m)."""
        return correlation(theta, self.t_sim, self.betaU[self.p :, c], self.cat_t)

    def prior_cov(self, x: np.ndarray, c: int) -> np.ndarray:
        """Sigma_U for component c among obs points at one theta (n, n), nugget included."""
        r = correlation(x, None, self.betaU[: self.p, c], self.cat_x) / self.lamUz[c]
        return r + np.eye(x.shape[0]) / self.lamWs[c]

    def predict(self, x: np.ndarray, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Predictive of u at (x_j, theta_g) given w, by dense solves.

        Args:
            x: (n, p) unit-scale known inputs of the n observations.
            theta: (G, q) unit-scale calibration parameters.

        Returns:
            mean (G, p_u, n) and covariance (G, p_u, n, n) in standardised weight units.
        """
        n, G = x.shape[0], theta.shape[0]
        check_memory(
            8.0 * G * n * (3.0 * self.m + 2.0 * self.p_u * n),
            f"the emulator's predictive at {G} theta values x {n} observation rows ({self.m} runs)",
        )
        mean = np.empty((G, self.p_u, n))
        cov = np.empty((G, self.p_u, n, n))
        h = None
        if self.coef is not None:  # the GLS mean at every (theta_g, x_j): (G * n, k)
            h = self.mean_basis.matrix(np.hstack([np.tile(x, (G, 1)), np.repeat(theta, n, 0)]))
        for c in range(self.p_u):
            rx = self.corr_x(x, c)
            rt = self.corr_t(theta, c)
            r = np.multiply(rt[:, None, :], rx[None, :, :], out=np.empty((G, n, self.m)))
            r /= self.lamUz[c]  # in place: one array of G n m, not three
            r = r.reshape(G * n, self.m)
            mean[:, c, :] = (r @ self.alpha[c]).reshape(G, n)
            if h is not None:
                mean[:, c, :] += (h @ self.coef[c]).reshape(G, n)
            # r.T is the Fortran-ordered right-hand side LAPACK takes: solved in place, not
            # copied (r is not needed after it)
            v = solve_triangular(self.chol[c], r.T, lower=True, overwrite_b=True)
            v = v.T.reshape(G, n, self.m)
            cov[:, c] = self.prior_cov(x, c)[None] - np.einsum("gim,gjm->gij", v, v)
        return mean, cov


def lower_solve(L: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``solve_triangular(L, b, lower=True)`` for float64 arrays without its input checks: the
    same LAPACK call on the same layout, so the same result, in a few microseconds instead of
    ~50 (a fast-path proposal makes several such solves of small systems)."""
    if L.flags.f_contiguous:
        x, info = lapack.dtrtrs(L, b, lower=1)
    else:  # the transposed system, as scipy solves it for a C-ordered factor
        x, info = lapack.dtrtrs(L.T, b, lower=0, trans=1)
    if info != 0:
        raise GPMSAError(f"a triangular solve failed (LAPACK dtrtrs info {info})")
    return x


def _cheb_coefficients(gp: FixedGP, c: int, tol: float, max_deg: int) -> np.ndarray | None:
    """Chebyshev coefficients (deg + 1, m) of x -> R_x(x, x_i) on x in [0, 1] (p == 1)."""
    beta = gp.betaU[0, c]
    test = np.linspace(0.0, 1.0, 401)
    exact = np.exp(-beta * (test[:, None] - gp.x_sim[None, :, 0]) ** 2)
    deg = 8
    while deg <= max_deg:
        nodes = np.cos(np.pi * (np.arange(deg + 1) + 0.5) / (deg + 1))
        vals = np.exp(-beta * ((nodes[:, None] + 1.0) / 2.0 - gp.x_sim[None, :, 0]) ** 2)
        coef = cheb.chebfit(nodes, vals, deg)
        if np.max(np.abs(cheb.chebval(2.0 * test - 1.0, coef).T - exact)) <= tol:
            return coef
        deg *= 2
    return None


def chebyshev_plan(gp: FixedGP, tol: float = 1e-14, max_deg: int = 128) -> tuple | None:
    """Per component, the Chebyshev coefficients (deg + 1, m) of x -> R_x(x, x_i) that let a
    `GridPredictor` on ``gp`` skip the solves per update (accurate to ``tol``, degree at most
    ``max_deg``); None where it solves densely: p > 1, a categorical input, a mean basis, or an
    expansion that does not reach ``tol``."""
    if not (gp.p == 1 and gp.cat is None and gp.mean_basis is None):
        return None
    coefs = tuple(_cheb_coefficients(gp, c, tol, max_deg) for c in range(gp.p_u))
    return None if any(cf is None for cf in coefs) else coefs


def predictor_bytes(gp: FixedGP, n_nodes: int, plan: tuple | None) -> tuple[float, float]:
    """Bytes a `GridPredictor` on ``n_nodes`` theta nodes keeps (R_t alpha, and H per
    component: nodes x (degree + 1)^2) and the most it needs besides while it is built (one
    component's R_t with the work arrays of its correlation and scaling, 3 nodes x m, or R_t
    and its Chebyshev products and their solve, nodes x m x (1 + 2 (degree + 1)))."""
    sizes = [0] * gp.p_u if plan is None else [cf.shape[0] for cf in plan]
    kept = 8.0 * n_nodes * (gp.p_u * gp.m + sum(na * na for na in sizes))
    return kept, 8.0 * n_nodes * gp.m * max(3, 1 + 2 * max(sizes))


class GridPredictor:
    """Predictive of u on a fixed theta grid for any x_obs, with a per-update cost of O(G m n).

    Precomputes, per grid node g and component c, R_t(theta_g) and, where ``plan`` (from
    `chebyshev_plan`) is not None, the matrix H_g = E_g^T Sigma_W^-1 E_g of the Chebyshev
    expansion of R_x(x, x_i) in x, so that Sigma_UW Sigma_W^-1 Sigma_UW^T = T(x) H_g T(x)^T needs
    no solve per update. Falls back to dense solves (`FixedGP.predict`) without a plan and for x
    outside [0, 1]. Its memory (`predictor_bytes`) is the caller's to check.
    """

    def __init__(self, gp: FixedGP, theta: np.ndarray, plan: tuple | None) -> None:
        self.gp = gp
        self.theta = np.asarray(theta, dtype=float)
        G = self.theta.shape[0]
        self.rt_alpha = np.empty((gp.p_u, G, gp.m))
        self.H: list[np.ndarray] | None = None if plan is None else []
        for c in range(gp.p_u):
            rt = gp.corr_t(self.theta, c) / gp.lamUz[c]
            self.rt_alpha[c] = rt * gp.alpha[c][None, :]
            if self.H is not None:  # its work arrays freed before the next component's
                self.H.append(_chebyshev_products(gp, c, rt, plan[c]))

    def predict(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """mean (G, p_u, n) and covariance (G, p_u, n, n) of u at (x, theta_g); x (n, p) unit."""
        gp = self.gp
        inside = bool(np.all((x >= 0.0) & (x <= 1.0)))
        if self.H is None or not inside:
            return gp.predict(x, self.theta)
        n, G = x.shape[0], self.theta.shape[0]
        mean = np.empty((G, gp.p_u, n))
        cov = np.empty((G, gp.p_u, n, n))
        s = 2.0 * x[:, 0] - 1.0
        for c in range(gp.p_u):
            mean[:, c, :] = self.rt_alpha[c] @ gp.corr_x(x, c).T
            H = self.H[c]
            na = H.shape[1]
            T = _cheb_vander(s, na)  # (n, na)
            HT = (H.reshape(G * na, na) @ T.T).reshape(G, na, n)
            cov[:, c] = gp.prior_cov(x, c)[None] - np.matmul(T[None], HT)
        return mean, cov


def _chebyshev_products(gp: FixedGP, c: int, rt: np.ndarray, coef: np.ndarray) -> np.ndarray:
    """H_g = E_g^T Sigma_W^-1 E_g (G, na, na) of component ``c``: E_g (m, na) the Chebyshev
    coefficients ``coef`` (na, m) of R_x(x, x_i) times R_t(theta_g, t_i) (``rt`` (G, m))."""
    G, na = rt.shape[0], coef.shape[0]
    # the solve's right-hand sides (m, G na), built in the Fortran order LAPACK takes (the
    # same products, not copied into it) and solved in place
    e = (rt[:, None, :] * coef[None, :, :]).reshape(G * na, gp.m).T
    v = solve_triangular(gp.chol[c], e, lower=True, overwrite_b=True)
    del e
    v = v.reshape(gp.m, G, na)
    return np.einsum("mga,mgb->gab", v, v)


def _cheb_vander(s: np.ndarray, size: int) -> np.ndarray:
    """Chebyshev polynomials T_k(s) = cos(k arccos s), k < size, at s (n,) in [-1, 1]: (n, size)."""
    return np.cos(np.outer(np.arccos(np.clip(s, -1.0, 1.0)), np.arange(size)))


@dataclass(frozen=True)
class LamOsPrior:
    """Gamma(shape, rate) prior of the observation precision lamOs, truncated to (lower, upper)."""

    shape: float
    rate: float
    lower: float = 0.0
    upper: float = np.inf

    def log_norm(self) -> float:
        """log P(lower < lamOs < upper) under the untruncated Gamma (-inf where it rounds to 0)."""
        mass = gammainc(self.shape, self.rate * self.upper) - gammainc(
            self.shape, self.rate * self.lower
        )
        with np.errstate(divide="ignore"):
            return float(np.log(mass))

    def upper_quantile(self, tail: float) -> float:
        """The value above which the (untruncated) prior has mass `tail`."""
        return float(gammainccinv(self.shape, tail) / self.rate)


@dataclass(frozen=True, eq=False)
class LamOsMarginal:
    """log p(u | theta_g) with lamOs integrated out, and the conditional of log(lamOs) per node.

    Attributes:
        loglik: (G,) log marginal density of the reduced data u at each theta node.
        log_lam: (S,) equally spaced nodes of s = log(lamOs), shared by all theta nodes.
    """

    loglik: np.ndarray
    log_lam: np.ndarray
    _weights: np.ndarray  # (G, S) trapezoid terms, scaled per row
    _sums: np.ndarray  # (G,) their row sums

    def log_cond(self, nodes: np.ndarray) -> np.ndarray:
        """(k, S) log trapezoid weights of the s nodes under p(s | u, theta) at theta ``nodes``
        (indices); each row's exponentials sum to one."""
        with np.errstate(divide="ignore"):
            return np.log(self._weights[nodes]) - np.log(self._sums[nodes, None])


def _whiten(
    mean: np.ndarray, cov: np.ndarray, u: np.ndarray, obs_chol: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues e (G, d) of L^-1 S L^-T and rotated residuals y (G, d) (Sigma_obs = L L^T)."""
    G, d = mean.shape
    if d == 1:
        s = obs_chol[0, 0]
        return cov[:, 0, :] / (s * s), (u[None, :] - mean) / s
    # the solves' right-hand sides (d, G d) are made in the Fortran order LAPACK takes and
    # solved in place: columns g d + j, S_g[:, j], then (L^-1 S_g)^T[:, i]
    z = solve_triangular(obs_chol, (u[None, :] - mean).T, lower=True, overwrite_b=True)  # (d, G)
    rhs = cov.transpose(0, 2, 1).copy().reshape(G * d, d).T  # (a copy: cov is not overwritten)
    a = solve_triangular(obs_chol, rhs, lower=True, overwrite_b=True)  # L^-1 S_g, column-wise
    rhs = np.ascontiguousarray(a.T.reshape(G, d, d).transpose(0, 2, 1)).reshape(G * d, d).T
    b = solve_triangular(obs_chol, rhs, lower=True, overwrite_b=True)
    b = b.T.reshape(G, d, d).transpose(0, 2, 1)  # L^-1 S_g L^-T
    e, vecs = np.linalg.eigh(0.5 * (b + b.transpose(0, 2, 1)))
    return e, np.einsum("gdk,dg->gk", vecs, z)


def _log_integrand(
    s: np.ndarray, e: np.ndarray, y2: np.ndarray, prior: LamOsPrior, const: float, null: int = 0
) -> np.ndarray:
    """log p(u | theta, lamOs) p(lamOs) lamOs at s = log lamOs; s (S,), e, y2 (G, d) -> (G, S);
    ``null``: the reduced data's unobserved directions (``ObsProblem.null_term``)."""
    lam = np.exp(s)
    tail = (prior.shape - 0.5 * null) * s - prior.rate * lam + const
    if e.shape[1] == 1:
        var = e + 1.0 / lam
        return tail - 0.5 * (np.log(var) + y2 / var)
    G, d = e.shape
    out = np.empty((G, s.size))
    rows = max(1, _CHUNK // (s.size * d))
    for g in range(0, G, rows):  # blocks of nodes whose work arrays stay in cache
        var = e[g : g + rows, None, :] + 1.0 / lam[None, :, None]  # (rows, S, d)
        out[g : g + rows] = tail - 0.5 * np.sum(np.log(var) + y2[g : g + rows, None, :] / var,
                                                axis=2)  # fmt: skip
    return out


@underflow_as_zero  # the integrand's far tails underflow to 0 as intended
def lamos_marginal(
    mean: np.ndarray,
    cov: np.ndarray,
    u: np.ndarray,
    obs_chol: np.ndarray,
    prior: LamOsPrior,
    cutoff: float = 25.0,
    max_step: float = 0.45,
    null: int = 0,
) -> LamOsMarginal:
    """Integrate lamOs out of N(u; mean_g, cov_g + Sigma_obs / lamOs) against its prior.

    The integral runs over s = log(lamOs) with the trapezoidal rule, which converges geometrically
    for this smooth integrand that decays at both ends (error in loglik about 1e-8 at the default
    step, checked against adaptive quadrature in the tests). A coarse pass (step 2 in s, on every
    COARSE_STRIDE-th theta node and the nodes of largest residual and smallest variance) finds
    where the integrand is within exp(-cutoff) of a node's peak (widened by one coarse step each
    side); a fine pass (step <= max_step, and <= the posterior sd of s, about
    sqrt(2 / (2 shape + d))) integrates over that window on nodes shared by all theta. Where the
    window reaches a finite prior bound the integrand is cut off, the rule is only second order,
    and the step is divided by TRUNCATED_REFINE.

    Args:
        mean: (G, d) predictive means of u (d = n p_u); cov: (G, d, d) predictive covariances.
        u: (d,) reduced observation data; obs_chol: (d, d) lower Cholesky factor of Sigma_obs.
        prior: the lamOs prior.
        null: the directions of u that no value observed (``ObsProblem.n_null``): their
            log(lamOs) / 2 each is taken off the integrand (``ObsProblem.null_term``).

    Returns:
        LamOsMarginal with loglik = log p(u | theta_g) (all normalising constants included).
    """
    d = mean.shape[1]
    check_memory(
        8.0 * mean.shape[0] * d * (4.0 * d + 4.0),
        f"the exact likelihood at {mean.shape[0]} theta values of {d} reduced observations",
    )
    e, y = _whiten(mean, cov, u, obs_chol)
    e = np.maximum(e, 0.0)
    y2 = y * y
    const, coarse = _prior_terms(prior, d)
    const -= float(np.sum(np.log(np.diag(obs_chol))))
    G = e.shape[0]
    y2_sum = y2.sum(axis=1)
    ends = [G - 1, int(np.argmax(y2_sum)), int(np.argmin(y2_sum)), int(np.argmin(e[:, 0]))]
    probe = np.concatenate([np.arange(0, G, COARSE_STRIDE), ends])
    phi = _log_integrand(coarse, e[probe], y2[probe], prior, const, null)
    keep = (phi >= phi.max(axis=1, keepdims=True) - cutoff).any(axis=0)
    inside = np.flatnonzero(keep)
    lo = coarse[max(inside[0] - 1, 0)]
    hi = coarse[min(inside[-1] + 1, coarse.size - 1)]
    step = min(max_step, np.sqrt(2.0 / (2.0 * prior.shape + d)))
    if (prior.lower > 0.0 and lo <= coarse[0]) or (np.isfinite(prior.upper) and hi >= coarse[-1]):
        step /= TRUNCATED_REFINE  # the integrand is cut off at a bound: the rule is O(step^2)
    n_float = np.ceil((hi - lo) / step) + 1
    check_memory(
        8.0 * G * n_float * (4.0 if d == 1 else 2.0 + d),
        f"the lamOs quadrature ({G} theta nodes x {n_float:.3g} log-lamOs nodes; the lamOs "
        f"prior's shape a = {prior.shape:.6g} sets the step)",
    )
    n_nodes = int(n_float)
    step = (hi - lo) / (n_nodes - 1)
    s = lo + step * np.arange(n_nodes)
    if d == 1 and not null:
        return _fine_pass_scalar(s, step, e[:, 0], y2[:, 0], prior, const)
    phi = _log_integrand(s, e, y2, prior, const, null)
    phi[:, 0] -= _LOG_2
    phi[:, -1] -= _LOG_2
    peak = phi.max(axis=1)
    w = np.exp(phi - peak[:, None])
    sums = w.sum(axis=1)
    return LamOsMarginal(np.log(sums) + peak + np.log(step), s, w, sums)


def _fine_pass_scalar(
    s: np.ndarray, step: float, e: np.ndarray, y2: np.ndarray, prior: LamOsPrior, const: float
) -> LamOsMarginal:
    """The fine pass for d = 1 in linear space: one exp and one sqrt per node instead of a log
    and an exp. Each row is scaled by an upper bound of its integrand, exp(B_g) with
    B_g = max_s tail(s) + max_v (-log(v) / 2 - y2 / (2 v)) over v >= e; rows that underflow
    (a bound more than ~700 above the peak) are recomputed in log space."""
    lam = np.exp(s)
    tail = prior.shape * s - prior.rate * lam + const
    tail_max = float(tail.max())
    v_star = np.maximum(y2, e)
    lik_max = -0.5 * (np.log(v_star) + y2 / v_star)
    r = 1.0 / (e[:, None] + 1.0 / lam[None, :])  # 1 / var, (G, S)
    w = np.sqrt(v_star[:, None] * r) * np.exp(-0.5 * y2[:, None] * (r - 1.0 / v_star[:, None]))
    w *= np.exp(tail - tail_max)[None, :]
    w[:, 0] *= 0.5
    w[:, -1] *= 0.5
    sums = w.sum(axis=1)
    loglik = np.log(sums) + tail_max + lik_max + np.log(step)
    low = ~(sums > 1e-250)
    if low.any():  # the scaling overshot: redo those rows in log space
        phi = _log_integrand(s, e[low, None], y2[low, None], prior, const)
        phi[:, 0] -= _LOG_2
        phi[:, -1] -= _LOG_2
        peak = phi.max(axis=1)
        w[low] = np.exp(phi - peak[:, None])
        sums[low] = w[low].sum(axis=1)
        loglik[low] = np.log(sums[low]) + peak + np.log(step)
    return LamOsMarginal(loglik, s, w, sums)


@lru_cache(maxsize=64)
def _prior_terms(prior: LamOsPrior, d: int) -> tuple[float, np.ndarray]:
    """Normalising constant of the integrand and the coarse s grid, per prior and data size."""
    const = (
        prior.shape * np.log(prior.rate)
        - gammaln(prior.shape)
        - prior.log_norm()
        - 0.5 * d * _LOG_2PI
    )
    with np.errstate(divide="ignore", invalid="ignore"):
        s_hi = float(np.log(min(prior.upper, prior.upper_quantile(1e-17))))
    s_lo = s_hi - 80.0
    if prior.lower > 0.0:
        s_lo = max(s_lo, float(np.log(prior.lower)))
    if not (np.isfinite(const) and np.isfinite(s_hi) and s_lo < s_hi):
        raise GPMSAError(
            f"the lamOs prior Gamma(a={prior.shape:g}, b={prior.rate:g}) on ({prior.lower:g}, "
            f"{prior.upper:g}) has no mass that the grid's integral over lamOs can reach in "
            "float64 (the mass above its lower bound rounds to 0, or its shape is too close to "
            "0); use a lamOs prior with mass in float64's range"
        )
    coarse = np.linspace(s_lo, s_hi, int(np.ceil((s_hi - s_lo) / 2.0)) + 1)
    coarse.flags.writeable = False
    return float(const), coarse
