"""A categorical theta element's move to another level, jointly with the continuous theta.

Where a level and a continuous calibration parameter trade off (level a at k = 0.4 explains
the data as well as level b at k = 0.9), a move of the level alone lands far from the data
and is never accepted: chains stay at the level they started from. The joint move proposes
another level l' uniformly (as the single-element move) and shifts the continuous sampled
theta elements by o[l'] - o[l], where o[l] is the mode of their conditional posterior at
level l, the other parameters held at their values when the offsets are found
(`level_offsets`: a coordinate grid search, once per chain before its draws; frozen then).
The shift is deterministic and volume preserving, and the reverse move (l' -> l, proposed
with the same probability) is the opposite shift: the acceptance is the posterior ratio, so
the chain after the search is an exact Metropolis-Hastings chain (a shifted point outside
the prior's bounds or the constraint is rejected). Any offsets keep it exact; good ones make
it mix.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

N_GRID = 41
"""Nodes of each line search: evenly over (0, 1), then over one coarse spacing either side of
the best node (a resolution of 1 / (20 N_GRID), 0.0012 of the unit range)."""
N_PASSES = 2
"""Passes over the continuous elements (a coordinate search: the elements' trade-offs)."""


def level_offsets(
    log_post: Callable[[np.ndarray], float],
    theta: np.ndarray,
    k: int,
    levels: Sequence[float],
    cont: Sequence[int],
) -> np.ndarray:
    """(n_levels, len(cont)): per level of element ``k`` of unit-scale ``theta`` (q,), the
    continuous elements ``cont`` at the mode of ``log_post`` (unit theta (q,) -> log posterior,
    -inf outside the prior or constraint) with element ``k`` at that level, from ``theta``'s
    values by `N_PASSES` coordinate line searches (an element keeps its value where no node
    is better)."""
    out = np.empty((len(levels), len(cont)))
    h = 1.0 / N_GRID
    coarse = (np.arange(N_GRID) + 0.5) * h
    fine = h * np.linspace(-1.0, 1.0, N_GRID)
    for r, level in enumerate(levels):
        th = np.array(theta, dtype=np.float64)
        th[k] = level
        best = log_post(th)
        for _ in range(N_PASSES):
            for j in cont:
                for nodes in (coarse, th[j] + fine):
                    keep = th[j]
                    for v in nodes:
                        th[j] = v
                        lp = log_post(th)
                        if lp > best:
                            best, keep = lp, float(v)
                    th[j] = keep
        out[r] = th[list(cont)]
    return out


def shift_table(offsets: np.ndarray) -> list[list[tuple[float, ...]]]:
    """[r][s]: the shift of the continuous elements from level row r to row s (o[s] - o[r])."""
    n = offsets.shape[0]
    return [[tuple(float(v) for v in offsets[s] - offsets[r]) for s in range(n)]
            for r in range(n)]  # fmt: skip


def shift(values: np.ndarray, cont: Sequence[int], steps: Sequence[float],
          log_prior: Callable[[int, float], float]) -> float:  # fmt: skip
    """Add ``steps`` (a row of `shift_table`) to ``values[cont]`` in place, one element after
    another; the change of their log priors (``log_prior(k, x)``: element ``cont[k]``'s at
    x), or -inf as soon as a shifted value lies outside its prior (``values`` then partly
    shifted: the caller's candidate, discarded)."""
    d_lp = 0.0
    for k, (j, d) in enumerate(zip(cont, steps, strict=True)):
        old = float(values[j])
        lp_new = log_prior(k, old + d)
        if lp_new == -math.inf:
            return -math.inf
        d_lp += lp_new - log_prior(k, old)
        values[j] = old + d
    return d_lp


def chains_record(per_chain: Sequence[dict[int, np.ndarray]], cont: Sequence[int]) -> dict:
    """The samplers' record of the offsets (``Chains.info["level_offsets"]``, unit scale):
    ``per_chain[c]``, categorical theta element -> its `level_offsets` (n_levels, len(cont)),
    as {"shifted": the continuous elements' positions, "offsets": element -> (n_chains,
    n_levels, len(cont))}; {} where no chain made the move."""
    if not per_chain or not per_chain[0]:
        return {}
    return {"shifted": [int(j) for j in cont],
            "offsets": {int(k): np.stack([np.asarray(c[k], dtype=np.float64) for c in per_chain])
                        for k in per_chain[0]}}  # fmt: skip


def native_record(record: dict, t_names: Sequence[str], t_min, t_max, levels) -> dict:
    """``chains_record``'s record for a person and a file (JSON): per categorical theta name,
    its "levels" (native codes, ``levels[k]``), the "shifted" continuous elements' names and
    "modes" [chain][level][shifted element], their conditional modes at each level in theta's
    native units (the move from level a to b shifts them by modes[c][b] - modes[c][a])."""
    if not record:
        return {}
    cont = record["shifted"]
    lo = np.asarray(t_min, dtype=np.float64)[cont]
    width = np.asarray(t_max, dtype=np.float64)[cont] - lo
    return {str(t_names[k]): {"levels": [int(v) for v in levels[k]],
                              "shifted": [str(t_names[j]) for j in cont],
                              "modes": (lo + np.asarray(off) * width).tolist()}
            for k, off in record["offsets"].items()}  # fmt: skip
