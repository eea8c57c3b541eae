"""Simulation and observation data containers (native units, validated on construction)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from gpmsa.errors import GPMSAError
from gpmsa.model import categorical


def as_float(value, name: str) -> np.ndarray:
    """Return ``value`` as a float64 array (a copy); GPMSAError naming ``name`` when it is not
    real numbers (strings, objects, ragged lists; complex values, which are never cast to their
    real part)."""
    try:
        is_complex = np.iscomplexobj(value)
        arr = None if is_complex else np.array(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise GPMSAError(f"{name} must be a numeric array, got {type(value).__name__}") from exc
    if arr is None:
        raise GPMSAError(f"{name} must hold real numbers, got complex values")
    return arr


def as_matrix(value, name: str, *, ncols: int | None = None) -> np.ndarray:
    """Return ``value`` as a finite float64 2-D array; a 1-D array becomes one column.

    Raises GPMSAError naming ``name`` for non-numeric or complex values, a wrong shape or
    non-finite entries.
    """
    arr = as_float(value, name)
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.ndim != 2 or arr.shape[0] == 0 or arr.shape[1] == 0:
        raise GPMSAError(
            f"{name} must be a non-empty 2-D array (rows x columns), got shape {arr.shape}"
        )
    if ncols is not None and arr.shape[1] != ncols:
        raise GPMSAError(f"{name} must have {ncols} columns, got shape {arr.shape}")
    check_finite(arr, name)
    return arr


def check_finite(arr: np.ndarray, name: str) -> None:
    """Raise GPMSAError if ``arr`` holds NaN or inf, naming the first bad position."""
    bad = ~np.isfinite(arr)
    if bad.any():
        pos = tuple(int(i) for i in np.argwhere(bad)[0])
        raise GPMSAError(f"{name} must be finite, got {arr[pos]} at index {pos}")


def check_count(value, name: str, low: int = 1, high: int | None = None) -> int:
    """``value`` as an int >= ``low`` (and <= ``high`` if given); GPMSAError naming ``name``
    otherwise (a bool, a float, a string or NaN is not a count)."""
    ok = not isinstance(value, bool) and isinstance(value, int | np.integer)
    if not ok or value < low or (high is not None and value > high):
        allowed = f">= {low}" if high is None else f"in [{low}, {high}]"
        raise GPMSAError(f"{name} must be an integer {allowed}, got {value!r}")
    return int(value)


def check_level(level) -> float:
    """A probability ``level`` of a credible or prediction interval as a float in (0, 1);
    GPMSAError otherwise (a string, a bool or an array is not a level)."""
    real = not isinstance(level, bool) and isinstance(level, int | float | np.integer | np.floating)
    if not (real and 0.0 < level < 1.0):
        raise GPMSAError(f"level must be a number in (0, 1), got {level!r}")
    return float(level)


MAX_SEED = 2**128
"""Seeds are integers in [0, MAX_SEED) (numpy's SeedSequence takes non-negative integers)."""


def check_seed(seed, name: str = "seed", *, generator: bool = False):
    """Return ``seed`` if it is None or an integer in [0, 2**128) (or, with ``generator=True``,
    a ``numpy.random.Generator``); else raise GPMSAError naming the argument and the range.

    numpy itself refuses a negative seed deep inside SeedSequence; this says so up front.
    """
    if seed is None or (generator and isinstance(seed, np.random.Generator)):
        return seed
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):
        kinds = "None, an integer or a numpy Generator" if generator else "None or an integer"
        raise GPMSAError(f"{name} must be {kinds}, got {seed!r} ({type(seed).__name__})")
    if not 0 <= int(seed) < MAX_SEED:
        raise GPMSAError(f"{name}={int(seed)} is out of range: allowed integers in [0, 2**128)")
    return int(seed)


def output_scale(y: np.ndarray) -> float:
    """GPM/SA's output scale of simulation outputs ``y`` (m, l): the sd (ddof=1) of all values
    after centring each column; GPMSAError naming ``y`` when it is zero or not finite (values so
    large that their squares overflow)."""
    with np.errstate(over="ignore", invalid="ignore"):
        sd = float(np.std(y - y.mean(axis=0), ddof=1))
    if not np.isfinite(sd):
        raise GPMSAError(
            f"y is too large to standardise: its spread overflows float64 (largest |y| = "
            f"{np.abs(y).max():.3g}); rescale y (e.g. other units)"
        )
    if not sd > 0:
        raise GPMSAError("y has zero spread after centring each column; the output must vary")
    return sd


def _names(names: Sequence[str] | None, n: int, prefix: str, what: str) -> tuple[str, ...]:
    if names is None:
        return tuple(f"{prefix}{i}" for i in range(n))
    names = tuple(str(s) for s in names)
    if len(names) != n:
        raise GPMSAError(f"{what} must have {n} entries, got {len(names)}: {names}")
    if len(set(names)) != n:
        raise GPMSAError(f"{what} must be unique, got {names}")
    return names


def _units(units: Sequence[str] | None, n: int, what: str) -> tuple[str, ...]:
    if units is None:
        return ("",) * n
    units = tuple(str(s) for s in units)
    if len(units) != n:
        raise GPMSAError(f"{what} must have {n} entries, got {len(units)}: {units}")
    return units


def _index(index, n: int, name: str) -> np.ndarray | None:
    if index is None:
        return None
    arr = as_float(index, name).reshape(-1)
    if arr.size != n:
        raise GPMSAError(f"{name} must have {n} entries (one per output column), got {arr.size}")
    check_finite(arr, name)
    return arr


@dataclass(frozen=True, eq=False)
class SimData:
    """Simulation runs: inputs ``x`` (m, p), parameters ``t`` (m, q), outputs ``y`` (m, l_sim).

    ``index`` (l_sim,) is the output grid of a multivariate output (None: 0..l_sim-1).
    Names default to x0.., t0.., y0..; units to "". A 1-D ``x``, ``t`` or ``y`` is one column.
    ``x_categorical``, ``t_categorical``: the categorical inputs (column indices or names; None:
    none), whose values are integer level codes; see docs/categorical-and-constraints.md.
    """

    x: np.ndarray
    t: np.ndarray
    y: np.ndarray
    index: np.ndarray | None = None
    x_names: tuple[str, ...] | None = None
    t_names: tuple[str, ...] | None = None
    y_names: tuple[str, ...] | None = None
    x_units: tuple[str, ...] | None = None
    t_units: tuple[str, ...] | None = None
    y_units: tuple[str, ...] | None = None
    x_categorical: Sequence[int | str] | None = None
    t_categorical: Sequence[int | str] | None = None

    def __post_init__(self) -> None:
        x = as_matrix(self.x, "x")
        t = as_matrix(self.t, "t")
        y = as_matrix(self.y, "y")
        m = x.shape[0]
        if t.shape[0] != m or y.shape[0] != m:
            raise GPMSAError(
                f"x, t and y must have the same number of rows (runs), got x {x.shape}, "
                f"t {t.shape}, y {y.shape}"
            )
        p, q = x.shape[1], t.shape[1]
        if m < p + q + 2:
            raise GPMSAError(
                f"need at least p + q + 2 = {p + q + 2} simulation runs for {p + q} inputs, got {m}"
            )
        for arr, name, names in ((x, "x", self.x_names), (t, "t", self.t_names)):
            span = arr.max(axis=0) - arr.min(axis=0)
            const = np.flatnonzero(span <= 1e-12 * np.maximum(1.0, np.abs(arr).max(axis=0)))
            if const.size:
                j = int(const[0])
                label = names[j] if names is not None and len(names) > j else f"{name}[:, {j}]"
                raise GPMSAError(
                    f"design column {label} is constant ({arr[0, j]}); every input must vary"
                )
        if np.ptp(y) == 0.0:
            raise GPMSAError(f"y is constant ({y[0, 0]}); the simulation output must vary")
        output_scale(y)
        object.__setattr__(self, "x", x)
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "y", y)
        object.__setattr__(self, "index", _index(self.index, y.shape[1], "index"))
        object.__setattr__(self, "x_names", _names(self.x_names, p, "x", "x_names"))
        object.__setattr__(self, "t_names", _names(self.t_names, q, "t", "t_names"))
        if shared := sorted(set(self.x_names) & set(self.t_names)):
            raise GPMSAError(
                f"x_names and t_names must not share a name (an input is either known or "
                f"calibrated), got {shared} in both"
            )
        object.__setattr__(self, "y_names", _names(self.y_names, y.shape[1], "y", "y_names"))
        object.__setattr__(self, "x_units", _units(self.x_units, p, "x_units"))
        object.__setattr__(self, "t_units", _units(self.t_units, q, "t_units"))
        object.__setattr__(self, "y_units", _units(self.y_units, y.shape[1], "y_units"))
        for arr, attr, names in ((x, "x_categorical", self.x_names),
                                 (t, "t_categorical", self.t_names)):  # fmt: skip
            cols = categorical.columns(getattr(self, attr), names, attr)
            categorical.check_integer_levels(arr, cols, names, attr[0])
            object.__setattr__(self, attr, cols)

    @property
    def m(self) -> int:
        """Number of simulation runs."""
        return self.x.shape[0]

    @property
    def p(self) -> int:
        """Number of known inputs."""
        return self.x.shape[1]

    @property
    def q(self) -> int:
        """Number of calibration parameters."""
        return self.t.shape[1]

    @property
    def l_sim(self) -> int:
        """Length of one simulation output."""
        return self.y.shape[1]

    @property
    def grid(self) -> np.ndarray:
        """Output index grid (l_sim,): ``index`` or 0..l_sim-1."""
        return self.index if self.index is not None else np.arange(self.l_sim, dtype=np.float64)

    @property
    def levels(self) -> categorical.Levels:
        """Per column of [x, t]: the training levels of a categorical input, None otherwise."""
        return categorical.levels_of(self.x, self.t, self.x_categorical, self.t_categorical)


@dataclass(frozen=True, eq=False)
class ObsData:
    """Field observations: known inputs ``x`` (n, p) and outputs ``y`` in native units.

    ``y`` is (n, l_obs), or a list of n 1-D arrays of differing lengths ("ragged"), each with its
    ``index`` grid (a list of arrays; a single array applies to every experiment; None means the
    simulation grid). ``precision`` is the observation-error precision in native units
    (1/unit^2): None (identity in standardised units, GPM/SA's default), or per experiment a
    scalar or an (l_j, l_j) matrix (a list, or an array of shape (n,) or (n, l, l)).
    """

    x: np.ndarray
    y: np.ndarray | list[np.ndarray]
    index: np.ndarray | list[np.ndarray] | None = None
    precision: np.ndarray | list[np.ndarray] | None = None
    experiments: list[np.ndarray] = field(init=False, repr=False)
    grids: list[np.ndarray | None] = field(init=False, repr=False)
    precisions: list[np.ndarray] | None = field(init=False, repr=False)

    def __post_init__(self) -> None:
        x = as_matrix(self.x, "x_obs")
        n = x.shape[0]
        ys = self._experiments(self.y, n)
        object.__setattr__(self, "x", x)
        object.__setattr__(self, "experiments", ys)
        object.__setattr__(self, "grids", self._grids(self.index, ys))
        object.__setattr__(self, "precisions", self._precisions(self.precision, ys))
        ragged = len({len(e) for e in ys}) > 1
        object.__setattr__(self, "y", ys if ragged else np.stack(ys))

    @staticmethod
    def _experiments(y, n: int) -> list[np.ndarray]:
        if isinstance(y, (list, tuple)) and any(np.ndim(e) == 1 and np.size(e) > 1 for e in y):
            ys = [as_float(e, f"y_obs[{j}]").reshape(-1) for j, e in enumerate(y)]
        else:
            arr = as_float(y, "y_obs")
            if arr.ndim == 1:
                arr = arr[:, None] if arr.size == n else arr[None, :]
            if arr.ndim != 2:
                raise GPMSAError(
                    f"y_obs must be (n, l_obs) or a list of 1-D arrays, got {arr.shape}"
                )
            ys = list(arr)
        if len(ys) != n:
            raise GPMSAError(f"y_obs must have one row per x_obs row ({n}), got {len(ys)}")
        for j, e in enumerate(ys):
            if e.size == 0:
                raise GPMSAError(f"y_obs[{j}] is empty")
            check_finite(e, f"y_obs[{j}]")
        return ys

    @staticmethod
    def _grids(index, ys: list[np.ndarray]) -> list[np.ndarray | None]:
        if index is None:
            return [None] * len(ys)
        if isinstance(index, (list, tuple)) and len(index) == len(ys) and np.ndim(index[0]) == 1:
            grids = [as_float(g, f"index_obs[{j}]").reshape(-1) for j, g in enumerate(index)]
        else:
            g = as_float(index, "index_obs").reshape(-1)
            grids = [g] * len(ys)
        for j, (g, e) in enumerate(zip(grids, ys, strict=True)):
            if g.size != e.size:
                raise GPMSAError(f"index of experiment {j} has {g.size} points, y_obs has {e.size}")
            check_finite(g, f"index_obs[{j}]")
        return grids

    @staticmethod
    def _precisions(precision, ys: list[np.ndarray]) -> list[np.ndarray] | None:
        if precision is None:
            return None
        if len(precision) != len(ys):
            raise GPMSAError(f"precision must have one entry per experiment ({len(ys)})")
        out = []
        for j, (lam, e) in enumerate(zip(precision, ys, strict=True)):
            lam = as_float(lam, f"precision[{j}]")
            if lam.ndim == 0:
                lam = lam * np.eye(e.size)
            if lam.shape != (e.size, e.size):
                raise GPMSAError(
                    f"precision[{j}] must be a scalar or ({e.size}, {e.size}), got {lam.shape}"
                )
            check_finite(lam, f"precision[{j}]")
            if not np.allclose(lam, lam.T) or np.linalg.eigvalsh(lam).min() <= 0:
                raise GPMSAError(f"precision[{j}] must be symmetric positive definite")
            out.append(lam)
        return out

    @property
    def n(self) -> int:
        """Number of experiments."""
        return self.x.shape[0]
