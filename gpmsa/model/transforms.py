"""Maps between native units and GPM/SA's unit-cube inputs and standardised outputs."""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from gpmsa.errors import ExtrapolationWarning, GPMSAError, numbers_text, user_stacklevel
from gpmsa.model import index_points
from gpmsa.model.data import SimData, check_increasing, column_scales, output_scale
from gpmsa.model.index_points import is_points, n_points

UNIT_TOL = 1e-9
"""Unit-scale values within this distance outside [0, 1] are rounding of the design's edges (a
design stretched onto [0.5, 2.0] may store 1.9999999999999998): they are snapped onto the edge, so
that an input at the domain's end never reads as outside it."""


Y_GIVEN = ("y_mean", "y_sd")
"""What of the output standardisation a user may give (``SimData(y_mean=, y_sd=)``), in the
order ``Standardizer.y_given`` and the file's ``model.y_given`` list it."""


EXTRAPOLATION_MARGIN = 0.1
"""How far (unit scale) inputs may lie outside the design's range, for predictions and
observations alike: outside the range a warning, beyond the margin a refusal."""


def check_extrapolation(
    native: np.ndarray,
    unit: np.ndarray,
    names: Sequence[str],
    lo,
    hi,
    what: str | Sequence[str],
    extrapolate: bool | None = None,
) -> None:
    """The library's rule for inputs (rows ``native`` (N, d), ``unit`` their unit scale) against
    the emulator's domain [``lo``, ``hi``] (per column, native units): inside it silent; outside
    it by up to ``EXTRAPOLATION_MARGIN`` of a column's width an ``ExtrapolationWarning``; beyond
    a GPMSAError, unless ``extrapolate`` (then the warning). Both name the argument (``what``:
    its name, or one per column where columns come from several arguments, as ``predict``'s x
    and t), the column, the values it reaches and the domain; ``extrapolate``: the caller's
    option of that name (False: the error points at it), None where it has none. The warning
    names the user's call, however deep the caller (`user_stacklevel`, found only when there is
    a warning to give)."""
    below, above = unit.min(axis=0), unit.max(axis=0)
    far = (below < -EXTRAPOLATION_MARGIN) | (above > 1 + EXTRAPOLATION_MARGIN)
    outside = far | (below < 0) | (above > 1)
    if not outside.any():
        return
    k = int(np.flatnonzero(far if far.any() else outside)[0])
    arg = what if isinstance(what, str) else what[k]
    a, b, c, d = numbers_text(native[:, k].min(), native[:, k].max(), lo[k], hi[k])
    msg = f"{arg}: {names[k]} reaches [{a}, {b}], outside the emulator's domain [{c}, {d}]"
    if far[k]:
        msg += f" by more than {EXTRAPOLATION_MARGIN:.0%} of its width"
        if not extrapolate:
            raise GPMSAError(
                msg + ("; pass extrapolate=True to allow it" if extrapolate is False else "")
            )
    msg += "; the emulator extrapolates there"
    warnings.warn(msg, ExtrapolationWarning, stacklevel=user_stacklevel())


def snap_to_unit(u: np.ndarray) -> np.ndarray:
    """``u`` with values within ``UNIT_TOL`` below 0 or above 1 moved onto the edge."""
    u = np.where((u < 0.0) & (u > -UNIT_TOL), 0.0, u)
    return np.where((u > 1.0) & (u < 1.0 + UNIT_TOL), 1.0, u)


def _domain(arr: np.ndarray, ranges) -> tuple[np.ndarray, np.ndarray, tuple[bool, ...]]:
    """Per column of a design ``arr`` its unit domain (lo, hi) and whether it was given:
    the design's min/max, or the (min, max) of ``ranges`` (`SimData`'s, None: none given)."""
    lo, hi = arr.min(axis=0), arr.max(axis=0)
    if ranges is None:
        return lo, hi, ()
    for j, r in enumerate(ranges):
        if r is not None:
            lo[j], hi[j] = r
    return lo, hi, tuple(r is not None for r in ranges)


@dataclass(frozen=True, eq=False)
class Standardizer:
    """x, t -> [0, 1] by the design's min/max (or the user's range); y -> (y - mean) / sd with
    one scalar sd, or one sd per output element (``SimData(y_scale="columnwise")``).

    Attributes (native units): ``x_min``, ``x_max`` (p,), ``t_min``, ``t_max`` (q,): the unit
    domain, per column the design's min/max or the range the user gave (``SimData(x_range=,
    t_range=)``), which ``x_ranged``, ``t_ranged`` flag (one bool per column; empty: none);
    ``y_mean`` (l_sim,) on the simulation grid ``grid`` (l_sim,) (or index points (l_sim, d)),
    ``y_sd``: a float (one sd, ddof=1, over all outputs: GPM/SA's default) or, scaled
    columnwise, an array (l_sim,) of
    each element's sd (``columnwise``); ``sd_on`` gives it on any grid. ``y_given``: which of
    "y_mean", "y_sd" the user gave (``SimData(y_mean=, y_sd=)``) instead of the runs' own
    (empty: neither); a given y_sd array (l_sim,) scales each element by its own.
    """

    x_min: np.ndarray
    x_max: np.ndarray
    t_min: np.ndarray
    t_max: np.ndarray
    y_mean: np.ndarray
    y_sd: float | np.ndarray
    grid: np.ndarray
    x_ranged: tuple[bool, ...] = ()
    t_ranged: tuple[bool, ...] = ()
    y_given: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        for name in ("x_ranged", "t_ranged"):  # no column given reads (), however built
            flags = tuple(getattr(self, name))
            object.__setattr__(self, name, flags if any(flags) else ())

    @classmethod
    def from_sim(cls, sim: SimData) -> Standardizer:
        """GPM/SA's default transforms fitted to the simulation design and outputs; a column
        with a given range (``sim.x_range``, ``sim.t_range``) maps that range onto [0, 1]; a
        given ``sim.y_mean``, ``sim.y_sd`` replaces the runs' mean, sd."""
        x_min, x_max, x_ranged = _domain(sim.x, sim.x_range)
        t_min, t_max, t_ranged = _domain(sim.t, sim.t_range)
        if sim.y_sd is not None:
            y_sd = sim.y_sd if isinstance(sim.y_sd, float) else sim.y_sd.copy()
        elif sim.y_scale == "columnwise" and sim.l_sim > 1:
            y_sd = column_scales(sim.y, sim.y_names)
        else:
            y_sd = output_scale(sim.y)
        return cls(
            x_min=x_min,
            x_max=x_max,
            t_min=t_min,
            t_max=t_max,
            y_mean=sim.y.mean(axis=0) if sim.y_mean is None else sim.y_mean.copy(),
            y_sd=y_sd,
            grid=sim.grid.copy(),
            x_ranged=x_ranged,
            t_ranged=t_ranged,
            y_given=tuple(k for k in Y_GIVEN if getattr(sim, k) is not None),
        )

    def ranged(self, names: tuple[str, ...]) -> tuple[str, ...]:
        """Of the inputs ``names`` (x names, then t names), those whose range the user gave."""
        flags = (self.x_ranged or (False,) * self.x_min.size) + (
            self.t_ranged or (False,) * self.t_min.size
        )
        return tuple(n for n, f in zip(names, flags, strict=True) if f)

    def x_to_unit(self, x: np.ndarray) -> np.ndarray:
        """Known inputs (n, p) native -> unit scale."""
        u = (np.asarray(x, dtype=np.float64) - self.x_min) / (self.x_max - self.x_min)
        return snap_to_unit(u)

    def x_from_unit(self, x: np.ndarray) -> np.ndarray:
        """Known inputs (n, p) unit scale -> native."""
        return np.asarray(x) * (self.x_max - self.x_min) + self.x_min

    def t_to_unit(self, t: np.ndarray) -> np.ndarray:
        """Parameters (n, q) native -> unit scale."""
        u = (np.asarray(t, dtype=np.float64) - self.t_min) / (self.t_max - self.t_min)
        return snap_to_unit(u)

    def t_from_unit(self, t: np.ndarray) -> np.ndarray:
        """Parameters (n, q) unit scale -> native: theta * (t_max - t_min) + t_min."""
        return np.asarray(t) * (self.t_max - self.t_min) + self.t_min

    def mean_on(self, grid: np.ndarray | None) -> np.ndarray:
        """The simulation mean interpolated onto ``grid`` (any order; None: the simulation
        grid, which is strictly increasing)."""
        return self._on(self.y_mean, grid)

    def _on(self, values: np.ndarray, grid: np.ndarray | None) -> np.ndarray:
        """``values`` (l_sim,) on the simulation grid, interpolated onto ``grid`` (index points
        (l, d): piecewise linearly on the simulation points' triangulation)."""
        if grid is None or (grid.shape == self.grid.shape and np.array_equal(grid, self.grid)):
            return values
        if values.size == 1:
            return np.full(n_points(grid), values[0])
        if is_points(self.grid) or is_points(grid):
            return index_points.weights(self.grid, grid, "observation index") @ values
        check_increasing(self.grid, "the simulation grid")
        return np.interp(grid, self.grid, values)

    @property
    def columnwise(self) -> bool:
        """Whether each output element has its own sd (``SimData(y_scale="columnwise")``, or a
        given ``y_sd`` array)."""
        return isinstance(self.y_sd, np.ndarray)

    def sd_on(self, grid: np.ndarray | None) -> float | np.ndarray:
        """The output scale on ``grid`` (as `mean_on`): the one sd (a float), or scaled
        columnwise each element's sd interpolated onto ``grid`` (l,)."""
        return self._on(self.y_sd, grid) if self.columnwise else self.y_sd

    def y_to_std(self, y: np.ndarray, grid: np.ndarray | None = None) -> np.ndarray:
        """Outputs (..., l) native -> standardised, on ``grid`` (None: the simulation grid)."""
        return (np.asarray(y, dtype=np.float64) - self.mean_on(grid)) / self.sd_on(grid)

    def y_from_std(self, y: np.ndarray, grid: np.ndarray | None = None) -> np.ndarray:
        """Outputs (..., l) standardised -> native."""
        return np.asarray(y) * self.sd_on(grid) + self.mean_on(grid)

    def var_from_std(self, var: np.ndarray, grid: np.ndarray | None = None) -> np.ndarray:
        """Variances (..., l) in standardised units -> native units^2, on ``grid``."""
        return np.asarray(var) * self.sd_on(grid) ** 2

    def precision_to_std(self, lam: np.ndarray, grid: np.ndarray | None = None) -> np.ndarray:
        """An observation precision matrix (l, l) in native units^-2 -> standardised units:
        lam * sd^2, or scaled columnwise S lam S with S = diag(sd on ``grid``)."""
        sd = self.sd_on(grid)
        return lam * sd**2 if not self.columnwise else lam * np.outer(sd, sd)
