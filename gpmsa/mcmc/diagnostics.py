"""MCMC diagnostics: effective sample size, R-hat and acceptance (ArviZ, imported lazily)."""

from __future__ import annotations

import warnings

import numpy as np


def _arviz():
    """Import arviz quietly (it emits a FutureWarning at import)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        import arviz

    return arviz


def to_inference_data(draws: dict[str, np.ndarray], log_post: np.ndarray | None = None):
    """ArviZ InferenceData from draws name -> (n_chains, n_draws, *shape)."""
    az = _arviz()
    sample_stats = {"lp": log_post} if log_post is not None else None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return az.from_dict(posterior=dict(draws), sample_stats=sample_stats)


def ess(x: np.ndarray) -> float:
    """Bulk effective sample size of x (n_chains, n_draws) (rank-normalised, as ArviZ)."""
    x = np.asarray(x, dtype=np.float64)
    if np.ptp(x) == 0:
        return float("nan")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return float(_arviz().ess(np.atleast_2d(x)))


def rhat(x: np.ndarray) -> float:
    """Rank-normalised split R-hat of x (n_chains, n_draws); one chain is split in two."""
    x = np.atleast_2d(np.asarray(x, dtype=np.float64))
    if np.ptp(x) == 0 or x.shape[1] < 8:
        return float("nan")
    if x.shape[0] == 1:
        half = x.shape[1] // 2
        x = np.vstack([x[0, :half], x[0, half : 2 * half]])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return float(_arviz().rhat(np.atleast_2d(x)))


def summarize(
    draws: dict[str, np.ndarray], accept_rate: dict[str, np.ndarray] | None = None
) -> dict[str, dict[str, list[float]]]:
    """Per parameter and element (flattened, C order): mean, sd, ESS, R-hat, acceptance.

    ``draws``: name -> (n_chains, n_draws, *shape) after burn-in; ``accept_rate``: name ->
    (n_chains, *shape). JSON-able (lists of floats; NaN for constant chains).
    """
    out = {}
    for name, d in draws.items():
        flat = d.reshape(d.shape[0], d.shape[1], -1)
        entry = {
            "mean": [float(v) for v in flat.mean(axis=(0, 1))],
            "sd": [float(v) for v in flat.std(axis=(0, 1), ddof=1)],
            "ess": [ess(flat[:, :, i]) for i in range(flat.shape[2])],
            "rhat": [rhat(flat[:, :, i]) for i in range(flat.shape[2])],
        }
        if accept_rate is not None and name in accept_rate:
            entry["accept"] = [float(v) for v in accept_rate[name].reshape(d.shape[0], -1).mean(0)]
        out[name] = entry
    return out
