"""The grid posterior's machinery for one or two calibration parameters: the density's
interpolation between nodes (linear, bilinear; in the log between finite values, in the density
next to a zero), a constraint's boundary inserted into a one-parameter grid and resolved on
split cells of a two-parameter one, marginals cut to their support, draws from the bilinear
density (those a constraint rejects redrawn), and the refinement of each peak the grid does
not resolve (where heavy tails hold the grid beyond its node budget, of the core of each
marginal, `tail_refined_axes`; one parameter: `refined_axis`).
``gpmsa.calibration.calibrator`` composes them; all work on unit-scale or native axes given by
the caller.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import RegularGridInterpolator

from gpmsa._fp_state import underflow_as_zero
from gpmsa.calibration.local_cubic import STENCIL, local_cubic
from gpmsa.calibration.posterior import GridMarginal, trapezoid_weights
from gpmsa.errors import GPMSAError

N_REFINE = 129
N_REFINE_2D = 49
"""Nodes per parameter of a refined mode (one, two calibration parameters)."""
RESOLVE_SD = 4.0
"""The grid resolves a mode of the posterior whose spread (`_spread`: its sd, or less where
heavy tails inflate the sd) spans at least this many node spacings (per parameter); otherwise
that mode is recomputed on a finer grid over the region holding its mass."""
MASS_CUTOFF = 1e-14
"""Nodes whose (marginal) posterior density is below this fraction of the peak carry no mass; the
runs of nodes above it are the posterior's modes."""
MODE_MASS = 1e-9
"""Modes holding less than this fraction of the posterior mass are not refined."""
VALLEY = 0.5
"""A local minimum of the density separates two peaks when it is below this fraction of the
highest density on either side of it."""
REFINE_MODES = 2
"""Up to this many modes are refined with N_REFINE (N_REFINE_2D) nodes each; more share
REFINE_MODES times that, at least MIN_MODE_NODES each."""
MIN_MODE_NODES = 9
MAX_REFINED = 4
"""A refined grid holds at most this many times the nodes of one refined mode (N_REFINE, or
N_REFINE_2D squared); refinement stops before a grid would hold more."""
REFINE_FACTORS = (2.0, 1.5, 1.25)
"""A refined region has at least this many times the cells it had (the first that fits)."""
SAME_NODE = 0.01
"""A refined node this close to a grid line it must keep (in node spacings) gives way to it."""
N_SUB = 4
"""Two parameters: each side of a grid cell that a constraint's boundary crosses is split into
this many parts, the constraint evaluated at the new nodes (`ConstraintCut`). The cut density
errs only in the split cells the boundary crosses; on tests/gpmsa/test_constraint_two_params.py's
case its mean and quantiles are within 6e-4 sd of the exact cut (2 parts: 4e-3, 8: 1.4e-4) and
an update costs 5-8 % more than without the constraint (8 parts: 20 %)."""
MAX_REDRAW_ROUNDS = 100
"""Rounds of redrawing the draws a constraint rejects (`draw_allowed`), at most."""
UNRESOLVED_SD = 1.5
"""Two parameters: where no refinement factor fits and a marginal's `resolution` is under this
many node spacings per sd, one last pass refines the core of each marginal under RESOLVE_SD
(`tail_refined_axes`; one parameter, `refined_axis`: where it is under RESOLVE_SD); a marginal
still under UNRESOLVED_SD afterwards is named in a warning (one parameter also where the
refinement passes run out or reach float64's resolution). On
`two_param_emulator` (few observations, one peak) the quantiles erred by about 0.15 / r**2 sd
and the cdf by about 0.025 / r**2 at r spacings per sd (0.19 sd, 0.029 at r = 0.91; 0.105,
0.019 at 1.22; 0.05, 0.009 at 1.75); the two-peak cases of the tests at 1.7 and 2.2 (their
quantiles within 0.006 sd, the cdf 0.006) are left as they were."""
TAIL_MASS = 1e-3
"""The core of a marginal that `tail_refined_axes` refines: the nodes holding all but this
fraction of its mass (half each side); the nodes beyond (the tails) stay, thinned."""
TAIL_SHARES = (1.0, 0.7, 0.5, 0.35, 0.25, 0.18, 0.12)
"""The shares of the tails' nodes that `tail_refined_axes` tries to keep (the first that fits)."""
RIDGE_SD = 0.5
"""Two parameters: a posterior whose sd along a parameter given the other (`conditional_sds`)
spans fewer than this many node spacings is a ridge the (refined) grid does not resolve (its
marginals can be wide, so refinement does not see it): a warning. Above it (0.54-1.9 spacings
on the cases tried) the summaries erred by about 2 % of an sd or less; far below it by tens of
per cent."""


def mesh(axes: list) -> np.ndarray:
    """The nodes (G, q) of the grid with the given axes, 'ij' order (first parameter slowest)."""
    if len(axes) == 1:
        return axes[0][:, None]
    mesh = np.meshgrid(*axes, indexing="ij")
    return np.column_stack([g.ravel() for g in mesh])


def constrained(free: np.ndarray, ok: np.ndarray | None) -> np.ndarray:
    """Log density ``free`` (G,) set to -inf where ``ok`` (G,) is False (None: nowhere)."""
    return free if ok is None else np.where(ok, free, -np.inf)


def check_log_density(vals: np.ndarray) -> None:
    if np.any(np.isnan(vals)) or np.any(vals == np.inf):
        raise GPMSAError("prior log densities must not be NaN or +inf")


def check_mass(logp: np.ndarray) -> None:
    if np.any(np.isnan(logp)) or not np.any(np.isfinite(logp)):
        raise GPMSAError("the posterior has no mass on the grid (prior zero everywhere?)")


def interp_log(
    table: np.ndarray, axis: np.ndarray, points: np.ndarray, smooth: bool = False
) -> np.ndarray:
    """Log densities ``table`` on the grid axis^q ((n^q,), 'ij' order; -inf: zero density) at
    the points (k, q), q = 1 or 2: linear (bilinear) in the log where the nodes around a point
    are finite, in the density where one of them is zero. ``smooth``: in the log, the local
    cubic (`local_cubic`) where the four nodes around a point (per axis) are finite and smooth.
    A point gets -inf only where the density is zero, and never NaN."""

    def at(values: np.ndarray) -> np.ndarray:
        if points.shape[1] == 1:
            return np.interp(points[:, 0], axis, values)
        return RegularGridInterpolator((axis, axis), values.reshape(axis.size, -1))(points)

    finite = np.isfinite(table)
    if not finite.any():
        return np.full(points.shape[0], -np.inf)
    peak = float(table[finite].max())
    by_log = at(np.where(finite, table, peak))
    if smooth and axis.size >= STENCIL:
        cubic = local_cubic(table, axis, points)
        by_log = np.where(np.isfinite(cubic), cubic, by_log)
    if finite.all():
        return by_log
    near_zero = at((~finite).astype(float)) > 0.0
    with np.errstate(divide="ignore", under="ignore"):
        by_density = np.log(at(np.exp(table - peak))) + peak
    return np.where(near_zero, by_density, by_log)


def with_edges(
    nodes: np.ndarray,
    free: np.ndarray,
    ok: np.ndarray,
    edges: tuple[np.ndarray, ...],
    prior: Callable[[np.ndarray], np.ndarray] | None = None,
    total: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One parameter: the unit-scale ``nodes`` (k,) with the constraint's boundary points
    ``edges`` (``Calibrator._constraint_edges``) inserted, so that the piecewise-linear density
    ends at the boundary instead of ramping to zero across the cell beyond it.

    Returns (nodes, log density, likelihood node of each node (its allowed neighbour for an
    inserted point)); an inserted point gets the log density ``free`` interpolated there
    (`interp_log`), or -inf where the constraint forbids it. ``prior`` (unit-scale points
    (e,) -> log densities (e,)): a log prior not in ``free`` (finite where ``ok``), added at
    the nodes (``total`` (k,): ``free`` plus that prior there, where the caller has it) and at
    the inserted points."""
    cells, first, second = edges
    if prior is not None and total is None:
        total = free + prior(nodes)
    logd = constrained(free if prior is None else total, ok)
    if cells.size == 0:
        return nodes, logd, np.arange(nodes.size)
    cell = np.concatenate([cells, cells])
    pts = np.concatenate([first, second])
    allowed = np.concatenate([ok[cells], ok[cells + 1]])
    new = (pts > nodes[cell]) & (pts < nodes[cell + 1])  # a point on a node is that node
    cell, pts, allowed = cell[new], pts[new], allowed[new]
    vals = interp_log(free, nodes, pts[:, None])
    if prior is not None and allowed.any():
        vals[allowed] += prior(pts[allowed])
    vals = np.where(allowed, vals, -np.inf)
    lik = np.where(ok[cell], cell, cell + 1)
    x = np.concatenate([nodes, pts])
    order = np.argsort(x, kind="stable")
    lik_all = np.concatenate([np.arange(nodes.size), lik])
    return x[order], np.concatenate([logd, vals])[order], lik_all[order]


def trimmed_marginal(
    nodes: np.ndarray, log_density: np.ndarray, weights: np.ndarray | None = None
) -> tuple[GridMarginal, slice]:
    """The GridMarginal of exp(log_density) on ``nodes`` cut to its support: one node of zero
    density is kept past the outermost nodes of positive density, no more (so that its quantile
    function ends where the mass ends); also the slice of the nodes kept."""
    gm = GridMarginal.from_log_density(nodes, log_density, weights)
    if gm.density[0] > 0.0 and gm.density[-1] > 0.0:
        return gm, slice(0, nodes.size)
    live = np.flatnonzero(gm.density > 0.0)
    kept = slice(max(int(live[0]) - 1, 0), min(int(live[-1]) + 2, nodes.size))
    if kept.stop - kept.start == nodes.size:
        return gm, kept
    return GridMarginal.from_log_density(nodes[kept], log_density[kept]), kept


def nearest(nodes: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Index of the node of the increasing ``nodes`` (k,) nearest to each value."""
    j = np.clip(np.searchsorted(nodes, values), 1, nodes.size - 1)
    return j - (values - nodes[j - 1] < nodes[j] - values)


def _cell_inverse(g0: np.ndarray, g1: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Inverse CDF on [0, 1] of the density proportional to (1 - s) g0 + s g1 at probabilities
    ``r`` (all (n,), g0, g1 >= 0)."""
    target = 0.5 * r * (g0 + g1)  # solve g0 s + (g1 - g0) s^2 / 2 = target
    denom = g0 + np.sqrt(np.maximum(g0 * g0 + 2.0 * (g1 - g0) * target, 0.0))
    return np.clip(2.0 * target / np.where(denom > 0.0, denom, 1.0), 0.0, 1.0)


@underflow_as_zero  # a density's far tails underflow to 0 as intended
def draw_bilinear(
    axes: list, dens: np.ndarray, rng: np.random.Generator, size: int
) -> tuple[np.ndarray, np.ndarray]:
    """``size`` draws (size, 2) from the bilinear interpolant of ``dens`` (n0, n1) on the grid of
    the native ``axes`` (the density whose marginals the posterior's GridMarginals are: a cell by
    its mass, then the first parameter from the cell's marginal, the second from its
    conditional), and the flat index ('ij') of each draw's nearest node."""
    h0, h1 = np.diff(axes[0]), np.diff(axes[1])
    corners = dens[:-1, :-1] + dens[1:, :-1] + dens[:-1, 1:] + dens[1:, 1:]
    cum = np.cumsum((np.outer(h0, h1) * corners).ravel())
    cell = np.searchsorted(cum, rng.random(size) * cum[-1], side="right")
    i, j = np.divmod(np.minimum(cell, cum.size - 1), h1.size)
    f00, f10, f01, f11 = dens[i, j], dens[i + 1, j], dens[i, j + 1], dens[i + 1, j + 1]
    s = _cell_inverse(f00 + f01, f10 + f11, rng.random(size))
    t = _cell_inverse((1 - s) * f00 + s * f10, (1 - s) * f01 + s * f11, rng.random(size))
    vals = np.column_stack([axes[0][i] + s * h0[i], axes[1][j] + t * h1[j]])
    node = (i + np.rint(s).astype(int)) * axes[1].size + j + np.rint(t).astype(int)
    return vals, node


def draw_allowed(
    axes: list,
    dens: np.ndarray,
    rng: np.random.Generator,
    size: int,
    allows: Callable[[np.ndarray], np.ndarray],
) -> np.ndarray:
    """``size`` draws (size, 2) from the bilinear interpolant of ``dens`` (n0, n1) on the native
    ``axes`` (`draw_bilinear`) restricted to where ``allows`` (native (k, 2) -> (k,) bool) holds:
    those it rejects are redrawn (each round draws the remainder over the acceptance seen so
    far). GPMSAError when MAX_REDRAW_ROUNDS rounds leave some undrawn."""
    kept, drawn, accepted = [], 0, 0
    for _ in range(MAX_REDRAW_ROUNDS):
        need = size - accepted
        if need == 0:
            break
        n = need if accepted == 0 else min(int(np.ceil(need * drawn / accepted)), 100 * need)
        vals = draw_bilinear(axes, dens, rng, n)[0]
        vals = vals[allows(vals)][:need]
        kept.append(vals)
        drawn, accepted = drawn + n, accepted + vals.shape[0]
    if accepted < size:
        raise GPMSAError(
            f"the constraint rejected {drawn - accepted} of {drawn} draws from the grid density "
            "(its allowed region is narrower than the grid resolves); use method='mcmc'"
        )
    return np.concatenate(kept)


@dataclass(frozen=True, eq=False)
class ConstraintCut:
    """A two-parameter grid (unit-scale ``axes``) whose cells that a constraint's boundary
    crosses (corners of both verdicts) are split N_SUB x N_SUB, the constraint evaluated at the
    new nodes in them: the density cut by the constraint is the bilinear interpolant of the
    free density onto the split grid, zero at its forbidden nodes, so that it falls to zero
    within one split cell of the boundary (a cell that no boundary crossing touches keeps the
    verdict of its corners).

    Attributes:
        axes: the split grid's unit-scale axes [(N0,), (N1,)] (every interval of a parameter
            that a crossed cell spans split in N_SUB).
        cells, frac: per parameter, the grid's interval (N_k,) holding each split node and its
            position in it, in [0, 1].
        allowed: (N0, N1) the constraint's verdict at the split grid's nodes.
        live: (n0, n1) the grid's nodes the cut density depends on: allowed ones and corners of
            crossed cells.
    """

    axes: list
    cells: list
    frac: list
    allowed: np.ndarray
    live: np.ndarray

    @classmethod
    def make(
        cls, axes: list, ok: np.ndarray, allows: Callable[[np.ndarray], np.ndarray]
    ) -> ConstraintCut:
        """The cut of the grid of unit-scale ``axes`` whose nodes have the verdicts ``ok``
        ((n0 n1,), 'ij' order); ``allows`` (unit-scale (k, 2) -> (k,) bool) gives the verdict
        at the new nodes."""
        ok = ok.reshape(axes[0].size, axes[1].size)
        corners = np.stack([ok[:-1, :-1], ok[1:, :-1], ok[:-1, 1:], ok[1:, 1:]])
        crossed = corners.any(axis=0) & ~corners.all(axis=0)
        fine, cells, frac, near = [], [], [], []
        for k, a in enumerate(axes):
            split = crossed.any(axis=1 - k)
            step = np.arange(1, N_SUB) / N_SUB
            new = (a[:-1, None] + np.diff(a)[:, None] * step)[split].ravel()
            f = np.sort(np.concatenate([a, new]))
            c = np.clip(np.searchsorted(a, f, side="right") - 1, 0, a.size - 2)
            t = np.clip((f - a[c]) / (a[c + 1] - a[c]), 0.0, 1.0)
            on_node = np.isin(f, a)
            below = np.where(on_node & (t == 0.0), np.maximum(c - 1, 0), c)  # cells touched
            fine.append(f), cells.append(c), frac.append(t), near.append((below, c, on_node))
        (lo0, hi0, node0), (lo1, hi1, node1) = near
        touches = (crossed[lo0][:, lo1] | crossed[lo0][:, hi1] | crossed[hi0][:, lo1]
                   | crossed[hi0][:, hi1])  # fmt: skip
        allowed = corners.all(axis=0)[cells[0]][:, cells[1]]  # the verdict of a cell not crossed
        allowed[np.ix_(node0, node1)] = ok
        check = touches & ~(node0[:, None] & node1[None, :])
        i, j = np.nonzero(check)
        allowed[i, j] = allows(np.column_stack([fine[0][i], fine[1][j]]))
        live = ok.copy()
        for di in (0, 1):
            for dj in (0, 1):
                live[di : di + crossed.shape[0], dj : dj + crossed.shape[1]] |= crossed
        return cls(fine, cells, frac, allowed, live)

    def density(self, dens: np.ndarray) -> np.ndarray:
        """The cut density (N0, N1) on the split grid from the free density ``dens`` (n0, n1)
        on the grid (bilinear, zero at forbidden nodes)."""
        (c0, c1), (t0, t1) = self.cells, self.frac
        rows = (1.0 - t0)[:, None] * dens[c0] + t0[:, None] * dens[c0 + 1]
        out = rows[:, c1] * (1.0 - t1) + rows[:, c1 + 1] * t1
        out[~self.allowed] = 0.0
        return out


def _one_resolved_peak(axis: np.ndarray, density: np.ndarray) -> bool:
    """Whether the density (k,) on ``axis`` (k,) rises to one peak and falls (no valley) with a
    spread (`_spread`) of at least RESOLVE_SD of the widest node spacing: a quick sufficient
    test that `_modes` finds nothing to refine (the usual case on the fixed grid)."""
    k = int(np.argmax(density))
    slope = np.diff(density)
    if slope[:k].min(initial=0.0) < 0.0 or slope[k:].max(initial=0.0) > 0.0:
        return False
    return bool(_spread(axis, density) >= RESOLVE_SD * np.diff(axis).max())


IQR_PER_SD = 1.3489795003921634
"""The interquartile range of a normal distribution, in sds."""


def _spread(axis: np.ndarray, mass: np.ndarray) -> float:
    """The smaller of the sd and IQR / IQR_PER_SD of the masses ``mass`` (k,) at the nodes
    ``axis`` (k,): the sd for a peak with light tails, less where heavy tails inflate the sd
    beyond the width of the peak's core (a heavy-tailed posterior cut by a constraint next to
    its peak: sd 2.2-2.8 times IQR / IQR_PER_SD, and the summaries at 4 spacings per sd up to
    0.15 sd off)."""
    total = mass.sum()
    mean = mass @ axis / total
    sd = float(np.sqrt(mass @ (axis - mean) ** 2 / total))
    cdf = (np.cumsum(mass) - 0.5 * mass) / total  # node i's mass centred on it
    q1, q3 = np.interp([0.25, 0.75], cdf, axis)
    return min(sd, float(q3 - q1) / IQR_PER_SD)


def _runs(density: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The runs of nodes of ``density`` (k,) above MASS_CUTOFF of its peak, as (first (r,),
    last (r,)), and its local minima (indices, for `_valleys`)."""
    live = np.flatnonzero(density >= MASS_CUTOFF * density.max())
    slope = np.diff(density)
    dips = np.flatnonzero((slope[:-1] < 0.0) & (slope[1:] > 0.0)) + 1
    cut = np.flatnonzero(np.diff(live) > 1)
    first = live[np.concatenate(([0], cut + 1))]
    last = live[np.concatenate((cut, [live.size - 1]))]
    return first, last, dips


def _modes(axis: np.ndarray, density: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The modes of a (marginal) density (k,) on the increasing ``axis`` (k,): the runs of nodes
    above MASS_CUTOFF of the peak, as (first (r,), last (r,), unresolved (r,)). A run is
    unresolved when a peak in it (the run cut at its `_valleys`) holds at least MODE_MASS of the
    mass and its spread (`_spread`) spans fewer than RESOLVE_SD of its node spacings. Nodes are
    equally spaced within a run (a refined region)."""
    first, last, dips = _runs(density)
    if first.size == 1 and dips.size == 0:  # one peak, the usual case
        _, sd, spacing = _mode_stats(axis, density, first[0], last[0])
        return first, last, np.array([sd < RESOLVE_SD * spacing])
    peaks, owner = [], []
    for r, (i0, i1) in enumerate(zip(first, last, strict=True)):
        bounds = [i0, *_valleys(density, dips, i0, i1), i1]
        peaks += [_mode_stats(axis, density, b0, b1) for b0, b1 in itertools.pairwise(bounds)]
        owner += [r] * (len(bounds) - 1)
    mass, sd, spacing = np.array(peaks).T
    narrow = (mass >= MODE_MASS * mass.sum()) & (sd < RESOLVE_SD * spacing)
    unresolved = np.zeros(first.size, dtype=bool)
    unresolved[np.asarray(owner)[narrow]] = True
    return first, last, unresolved


def _valleys(density: np.ndarray, dips: np.ndarray, i0: int, i1: int) -> list[int]:
    """The local minima ``dips`` inside the run i0..i1 of ``density`` that separate two peaks:
    lower than VALLEY times the highest density on either side, within the run (a shallow dip,
    such as rounding noise on a flat density, separates nothing)."""
    inside = dips[(dips > i0) & (dips < i1)]
    if inside.size == 0:
        return []
    run = density[i0 : i1 + 1]
    left = np.maximum.accumulate(run)[inside - i0]
    right = np.maximum.accumulate(run[::-1])[::-1][inside - i0]
    return inside[density[inside] < VALLEY * np.minimum(left, right)].tolist()


def _mode_stats(axis: np.ndarray, density: np.ndarray, i0: int, i1: int) -> tuple[float, ...]:
    """(mass, spread (`_spread`), node spacing) of the mode on nodes i0..i1 (and one more each
    side)."""
    d, a = density[i0 : i1 + 1], axis[i0 : i1 + 1]
    j0, j1 = max(i0 - 1, 0), min(i1 + 1, axis.size - 1)
    spacing = (axis[j1] - axis[j0]) / (j1 - j0)
    return d.sum() * spacing, _spread(a, d), spacing


def _finer_axis(
    axis: np.ndarray, modes: tuple, n: int, keep: np.ndarray | None, factor: float
) -> np.ndarray:
    """The axis of a refined grid: each mode's region (its nodes and one more each side) with
    ``n`` equally spaced nodes (fewer beyond REFINE_MODES modes), at least ``factor`` times as
    many cells as it has, where the mode is unresolved; its present nodes where it is resolved;
    the grid lines ``keep`` inside a refined region are kept."""
    first, last, unresolved = modes
    k = int(unresolved.sum())
    if k > REFINE_MODES:
        n = max(REFINE_MODES * n // k, MIN_MODE_NODES)
    pieces = []
    for i0, i1, finer in zip(first, last, unresolved, strict=True):
        j0, j1 = max(i0 - 1, 0), min(i1 + 1, axis.size - 1)
        if not finer:
            pieces.append(axis[j0 : j1 + 1])
            continue
        piece = np.linspace(axis[j0], axis[j1], max(n, int(np.ceil(factor * (j1 - j0))) + 1))
        if keep is not None:
            lines = keep[(keep > axis[j0]) & (keep < axis[j1])]
            near = np.abs(piece[:, None] - lines[None, :]).min(axis=1, initial=np.inf)
            piece = np.concatenate([piece[near > SAME_NODE * (piece[1] - piece[0])], lines])
        pieces.append(piece)
    return np.unique(np.concatenate(pieces))


def zero_edges(axes: list, log_prior: np.ndarray) -> list:
    """Per parameter, the grid lines a refined grid keeps for a gridded prior with zeros (log
    values ``log_prior`` (G,) on the grid of ``axes``, -inf where it is zero): both lines of
    every cell across which the prior changes between zero and non-zero, so that its zero region
    and the linear ramp into it stay where the fixed grid puts them. Only those: keeping every
    line held a fine base grid (n_grid > 516) at its own nodes, unrefined."""
    zero = np.isneginf(log_prior).reshape([a.size for a in axes])
    out = []
    for k, a in enumerate(axes):
        z = np.moveaxis(zero, k, 0).reshape(a.size, -1)
        crossed = np.any(z[1:] != z[:-1], axis=1)  # cell i (lines i, i + 1) crossed
        out.append(a[np.concatenate(([False], crossed)) | np.concatenate((crossed, [False]))])
    return out


@underflow_as_zero  # a density's far tails underflow to 0 as intended
def conditional_sds(axes: list, logp: np.ndarray) -> tuple[float, float]:
    """Two parameters: per parameter, the root of the mean (over the posterior, log density
    ``logp`` (G,) on the grid of ``axes``) of its variance given the other parameter's node, in
    units of the local node spacing (root of the mean squared spacing at the posterior's nodes).
    Computed on the nodes, so a ridge narrower than a spacing gets well under RIDGE_SD."""
    f = np.exp(logp - np.max(logp)).reshape(axes[0].size, axes[1].size)
    w = [trapezoid_weights(a) for a in axes]
    mass = f * np.outer(w[0], w[1])
    out = []
    for k, a in enumerate(axes):
        m = mass if k == 1 else mass.T  # rows: the other parameter's nodes
        row = m.sum(axis=1)
        live = row > 0.0
        m, row = m[live], row[live]
        mean = m @ a / row
        var = np.sum(m * (a[None, :] - mean[:, None]) ** 2, axis=1) / row
        h = np.diff(a)
        local = np.concatenate(([h[0]], np.maximum(h[:-1], h[1:]), [h[-1]]))
        spacing2 = m.sum(axis=0) @ local**2 / row.sum()
        out.append(float(np.sqrt(row @ var / row.sum() / spacing2)))
    return out[0], out[1]


def _marginals(axes: list, logp: np.ndarray) -> list:
    """The posterior's (log density ``logp`` (G,) on the grid of ``axes``) marginal density
    (unnormalised) at the nodes of each axis (trapezoid sums; one parameter: the density)."""
    if len(axes) == 1:
        return [np.exp(logp - np.max(logp))]
    f = np.exp(logp - np.max(logp)).reshape(axes[0].size, axes[1].size)
    w = [trapezoid_weights(a) for a in axes]
    return [f @ w[1], w[0] @ f]


def _resolution(axis: np.ndarray, density: np.ndarray) -> float:
    """The node spacings per sd of the marginal ``density`` (k,) on ``axis`` (k,), its peaks
    (runs above MASS_CUTOFF cut at their `_valleys`) taken together: the inverse root of the
    mass-weighted mean of (local spacing / sd)^2 over the peaks, a peak's sd (its `_spread`)
    and spacing taken at its own nodes (trapezoid weights; the local spacing the wider interval
    next to a node, root-mean-squared over the peak's mass), so that a refined, non-uniform
    axis is measured by the spacing where the mass lies. The interpolation errors go as its
    inverse square. A peak on one node is unresolved (0.0) where it holds MODE_MASS of the mass
    or more, left out below (as `_modes` leaves it unrefined: a far tail's bump at 1e-13 read
    as "0 node spacings" a posterior that its other nodes resolved)."""
    w = trapezoid_weights(axis)
    h = np.diff(axis)
    local2 = np.concatenate(([h[0]], np.maximum(h[:-1], h[1:]), [h[-1]])) ** 2
    first, last, dips = _runs(density)
    total, inverse2, points = 0.0, 0.0, 0.0
    for i0, i1 in zip(first, last, strict=True):
        bounds = [i0, *_valleys(density, dips, i0, i1), i1]
        for b0, b1 in itertools.pairwise(bounds):
            m, a = density[b0 : b1 + 1] * w[b0 : b1 + 1], axis[b0 : b1 + 1]
            mass = m.sum()
            var = _spread(a, m) ** 2
            if var > 0.0:
                inverse2 += m @ local2[b0 : b1 + 1] / var
                total += mass
            else:  # a peak on one node
                points = max(points, mass)
    if points >= MODE_MASS * density @ w:
        return 0.0
    return float(np.sqrt(total / inverse2))


@underflow_as_zero  # a density's far tails underflow to 0 as intended
def resolution(axes: list, logp: np.ndarray) -> tuple[float, ...]:
    """Per parameter, the node spacings per sd of its marginal on the grid of ``axes``
    (`_resolution`; the posterior's log density ``logp`` (G,))."""
    return tuple(_resolution(a, m) for a, m in zip(axes, _marginals(axes, logp), strict=True))


def _core(axis: np.ndarray, density: np.ndarray) -> tuple[int, int]:
    """The first and last node of ``axis`` (k,) bounding all but at most TAIL_MASS of the mass of
    the piecewise-linear ``density`` (k,) (half each side), one more node each side."""
    cells = np.cumsum(0.5 * np.diff(axis) * (density[:-1] + density[1:]))
    below = np.concatenate(([0.0], cells))  # the mass before each node
    tail = 0.5 * TAIL_MASS * below[-1]
    i0 = int(np.flatnonzero(below <= tail)[-1])
    i1 = int(np.flatnonzero(below >= below[-1] - tail)[0])
    return max(i0 - 1, 0), min(i1 + 1, axis.size - 1)


@underflow_as_zero  # a density's far tails underflow to 0 as intended
def tail_refined_axes(
    axes: list,
    logp: np.ndarray,
    keep: list | None,
    res: tuple[float, ...],
    below: float = UNRESOLVED_SD,
) -> list | None:
    """Where `refined_axes` found no refinement factor that fits MAX_REFINED: when the
    resolution ``res`` (`resolution`) of some parameter is under ``below`` (two parameters:
    UNRESOLVED_SD; one, `refined_axis`: RESOLVE_SD), the
    unit-scale axes of a grid on which each parameter under RESOLVE_SD has the nodes of its
    core (`_core`: the region holding all but TAIL_MASS of its marginal mass) replaced by
    equally spaced ones, about RESOLVE_SD per sd (at least N_REFINE_2D, N_REFINE for one
    parameter, and REFINE_FACTORS[-1] times the cells), and a share of its tails' nodes kept
    (`_with_core`; the first of TAIL_SHARES that fits the grid within MAX_REFINED times
    N_REFINE_2D squared nodes, N_REFINE for one parameter);
    ``keep``: grid lines per parameter that it keeps (None: none). None where no parameter is
    under ``below``, or no core is narrower than its axis (heavy tails are not what holds
    the grid), or nothing fits."""
    if min(res) >= below:
        return None
    n_core = N_REFINE if len(axes) == 1 else N_REFINE_2D
    parts = []
    for k, (a, m) in enumerate(zip(axes, _marginals(axes, logp), strict=True)):
        c0, c1 = _core(a, m)
        if res[k] >= RESOLVE_SD or c1 - c0 + 1 == a.size:
            parts.append((a, None, None, None))
            continue
        factor = max(REFINE_FACTORS[-1], RESOLVE_SD / max(res[k], 0.1))
        n = max(n_core, int(np.ceil(factor * (c1 - c0))) + 1)
        core = np.linspace(a[c0], a[c1], n)
        if keep is not None:
            lines = keep[k][(keep[k] > a[c0]) & (keep[k] < a[c1])]
            near = np.abs(core[:, None] - lines[None, :]).min(axis=1, initial=np.inf)
            core = np.concatenate([core[near > SAME_NODE * (core[1] - core[0])], lines])
        parts.append((a, core, c0, c1))
    if all(core is None for _, core, _, _ in parts):
        return None
    limit = MAX_REFINED * n_core ** len(axes)
    for share in TAIL_SHARES:
        finer = [a if core is None else _with_core(a, core, c0, c1, share, keep, k)
                 for k, (a, core, c0, c1) in enumerate(parts)]  # fmt: skip
        if np.prod([a.size for a in finer]) <= limit:
            return finer
    return None


def _with_core(
    axis: np.ndarray, core: np.ndarray, c0: int, c1: int, share: float, keep: list | None, k: int
) -> np.ndarray:
    """``axis`` with its nodes c0..c1 replaced by ``core`` and ``share`` of the nodes beyond on
    each side kept, spaced geometrically from the core (all the nearest, ever fewer further
    out; the end nodes and the grid lines ``keep[k]`` kept)."""
    pieces = [core, axis[[0, -1]]]
    for edge, far in ((c0, 0), (c1, axis.size - 1)):
        span = abs(far - edge)  # the nodes beyond the core on this side
        if span > 0:
            count = max(int(np.ceil(share * span)), 2)
            offsets = np.unique(np.rint(np.geomspace(1, span, count)).astype(int))
            pieces.append(axis[edge + np.sign(far - edge) * offsets])
    if keep is not None:
        pieces.append(keep[k][(keep[k] >= axis[0]) & (keep[k] <= axis[-1])])
    return np.unique(np.concatenate(pieces))


@underflow_as_zero  # a density's far tails underflow to 0 as intended
def refined_axes(axes: list, logp: np.ndarray, keep: list | None) -> list | None:
    """Two parameters: the unit-scale axes of a finer grid where a mode of the posterior (log
    density ``logp`` (G,) on the grid of ``axes``) is not resolved along some parameter
    (`_modes` of its marginal), None when all are or no refinement factor fits MAX_REFINED;
    ``keep``: grid lines per parameter that a refined region keeps (None: none). One
    parameter: `refined_axis`."""
    modes = [_modes(a, m) for a, m in zip(axes, _marginals(axes, logp), strict=True)]
    if not any(m[2].any() for m in modes):
        return None
    for factor in REFINE_FACTORS:  # the largest that keeps the grid within MAX_REFINED
        finer = [
            _finer_axis(a, m, N_REFINE_2D, None if keep is None else keep[k], factor)
            for k, (a, m) in enumerate(zip(axes, modes, strict=True))
        ]
        if finer[0].size * finer[1].size <= MAX_REFINED * N_REFINE_2D**2:
            return finer
    return None


def whole_refined_axis(axis: np.ndarray) -> np.ndarray:
    """One parameter: the axis `refined_axis` gives when one unresolved mode holds the whole
    ``axis`` (the usual refinement of a narrow posterior with heavy tails, no grid lines kept):
    what a Calibrator can prepare its predictor for once, instead of dense solves per update."""
    last = np.array([axis.size - 1])
    return _finer_axis(axis, (np.array([0]), last, np.array([True])), N_REFINE, None,
                       REFINE_FACTORS[0])  # fmt: skip


@underflow_as_zero  # a density's far tails underflow to 0 as intended
def refined_axis(
    axis: np.ndarray, logp: np.ndarray, keep: np.ndarray | None, min_step: float
) -> tuple[np.ndarray | None, str]:
    """One parameter: the unit-scale axis of the next grid and why, from the posterior's log
    density ``logp`` (k,) on ``axis`` (k,):

    - (None, "resolved"): every peak is resolved (the usual case, found by a quick test);
    - (finer, "refine"): a finer axis over each unresolved peak (as `refined_axes` for two);
    - (finer, "tails") or (None, "tails"): no refinement factor fits MAX_REFINED (heavy tails
      hold a region above MASS_CUTOFF wider than the node budget): `tail_refined_axes` (None
      where it does not apply or fit); the last pass;
    - (None, "float"): the finer axis would space nodes closer than ``min_step`` (float64's
      resolution of the parameter, unit scale): the posterior is narrower than the grid can
      represent.

    ``keep``: grid lines a refined region keeps (None: none)."""
    f = np.exp(logp - np.max(logp))
    if _one_resolved_peak(axis, f):
        return None, "resolved"
    modes = _modes(axis, f)  # no trapezoid weights: equally spaced within a mode
    if not modes[2].any():
        return None, "resolved"
    for factor in REFINE_FACTORS:  # the largest that keeps the grid within MAX_REFINED
        finer = _finer_axis(axis, modes, N_REFINE, keep, factor)
        if finer.size <= MAX_REFINED * N_REFINE:
            return (None, "float") if np.diff(finer).min() < min_step else (finer, "refine")
    keeps = None if keep is None else [keep]
    tails = tail_refined_axes([axis], logp, keeps, resolution([axis], logp), RESOLVE_SD)
    if tails is not None and np.diff(tails[0]).min() < min_step:
        return None, "float"
    return (None if tails is None else tails[0]), "tails"
