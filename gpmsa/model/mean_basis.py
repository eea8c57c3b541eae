"""A user-set mean basis for the GP of each basis weight: w_j(z) ~ GP(h(z)^T c_j, Sigma_j).

GPM/SA's default is a zero mean. With a mean basis h (``"constant"``: h(z) = 1; ``"linear"``:
h(z) = [1, z_1, ..., z_d] on the unit-scale inputs z = [x, t]; or a callable of unit-scale
z (n, d) -> (n, k)), the coefficients c_j have a flat prior and are integrated out (as SEPIA's
``mean_basis``, Higdon et al. 2008 section 2):

- the fit samples the restricted (marginal) likelihood of w_j:
  -1/2 log|Sigma| - 1/2 log|H^T Sigma^-1 H| - 1/2 (w - H c^)^T Sigma^-1 (w - H c^),
  with c^ = (H^T Sigma^-1 H)^-1 H^T Sigma^-1 w the GLS estimate (H = h(design), (m, k));
- a prediction at z has mean h(z)^T c^ + r^T Sigma^-1 (w - H c^) and adds to the variance
  g^T (H^T Sigma^-1 H)^-1 g, g = h(z) - H^T Sigma^-1 r (the coefficients' uncertainty);
- the observation term of a joint fit and calibration use the GLS mean h([x_obs, theta]) c^ at
  the current emulator parameters (without the coefficients' variance).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from scipy.linalg import cho_factor, cho_solve, solve_triangular

from gpmsa.errors import GPMSAError

KINDS = ("constant", "linear")
"""The named mean bases (they can be saved in an emulator file; a callable cannot)."""


@dataclass(frozen=True, eq=False)
class MeanBasis:
    """A mean basis: ``kind`` "constant", "linear" or "callable" (then ``fn``), over d inputs.

    >>> MeanBasis("linear", 2).matrix(np.array([[0.5, 1.0]]))
    array([[1. , 0.5, 1. ]])
    """

    kind: str
    d: int
    fn: Callable[[np.ndarray], np.ndarray] | None = None
    k: int | None = None  # a callable's column count on the design (None: not known yet)

    def matrix(self, z: np.ndarray) -> np.ndarray:
        """h at unit-scale points z (n, d): (n, k)."""
        z = np.asarray(z, dtype=np.float64)
        n = z.shape[0]
        if self.kind == "constant":
            return np.ones((n, 1))
        if self.kind == "linear":
            return np.hstack([np.ones((n, 1)), z])
        try:
            raw = np.asarray(self.fn(z.copy()))  # a copy: the callable cannot edit the design
        except GPMSAError:
            raise
        except Exception as exc:
            raise GPMSAError(f"mean_basis callable failed on unit inputs {z.shape}: {exc}") from exc
        if raw.dtype.kind not in "biuf":
            raise GPMSAError(f"mean_basis must return real numbers, got dtype {raw.dtype}")
        h = raw.astype(np.float64)
        if h.ndim == 1:
            h = h[:, None]
        if h.ndim != 2 or h.shape[0] != n or h.shape[1] == 0:
            raise GPMSAError(
                f"mean_basis must return a finite (n, k) matrix, k >= 1, for n = {n} points, "
                f"got shape {h.shape}"
            )
        if self.k is not None and h.shape[1] != self.k:
            raise GPMSAError(
                f"mean_basis returned {h.shape[1]} columns for n = {n} points, but {self.k} on "
                "the simulation design: it must give the same columns at any point"
            )
        if not np.all(np.isfinite(h)) or np.max(np.abs(h)) > MAX_ABS:
            raise GPMSAError(
                f"mean_basis returned NaN, inf or values beyond {MAX_ABS:g} for n = {n} "
                "unit-scale points (scale its columns)"
            )
        return h


MAX_ABS = 1e100
"""Largest |value| a mean basis may return: its GLS products square them."""


MAX_CONDITION = 1e6
"""Largest condition number of a mean basis on the simulation design, its columns scaled to unit
length (`check_rank`). The restricted likelihood factors H^T Sigma_W^-1 H, whose conditioning is
about this number squared times Sigma_W's: over the default priors' support (betaU 1e-4 to 1e3,
lamUz 0.3 to 100, nugget 1e-5 to 0.1; 20 to 200 runs) a basis at 2e6 factored everywhere tried,
its log-determinant term within 0.4 nats of a QR-based one, while from 7e6 (60 runs) it failed at
some parameters and from 2e8 at a third of them."""


def check_rank(basis: MeanBasis, z: np.ndarray, names: list[str] | None = None) -> None:
    """GPMSAError when ``basis``'s columns are linearly dependent on the design z (m, d): its
    GLS coefficients would not be identified; or nearly so, their condition number (columns
    scaled to unit length) above ``MAX_CONDITION``: the GLS term would not factor at every
    emulator parameter. ``names`` (d,): the inputs' names, which name a "linear" basis's columns
    in the message (else z0, z1, ...)."""
    h = basis.matrix(z)
    rank = np.linalg.matrix_rank(h)
    if rank < h.shape[1]:
        raise GPMSAError(
            f"the mean basis is collinear on the simulation design: its {h.shape[1]} columns "
            f"have rank {rank}"
        )
    cond, vt = _scaled_condition(h)
    if cond <= MAX_CONDITION:
        return
    if basis.kind == "linear":
        labels = ["the constant", *(names or [f"z{i}" for i in range(basis.d)])]
    else:
        labels = [str(i) for i in range(h.shape[1])]
    weight = np.abs(vt[-1])
    involved = ", ".join(labels[i] for i in np.flatnonzero(weight > 0.1 * weight.max()))
    raise GPMSAError(
        f"the mean basis is nearly collinear on the simulation design: its columns {involved} "
        f"are close to linearly dependent (condition number {cond:.3g} with the columns scaled "
        f"to unit length, above MAX_CONDITION = {MAX_CONDITION:g}), so the GLS term "
        "H^T Sigma_W^-1 H would not factor at every emulator parameter; drop one of them or "
        "orthogonalise the columns (e.g. Legendre polynomials of z instead of its powers)"
    )


def _scaled_condition(h: np.ndarray) -> tuple[float, np.ndarray]:
    """Condition number of h (m, k) with its columns scaled to unit length, and the right
    singular vectors (k, k; the last row: the columns' nearest linear dependence)."""
    _, s, vt = np.linalg.svd(h / np.linalg.norm(h, axis=0), full_matrices=False)
    return float(s[0] / s[-1]), vt


def make(spec, d: int, m: int | None = None) -> MeanBasis | None:
    """A ``MeanBasis`` from the user's ``mean_basis``: None (zero mean), "constant", "linear" or
    a callable of unit-scale inputs (n, d) -> (n, k); ``m`` runs (k < m needed)."""
    if spec is None:
        return None
    if isinstance(spec, MeanBasis):
        basis = spec
    elif isinstance(spec, str):
        if spec not in KINDS:
            raise GPMSAError(f"mean_basis must be None, one of {KINDS} or a callable, got {spec!r}")
        basis = MeanBasis(spec, d)
    elif callable(spec):
        basis = MeanBasis("callable", d, spec)
    else:
        raise GPMSAError(f"mean_basis must be None, one of {KINDS} or a callable, got {spec!r}")
    k = basis.matrix(np.full((2, d), 0.5)).shape[1]
    if m is not None and k >= m:
        raise GPMSAError(f"mean_basis has {k} columns; it needs fewer than the {m} runs")
    return basis if basis.kind != "callable" else replace(basis, k=k)


@dataclass(frozen=True, eq=False)
class GLS:
    """The GLS fit of one weight vector: coefficients ``coef`` (k,), ``alpha`` =
    Sigma^-1 (w - H coef) (m,), ``A`` = L^-1 H (m, k), ``Q`` = cho_factor(H^T Sigma^-1 H)."""

    coef: np.ndarray
    alpha: np.ndarray
    A: np.ndarray
    Q: tuple

    @classmethod
    def of(cls, L: np.ndarray, w: np.ndarray, H: np.ndarray) -> GLS:
        """From the lower Cholesky factor L of Sigma, the weights w (m,) and H (m, k)."""
        A = solve_triangular(L, H, lower=True)
        a = solve_triangular(L, w, lower=True)
        try:
            Q = cho_factor(A.T @ A, lower=True)
        except np.linalg.LinAlgError as exc:
            raise GPMSAError(
                "the mean basis's GLS term H^T Sigma_W^-1 H is not positive definite in float64 at "
                "these emulator parameters: its columns are (nearly) collinear on the simulation "
                f"design (condition number {_scaled_condition(H)[0]:.3g}, columns scaled to unit "
                "length)"
            ) from exc
        coef = cho_solve(Q, A.T @ a)
        alpha = solve_triangular(L, a - A @ coef, lower=True, trans="T")
        return cls(coef, alpha, A, Q)

    def variance(self, h: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Added predictive variance (N,) at points with h (N, k) and v = L^-1 r^T (m, N)."""
        g = h.T - self.A.T @ v
        return np.sum(g * cho_solve(self.Q, g), axis=0)
