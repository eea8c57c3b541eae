"""Output bases: the PCA emulator basis K and the discrepancy basis D (GPM/SA conventions)."""

from __future__ import annotations

import hashlib

import numpy as np

from gpmsa.errors import GPMSAError
from gpmsa.model.data import as_float, check_count, check_increasing

VARIANCE_FRACTION = 0.995


def pca_basis(
    y_std: np.ndarray, n_pc: int | float | None = None, fraction: float = VARIANCE_FRACTION
) -> np.ndarray:
    """PCA basis K (l_sim, p_u) of standardised outputs y_std (m, l_sim): K = U S / sqrt(m).

    p_u = ``n_pc`` if an integer; a float in (0, 1) is a variance fraction (as SEPIA's
    ``create_K_basis(n_pc=0.99)``): the fewest components reaching it, as ``fraction`` is when
    ``n_pc`` is None. A scalar output (l_sim = 1) gives K = [[1]].
    """
    m, l_sim = y_std.shape
    if isinstance(n_pc, float | np.floating) and 0.0 < n_pc < 1.0:
        n_pc, fraction = None, float(n_pc)
    elif n_pc is not None:
        if isinstance(n_pc, float | np.floating):
            raise GPMSAError(
                f"n_pc must be an integer >= 1 (components) or a variance fraction in (0, 1), "
                f"got {n_pc!r}"
            )
        n_pc = check_count(n_pc, "n_pc")
    if l_sim == 1:
        if n_pc not in (None, 1):
            raise GPMSAError(f"n_pc must be 1 for a scalar output, got {n_pc!r}")
        return np.ones((1, 1))
    u, s, _ = np.linalg.svd(y_std.T, full_matrices=False)
    if n_pc is None:
        if not 0 < fraction <= 1:
            raise GPMSAError(f"fraction must be in (0, 1], got {fraction}")
        share = np.cumsum(s**2) / np.sum(s**2)
        n_pc = int(np.searchsorted(share, fraction - 1e-12) + 1)
    if not 1 <= n_pc <= min(m, l_sim):
        raise GPMSAError(f"n_pc must be in [1, {min(m, l_sim)}], got {n_pc!r}")
    return u[:, :n_pc] * s[:n_pc] / np.sqrt(m)


def basis_weights(y_std: np.ndarray, K: np.ndarray) -> np.ndarray:
    """Weights w (m, p_u) = y_std K^+^T (least-squares projection on the basis)."""
    return y_std @ np.linalg.pinv(K).T


def interpolate_basis(K: np.ndarray, grid: np.ndarray, new_grid: np.ndarray | None) -> np.ndarray:
    """Basis columns interpolated linearly from ``grid`` (strictly increasing) onto ``new_grid``
    (any order; None: unchanged)."""
    if new_grid is None or (new_grid.shape == grid.shape and np.array_equal(new_grid, grid)):
        return K
    if K.shape[0] == 1:
        return np.repeat(K, new_grid.size, axis=0)
    check_increasing(grid, "the simulation grid")
    lo, hi = grid.min(), grid.max()
    if new_grid.min() < lo or new_grid.max() > hi:
        raise GPMSAError(
            f"observation index must lie within the simulation grid [{lo}, {hi}], "
            f"got [{new_grid.min()}, {new_grid.max()}]"
        )
    return np.column_stack([np.interp(new_grid, grid, K[:, j]) for j in range(K.shape[1])])


def discrepancy_basis(kind, grid: np.ndarray) -> np.ndarray | None:
    """Discrepancy basis D (l_obs, p_v) on ``grid`` (l_obs,), normalised so max diag(D D^T) = 1.

    ``kind``: None (no discrepancy), "constant", "linear" (1 and the index), or a given
    (l_obs, p_v) array.
    """
    if kind is None:
        return None
    if isinstance(kind, str):
        if kind == "constant":
            D = np.ones((grid.size, 1))
        elif kind == "linear":
            D = np.column_stack([np.ones(grid.size), grid])
        else:
            raise GPMSAError(
                f"discrepancy must be None, 'constant', 'linear' or an array, got {kind!r}"
            )
    else:
        D = as_float(kind, "discrepancy basis")
        if D.ndim == 1:
            D = D[:, None]
        if D.ndim != 2 or D.shape[0] != grid.size:
            raise GPMSAError(f"discrepancy basis must be ({grid.size}, p_v), got {D.shape}")
        if not np.all(np.isfinite(D)):
            raise GPMSAError("discrepancy basis must be finite")
    with np.errstate(over="ignore", under="ignore"):
        scale = np.max(np.sum(D**2, axis=1))
    if not np.finfo(np.float64).tiny <= scale < np.inf and np.any(D):
        D = D / np.max(np.abs(D))  # its squares overflow or underflow float64: rescale first
        scale = np.max(np.sum(D**2, axis=1))
    if not scale > 0:
        raise GPMSAError("discrepancy basis is all zeros")
    return D / np.sqrt(scale)


DIGEST_STEP = 2.0**-24
"""`basis_digest` rounds the normalised bases (max row norm 1) to multiples of this, so that
a multiple of a basis, whose normalisation differs from the basis's by an ulp or two, is the
same basis (one element in about 1e8 lands within an ulp of a rounding point)."""


def basis_digest(bases, groups=None) -> str | None:
    """SHA-256 of the normalised discrepancy bases of a reduction (``ObsProblem.D``: one array
    per experiment, rounded to DIGEST_STEP, with their shapes) and of their precision groups
    (``ObsProblem.v_groups``; None, one group, adds nothing); None without a discrepancy. A
    joint fit and ``gpmsa.calibrate`` record it, so that ``gpmsa.full_prediction`` refuses
    another basis or grouping."""
    if bases is None:
        return None
    h = hashlib.sha256()
    if groups is not None:
        h.update(f"groups:{list(groups)}".encode())
    for k, D in enumerate(bases):
        arr = np.ascontiguousarray(np.rint(np.asarray(D, dtype=np.float64) / DIGEST_STEP), "<i8")
        h.update(f"{k}:{arr.shape}".encode())
        h.update(arr.tobytes())
    return h.hexdigest()
