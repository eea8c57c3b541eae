"""GPM/SA's product Gaussian correlation: R(a, b; beta) = exp(-sum_k beta_k (a_k - b_k)^2)."""

from __future__ import annotations

import numpy as np


def sq_diffs(a: np.ndarray, b: np.ndarray | None = None) -> np.ndarray:
    """Squared differences per input dimension: (d, n_a, n_b) from a (n_a, d) and b (n_b, d)."""
    b = a if b is None else b
    return np.square(a.T[:, :, None] - b.T[:, None, :])


def correlation(a: np.ndarray, b: np.ndarray | None, beta: np.ndarray) -> np.ndarray:
    """R (n_a, n_b) between points a (n_a, d) and b (n_b, d) (b=None: a with itself); beta (d,).

    Accumulated one input dimension at a time in one (n_a, n_b) buffer: no (d, n_a, n_b)
    temporary, and little fixed cost for the one-row calls of online calibration.
    """
    b = a if b is None else b
    beta = np.asarray(beta, dtype=np.float64)
    exponent = np.zeros((a.shape[0], b.shape[0]))
    for k in range(beta.size):
        diff = a[:, k, None] - b[None, :, k]
        diff *= diff
        diff *= beta[k]
        exponent -= diff
    return np.exp(exponent, out=exponent)


def beta_to_rho(beta: np.ndarray) -> np.ndarray:
    """rho = exp(-beta / 4): the correlation at distance 1/2 on the unit scale."""
    return np.exp(-0.25 * np.asarray(beta))


def rho_to_beta(rho: np.ndarray) -> np.ndarray:
    """beta = -4 log(rho)."""
    return -4.0 * np.log(np.asarray(rho))
