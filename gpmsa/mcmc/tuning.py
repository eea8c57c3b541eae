"""GPM/SA step-size tuning (``stepsize``, after Graves 2011): a binomial GLM per element.

Candidate widths step0 * base^e, e = -(L-1)/2 .. (L-1)/2; ``n_burn`` rounds each run one sweep
at every level; per element, a logistic regression of acceptance on log(width) picks the width
with acceptance 1/e.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from gpmsa.errors import GPMSAError
from gpmsa.model.data import check_count

TARGET = 1.0 / np.e
N_BURN = 50
N_LEVELS = 20
MAX_LEVELS = 1000
"""Most candidate widths per element (``tune_levels``)."""
MAX_SWEEPS = 1_000_000
"""Most tuning sweeps per chain (``tune_rounds`` x ``tune_levels``): 1,000 times GPM/SA's."""


def check_tuning(tune_rounds, tune_levels) -> tuple[int, int]:
    """(tune_rounds, tune_levels) as ints: rounds >= 1, levels in [2, MAX_LEVELS], at most
    ``MAX_SWEEPS`` sweeps in all; GPMSAError naming the argument otherwise."""
    rounds = check_count(tune_rounds, "tune_rounds", 1, MAX_SWEEPS)
    levels = check_count(tune_levels, "tune_levels", 2, MAX_LEVELS)
    if rounds * levels > MAX_SWEEPS:
        raise GPMSAError(
            f"tune_rounds x tune_levels = {rounds} x {levels} tuning sweeps per chain, above the "
            f"most allowed ({MAX_SWEEPS}; GPM/SA's tuning is {N_BURN} x {N_LEVELS})"
        )
    return rounds, levels


def level_bases(name: str, n_levels: int) -> tuple[float, float]:
    """(base for e <= 0, base for e > 0) of parameter ``name``, as in GPM/SA."""
    up = 2.0
    if n_levels > 1:
        if name == "theta":
            up = 20.0 ** (2.0 / (n_levels - 1))
        elif name in ("betaU", "betaV"):
            up = 10.0 ** (2.0 / (n_levels - 1))
        elif name in ("lamUz", "lamOs"):
            up = 100.0 ** (2.0 / (n_levels - 1))
    return 2.0, up


def level_widths(names: list[str], widths: np.ndarray, n_levels: int) -> np.ndarray:
    """Candidate widths (n_levels, n_elements) for elements of parameters ``names``."""
    ex = np.linspace(-(n_levels - 1) / 2, (n_levels - 1) / 2, n_levels)
    out = np.empty((n_levels, len(names)))
    for i, name in enumerate(names):
        down, up = level_bases(name, n_levels)
        base = np.where(ex <= 0, down, up)
        out[:, i] = widths[i] * base**ex
    return out


def fit_logistic(x: np.ndarray, k: np.ndarray, n: int, ridge: float = 1e-6) -> np.ndarray | None:
    """Binomial GLM (logit link) of k successes in n trials on x: returns (b0, b1) or None.

    Newton-Raphson (IRLS) with a tiny ridge so that fully separated data still give a finite fit.
    """
    X = np.column_stack([np.ones_like(x), x])
    b = np.zeros(2)
    for _ in range(100):
        eta = X @ b
        p = 1.0 / (1.0 + np.exp(-eta))
        grad = X.T @ (k - n * p) - ridge * b
        H = (X * (n * p * (1 - p))[:, None]).T @ X + ridge * np.eye(2)
        try:
            step = np.linalg.solve(H, grad)
        except np.linalg.LinAlgError:
            return None
        b = b + step
        if np.max(np.abs(step)) < 1e-10 * (1 + np.max(np.abs(b))):
            break
    return b if np.all(np.isfinite(b)) else None


def choose_widths(
    widths: np.ndarray, candidates: np.ndarray, accepted: np.ndarray, n_burn: int
) -> np.ndarray:
    """Tuned width per element: where the fitted acceptance equals 1/e, within the candidates.

    ``candidates`` (n_levels, n_el) widths, ``accepted`` (n_levels, n_el) acceptance counts out of
    ``n_burn``. The fit only knows the tested range, so the width is held to the element's
    candidates [min, max]: a fitted 1/e point beyond them (acceptance above 1/e at every
    candidate) gives the widest, one below them the narrowest. An element that accepted every
    proposal at every candidate gets the widest, one that accepted none the narrowest (no
    logistic fit exists there: its slope would be the ridge's, whose sign follows that of the
    widths' logarithms, not the data). An element whose fit fails (or gives acceptance rising
    with width) keeps ``widths``.
    """
    logit = np.log(TARGET / (1 - TARGET))
    out = widths.copy()
    for i in range(widths.size):
        cand = candidates[:, i]
        if np.all(accepted[:, i] <= 0):
            out[i] = cand.min()
            continue
        if np.all(accepted[:, i] >= n_burn):
            out[i] = cand.max()
            continue
        b = fit_logistic(np.log(cand), accepted[:, i], n_burn)
        if b is None or not b[1] < 0:
            continue
        # a tiny slope gives inf or 0 (overflow, underflow): clipped to the widest or narrowest
        with np.errstate(over="ignore", under="ignore"):
            w = np.exp((logit - b[0]) / b[1])
        out[i] = np.clip(w, cand.min(), cand.max())
    return out


def tune_widths(
    sweep: Callable[[np.ndarray, bool, np.ndarray], None],
    names: list[str],
    widths: np.ndarray,
    n_rounds: int,
    n_levels: int,
    on_round: Callable[[int], None] | None = None,
) -> np.ndarray:
    """GPM/SA's tuning run: ``n_rounds`` rounds of one sweep at each candidate level, then the
    width per element where the fitted acceptance is 1/e.

    ``sweep(widths, prop_mh, accepted)`` is a chain's Metropolis-within-Gibbs sweep (adding its
    acceptances to ``accepted``); ``on_round(n_levels)`` is called after each round (a progress
    bar's ``update``).
    """
    cands = level_widths(names, widths, n_levels)
    acc = np.zeros((n_levels, widths.size))
    for _ in range(n_rounds):
        for lev in range(n_levels):
            sweep(cands[lev], False, acc[lev])
        if on_round is not None:
            on_round(n_levels)
    return choose_widths(widths, cands, acc, n_rounds)
