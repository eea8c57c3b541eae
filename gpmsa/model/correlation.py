"""GPM/SA's product correlation over unit-scale inputs.

Continuous input k: exp(-beta_k (a_k - b_k)^2) (squared exponential). Categorical input k (SEPIA's
categorical kernel): rho_k^(1[a_k != b_k]) = exp(-beta_k / 4 * 1[a_k != b_k]), i.e. correlation
rho_k = exp(-beta_k / 4) between different levels and 1 within a level. ``categorical`` is a
boolean mask over the input columns (None: every input continuous).
"""

from __future__ import annotations

import numpy as np

CATEGORICAL_DISTANCE = 0.25
"""The "squared distance" of two different levels of a categorical input (equal levels: 0), so
that exp(-beta d) = rho = exp(-beta / 4), the rho a continuous input has at distance 1/2."""


def _col_diff(a: np.ndarray, b: np.ndarray, categorical: bool) -> np.ndarray:
    """(n_a, n_b) squared difference (or categorical distance) of columns a (n_a,), b (n_b,)."""
    if categorical:
        return CATEGORICAL_DISTANCE * (a[:, None] != b[None, :])
    diff = a[:, None] - b[None, :]
    diff *= diff
    return diff


def _mask(categorical, d: int) -> np.ndarray:
    if categorical is None:
        return np.zeros(d, dtype=bool)
    mask = np.asarray(categorical, dtype=bool).reshape(-1)
    if mask.size != d:
        raise ValueError(f"categorical mask has {mask.size} entries for {d} input columns")
    return mask


def sq_diffs(a: np.ndarray, b: np.ndarray | None = None, categorical=None) -> np.ndarray:
    """Squared differences per input dimension: (d, n_a, n_b) from a (n_a, d) and b (n_b, d);
    a categorical column gives ``CATEGORICAL_DISTANCE`` between different levels, 0 within one."""
    b = a if b is None else b
    mask = _mask(categorical, a.shape[1])
    if not mask.any():
        return np.square(a.T[:, :, None] - b.T[:, None, :])
    return np.stack([_col_diff(a[:, k], b[:, k], bool(mask[k])) for k in range(a.shape[1])])


def correlation(
    a: np.ndarray, b: np.ndarray | None, beta: np.ndarray, categorical=None
) -> np.ndarray:
    """R (n_a, n_b) between points a (n_a, d) and b (n_b, d) (b=None: a with itself); beta (d,);
    ``categorical``: boolean mask (d,) of the categorical inputs (None: none).

    Accumulated one input dimension at a time in one (n_a, n_b) buffer: no (d, n_a, n_b)
    temporary, and little fixed cost for the one-row calls of online calibration.
    """
    b = a if b is None else b
    beta = np.asarray(beta, dtype=np.float64)
    mask = _mask(categorical, beta.size)
    exponent = np.zeros((a.shape[0], b.shape[0]))
    for k in range(beta.size):
        diff = _col_diff(a[:, k], b[:, k], bool(mask[k]))
        diff *= beta[k]
        exponent -= diff
    with np.errstate(under="ignore"):  # far apart: 0, whatever the caller's np.seterr
        return np.exp(exponent, out=exponent)


def correlation_row(
    a: list[float], b_cols: list[np.ndarray], beta: list[float], categorical: list[bool]
) -> np.ndarray:
    """``correlation(np.array([a]), b, beta, categorical)[0]`` (the same operations, so the same
    values) for one point a (d floats) against b given as its d contiguous columns (n_b,): the
    per-proposal call of a sampler, without the array set-up (a few microseconds)."""
    exponent = np.zeros(b_cols[0].shape[0])
    for ak, bk, beta_k, cat in zip(a, b_cols, beta, categorical, strict=True):
        if cat:
            diff = CATEGORICAL_DISTANCE * (ak != bk)
        else:
            diff = ak - bk
            diff *= diff
        diff *= beta_k
        exponent -= diff
    with np.errstate(under="ignore"):
        return np.exp(exponent, out=exponent)


def beta_to_rho(beta: np.ndarray) -> np.ndarray:
    """rho = exp(-beta / 4): the correlation at distance 1/2 on the unit scale."""
    return np.exp(-0.25 * np.asarray(beta))


def rho_to_beta(rho: np.ndarray) -> np.ndarray:
    """beta = -4 log(rho)."""
    return -4.0 * np.log(np.asarray(rho))
