"""A gridded log prior between its nodes: local cubic interpolation where the table is smooth.

A log prior given as values on the Calibrator's grid is often other windows' summed
log-likelihood (a sequential filter): a smooth, nearly quadratic function whose peak may be
narrower than a node spacing. Linear interpolation in the log then errs by an eighth of the
log's second difference mid-cell (2 nats for a peak of sd h / 4), and chaining ten informative
windows of three observations (tests/gpmsa/test_prior_chaining_s70.py's case, posterior sd
0.26-0.9 spacings) left the mean up to 0.26 sd off and the sd up to 23 % too wide; the cubic
through the four nodes around a cell, exact for quadratics and cubics, brings that to 0.04 sd
and 4.4 % (9 cases). A not-a-knot spline over the whole grid did better (0.011 sd, 1 %) but
rings over many cells from a single jump.

A cubic rings next to a jump (a finite step of 50 nats in the log would put a bump of e^5 in the
cell before it), so a cell takes the cubic only where its four nodes are finite and the log's
two second differences there agree (`SMOOTH_GATE`); elsewhere it keeps the linear value.
"""

from __future__ import annotations

import numpy as np

STENCIL = 4
"""Nodes of the interpolating polynomial around a cell (a cubic). Six (a quintic) let the gate
below refuse most cells near a chained likelihood's peak, whose log is not quadratic over five
spacings (the lamOs integral gives it t-like tails): no better than linear there."""
SMOOTH_GATE = 0.5
"""A cell's stencil counts as smooth where its second differences D1, D2 satisfy
|D2 - D1| <= SMOOTH_GATE max(|D1|, |D2|) (a quadratic: D1 = D2; a step or noise: |D2 - D1| about
2 max(|D1|, |D2|), and a step next to a flat stretch: equal to it)."""

NARROW_PRIOR_SD = {1: 0.28, 2: 0.4}
"""Per count of parameters, the narrowest gridded prior (`narrowest_sd`: its sd given the other
parameter, in node spacings, from the log's second difference at its highest node) that the
interpolation keeps accurate; narrower, the Calibrator warns. Measured on ten chained windows
against a 16,385-node grid (one parameter; 15 cases): priors of 0.30-0.96 spacings gave
posteriors within 0.041 sd and 4.4 %, priors of 0.25-0.28 (a sharper emulator: the peaks' logs
are t-like, narrower in the core than the second difference says) up to 0.155 sd off and 24 %
too wide; two parameters (6 windows against an exact callable prior): 0.45-0.62 spacings within
0.05 sd and 2 %, 0.28 up to 0.13 sd, 0.19 up to 0.52 sd and 16 %."""


def narrowest_sd(table: np.ndarray, n: int, q: int) -> float:
    """The sd (node spacings) of the log density ``table`` ((n^q,), 'ij' order) given the other
    parameter, at its highest node, the smaller over the parameters: 1 / sqrt(-D) for the log's
    second difference D there (inf where D >= 0 or a neighbour is not finite)."""
    grid = table.reshape((n,) * q)
    peak = np.unravel_index(int(np.argmax(table)), grid.shape)
    out = np.inf
    for k in range(q):
        at = list(peak)
        at[k] = min(max(at[k], 1), n - 2)
        vals = []
        for step in (-1, 0, 1):
            node = list(at)
            node[k] += step
            vals.append(grid[tuple(node)])
        d = vals[0] - 2.0 * vals[1] + vals[2]
        if np.isfinite(d) and d < 0:
            out = min(out, 1.0 / np.sqrt(-d))
    return float(out)


def _stencil(axis: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The cell of each point (its left node) and the first of its STENCIL stencil nodes."""
    n = axis.size
    cell = np.clip(np.searchsorted(axis, x, side="right") - 1, 0, n - 2)
    return cell, np.clip(cell - (STENCIL // 2 - 1), 0, n - STENCIL)


def _along(values: np.ndarray, nodes: np.ndarray, x: np.ndarray, at: np.ndarray) -> np.ndarray:
    """Values (k, STENCIL) at stencil ``nodes`` (k, STENCIL) interpolated at ``x`` (k,), whose
    cell starts at stencil position ``at`` (k,): the polynomial where smooth and finite, else
    linear in the cell."""
    rows = np.arange(x.size)
    left, right = values[rows, at], values[rows, at + 1]
    x0, x1 = nodes[rows, at], nodes[rows, at + 1]
    u = np.clip((x - x0) / (x1 - x0), 0.0, 1.0)
    with np.errstate(invalid="ignore"):  # inf - inf where a node is -inf: linear there
        linear = np.where(u == 0.0, left, np.where(u == 1.0, right, left + u * (right - left)))
        d = np.diff(values, 2, axis=1)
        smooth = np.ptp(d, axis=1) <= SMOOTH_GATE * np.abs(d).max(axis=1)
    smooth &= np.isfinite(values).all(axis=1)
    if not smooth.any():
        return linear
    weights = np.ones_like(nodes)
    for j in range(STENCIL):
        for m in range(STENCIL):
            if m != j:
                weights[:, j] *= (x - nodes[:, m]) / (nodes[:, j] - nodes[:, m])
    cubic = np.sum(weights * np.where(np.isfinite(values), values, 0.0), axis=1)
    return np.where(smooth, cubic, linear)


def local_cubic(table: np.ndarray, axis: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Values ``table`` on the grid axis^q ((n^q,), 'ij' order) at the points (k, q), q = 1 or 2:
    per axis, the cubic through the four nodes around each point where they are finite and
    smooth (`SMOOTH_GATE`), linear (bilinear) in the cell otherwise. Needs n >= STENCIL."""
    n = axis.size
    first, at_first = _stencil(axis, points[:, 0])
    offsets = np.arange(STENCIL)
    if points.shape[1] == 1:
        idx = at_first[:, None] + offsets
        return _along(table[idx], axis[idx], points[:, 0], first - at_first)
    second, at_second = _stencil(axis, points[:, 1])
    grid = table.reshape(n, n)
    rows = at_first[:, None] + offsets  # (k, STENCIL)
    cols = at_second[:, None] + offsets
    block = grid[rows[:, :, None], cols[:, None, :]]  # (k, STENCIL, STENCIL)
    k = points.shape[0]
    along_second = _along(
        block.reshape(STENCIL * k, STENCIL),
        np.repeat(axis[cols], STENCIL, axis=0),
        np.repeat(points[:, 1], STENCIL),
        np.repeat(second - at_second, STENCIL),
    ).reshape(k, STENCIL)
    return _along(along_second, axis[rows], points[:, 0], first - at_first)
