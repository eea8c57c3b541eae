"""The result of a calibration: named posterior draws, and (fast path) an exact grid density."""

from __future__ import annotations

import functools
import threading
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, overload

import numpy as np

from gpmsa._fp_state import underflow_as_zero
from gpmsa.errors import GPMSAError
from gpmsa.limits import BYTES_PER_HISTOGRAM_BIN, check_memory
from gpmsa.mcmc import diagnostics
from gpmsa.model.data import (
    _label_text,
    as_float,
    as_real,
    check_count,
    check_finite,
    check_level,
    check_probabilities,
    numbers_text,
    quantile_keys,  # gpmsa.calibration.posterior.quantile_keys, as before session 74
    repr_name,
)

if TYPE_CHECKING:
    from matplotlib.figure import Figure

#: Lower tail probabilities tried by `GridMarginal.hdi`.
HDI_STEPS = 201


def trapezoid_weights(nodes: np.ndarray) -> np.ndarray:
    """Trapezoid-rule weights (k,) of sorted nodes (k,)."""
    h = np.diff(nodes)
    w = np.zeros(nodes.size)
    w[:-1] += 0.5 * h
    w[1:] += 0.5 * h
    return w


def _set_read_only_state(marginal: object, state: dict) -> None:
    """A marginal's unpickled ``state``, its arrays as read-only copies (a ``copy.copy``'s state
    holds the original's arrays, and a ``copy.deepcopy`` of a list holding the marginal and its
    nodes shares them with the list: a copy leaves those as they are and shares nothing)."""
    for name, value in state.items():
        if isinstance(value, np.ndarray):
            value = value.copy()
            value.flags.writeable = False
        object.__setattr__(marginal, name, value)


@dataclass(frozen=True, eq=False)
class GridMarginal:
    """A 1-D posterior density known at the nodes of a sorted grid (native units).

    Moments are trapezoid sums over the nodes (geometrically accurate for a smooth density that
    is resolved by the grid); the CDF, quantiles and draws use the piecewise-linear interpolant of
    the density, normalised by the same trapezoid sum. Far tails underflow to 0 (subnormal) as
    in numpy's default state, whatever the caller's ``np.seterr(under=...)``.

    Attributes:
        nodes: (k,) strictly increasing parameter values.
        density: (k,) density values (native units), trapezoid integral 1.
        weights: (k,) trapezoid weights of the nodes.
    """

    nodes: np.ndarray
    density: np.ndarray
    weights: np.ndarray

    def __setstate__(self, state: dict) -> None:
        """Unpickling (and ``copy.deepcopy``): the arrays read-only again, as made (numpy
        restores an array writable)."""
        _set_read_only_state(self, state)

    @classmethod
    @underflow_as_zero
    def from_log_density(
        cls, nodes: np.ndarray, log_density: np.ndarray, weights: np.ndarray | None = None
    ) -> GridMarginal:
        """Normalise exp(log_density) on ``nodes`` (any additive constant); ``weights``: the
        grid's trapezoid weights when already known. GPMSAError unless ``nodes`` are at least 2
        finite, strictly increasing values and ``log_density`` one value per node, none NaN or
        +inf, some finite (-inf: zero density). The marginal holds read-only copies of
        ``nodes`` and ``weights`` (often a Calibrator's or a filter's own grid, which a write into
        a posterior's nodes changed for every later posterior) and a read-only density."""
        nodes = np.array(nodes, dtype=float)
        log_density = np.asarray(log_density, dtype=float)
        if nodes.ndim != 1 or nodes.size < 2:
            raise GPMSAError(f"a grid marginal needs at least 2 finite nodes (k,), got "
                             f"{nodes.size} of shape {nodes.shape}")  # fmt: skip
        # strictly increasing between finite ends: all finite (a NaN fails the comparison)
        if not (np.min(np.diff(nodes)) > 0 and np.isfinite(nodes[0]) and np.isfinite(nodes[-1])):
            raise GPMSAError("a grid marginal's nodes must be finite and strictly increasing")
        if log_density.shape != nodes.shape:
            raise GPMSAError(f"log_density must have one value per node {nodes.shape}, got "
                             f"{log_density.shape}")  # fmt: skip
        top = np.max(log_density)  # NaN if any is NaN
        if np.isnan(top) or top == np.inf:
            raise GPMSAError("log_density must not be NaN or +inf")
        if top == -np.inf:
            raise GPMSAError("log_density is -inf at every node: the density has no mass")
        w = trapezoid_weights(nodes) if weights is None else np.array(weights, dtype=float)
        f = np.exp(log_density - top)
        density = f / float(w @ f)
        for a in (nodes, density, w):
            a.flags.writeable = False
        return cls(nodes, density, w)

    def _cell_mass(self) -> np.ndarray:
        return 0.5 * np.diff(self.nodes) * (self.density[:-1] + self.density[1:])

    @underflow_as_zero
    def mean(self) -> float:
        """Posterior mean."""
        return float((self.weights * self.density) @ self.nodes)

    @underflow_as_zero
    def sd(self) -> float:
        """Posterior standard deviation."""
        d = self.nodes - self.mean()
        return float(np.sqrt((self.weights * self.density) @ (d * d)))

    def __repr__(self) -> str:
        k = np.size(self.nodes)
        first, last = (float(self.nodes[0]) + 0.0, float(self.nodes[-1]) + 0.0) if k else (0, 0)
        ends = numbers_text(first, last, digits=4)  # (+ 0.0: a zero as "0", never "-0")
        span = f" on [{ends[0]}, {ends[1]}]" if k else ""
        return f"GridMarginal({k} nodes{span}, mean={self.mean():.4g}, sd={self.sd():.3g})"

    @underflow_as_zero
    def cdf(self, value: np.ndarray | float) -> np.ndarray:
        """P(X <= value) under the piecewise-linear density (0 below the first node, 1 from the
        last; GPMSAError for a NaN value)."""
        x = _values_without_nan(value)
        cum = np.concatenate([[0.0], np.cumsum(self._cell_mass())])
        k = np.clip(np.searchsorted(self.nodes, x, side="right") - 1, 0, self.nodes.size - 2)
        a, h = self.nodes[k], np.diff(self.nodes)[k]
        f0, f1 = self.density[k], self.density[k + 1]
        t = np.clip(x - a, 0.0, h)
        # a whole cell adds its mass as the cumsum did (the ramp's formula can round 1 ulp off
        # it): exact at every node, so exactly 1 from the last node with mass on
        out = np.where(t < h, cum[k] + f0 * t + 0.5 * (f1 - f0) * t * t / h, cum[k + 1])
        return np.clip(out / cum[-1], 0.0, 1.0)

    def ppf(self, q: np.ndarray | float) -> np.ndarray:
        """Quantile function: the inverse of ``cdf`` (exact for the piecewise-linear density);
        ``q`` in [0, 1] (GPMSAError otherwise)."""
        return self._ppf(check_probabilities(q, "q"))

    @underflow_as_zero
    def _ppf(self, q: np.ndarray) -> np.ndarray:
        """`ppf` of probabilities already checked to lie in [0, 1]."""
        width = self.nodes[1:] - self.nodes[:-1]
        mass = 0.5 * width * (self.density[:-1] + self.density[1:])  # (`_cell_mass`)
        cells = np.flatnonzero(mass > 0.0)  # cells without mass hold no quantile
        cum = np.zeros(cells.size + 1)
        np.cumsum(mass[cells], out=cum[1:])
        target = q * cum[-1]
        # the cell of each target: searchsorted(cum, target) - 1 clipped to [0, cells - 1]
        # (cum[0] = 0 < cum[1] <= ... <= cum[-1]), without the clip
        j = np.searchsorted(cum[1:-1], target, side="left")
        k = cells[j]
        a, h = self.nodes[k], width[k]
        f0, f1 = self.density[k], self.density[k + 1]
        r = target - cum[j]  # solve f0 t + (f1 - f0) t^2 / (2h) = r for t in [0, h]
        slope = (f1 - f0) / h
        denom = f0 + np.sqrt(np.maximum(f0 * f0 + 2.0 * slope * r, 0.0))
        t = 2.0 * r / np.where(denom > 0.0, denom, 1.0)
        return a + np.clip(t, 0.0, h)

    def hdi(self, level: float) -> tuple[float, float]:
        """The shortest interval holding probability ``level`` (the highest-density interval of a
        unimodal density; it reaches a grid end where the density piles up there), its lower
        tail probability resolved to (1 - level) / (HDI_STEPS - 1). ``level`` in (0, 1)
        (GPMSAError otherwise)."""
        ends = self._ppf(_float_hdi_probabilities(check_level(level)))
        lo, hi = ends[:HDI_STEPS], ends[HDI_STEPS:]
        k = int(np.argmin(hi - lo))
        return float(lo[k]), float(hi[k])

    def sample(self, rng: np.random.Generator, size: int) -> np.ndarray:
        """Independent draws from the piecewise-linear density."""
        return self._ppf(rng.random(size))


@dataclass(frozen=True, eq=False)
class LevelMarginal:
    """The posterior of a categorical parameter: a probability per level (native codes), exact.

    Its summaries are those of a discrete distribution on the level codes: ``mean`` and ``sd``
    the probability-weighted moments of the codes (as the mean and sd of an MCMC's draws of
    it); ``cdf`` P(X <= value); ``ppf`` (quantiles) the lower quantile, the smallest level
    whose CDF reaches q (a level, never a value between levels); draws and ``hdi``'s ends are
    levels too. ``nodes``, ``density`` and ``weights`` (ones) read as a `GridMarginal`'s
    (``weights @ density`` = 1). A far level's probability underflows to 0 (subnormal) as in
    numpy's default state, whatever the caller's ``np.seterr(under=...)``.

    Attributes:
        nodes: (k,) the levels, increasing.
        density: (k,) their probabilities, sum 1.
        weights: (k,) ones.
    """

    nodes: np.ndarray
    density: np.ndarray
    weights: np.ndarray

    def __setstate__(self, state: dict) -> None:
        """Unpickling (and ``copy.deepcopy``): the arrays read-only again, as made (numpy
        restores an array writable)."""
        _set_read_only_state(self, state)

    @classmethod
    @underflow_as_zero
    def from_probabilities(cls, levels, probabilities) -> LevelMarginal:
        """Normalise ``probabilities`` (k,), non-negative, some positive, of the increasing
        ``levels`` (k,); GPMSAError otherwise. The marginal holds a read-only copy of ``levels``
        (often a Calibrator's own level codes) and read-only probabilities and weights, as a
        `GridMarginal` does."""
        levels = np.array(levels, dtype=float)
        p = np.asarray(probabilities, dtype=float)
        if levels.ndim != 1 or levels.size < 1 or p.shape != levels.shape:
            raise GPMSAError(f"a level marginal needs one probability per level, got levels "
                             f"{levels.shape} and probabilities {p.shape}")  # fmt: skip
        if not (np.all(np.isfinite(levels)) and np.all(np.diff(levels) > 0)):
            raise GPMSAError("a level marginal's levels must be finite and strictly increasing")
        total = float(np.sum(p))
        if not (np.all(np.isfinite(p)) and np.all(p >= 0.0) and total > 0.0):
            raise GPMSAError("a level marginal's probabilities must be finite, non-negative "
                             "and not all 0")  # fmt: skip
        density, weights = p / total, np.ones(levels.size)
        for a in (levels, density, weights):
            a.flags.writeable = False
        return cls(levels, density, weights)

    def probabilities(self) -> dict[float, float]:
        """level -> its posterior probability."""
        return {float(v): float(p) for v, p in zip(self.nodes, self.density, strict=True)}

    @underflow_as_zero
    def mean(self) -> float:
        """Posterior mean of the level code (between levels where two carry mass)."""
        return float(np.clip(self.density @ self.nodes, self.nodes[0], self.nodes[-1]))

    @underflow_as_zero
    def sd(self) -> float:
        """Posterior standard deviation of the level code."""
        d = self.nodes - self.mean()
        return float(np.sqrt(self.density @ (d * d)))

    def __repr__(self) -> str:
        probs = ", ".join(f"{v:g}: {p:.3g}" for v, p in self.probabilities().items())
        return f"LevelMarginal({{{probs}}})"

    def cdf(self, value: np.ndarray | float) -> np.ndarray:
        """P(X <= value) (GPMSAError for a NaN value)."""
        cum = np.cumsum(self.density)
        k = np.searchsorted(self.nodes, _values_without_nan(value), side="right")
        return np.clip(np.where(k > 0, cum[np.maximum(k - 1, 0)], 0.0), 0.0, 1.0)

    def ppf(self, q: np.ndarray | float) -> np.ndarray:
        """The lower quantile: the smallest level with mass whose CDF reaches q (q = 0: the
        smallest level with mass); ``q`` in [0, 1] (GPMSAError otherwise)."""
        return self._ppf(check_probabilities(q, "q"))

    def _ppf(self, q: np.ndarray) -> np.ndarray:
        """`ppf` of probabilities already checked to lie in [0, 1]."""
        live = np.flatnonzero(self.density > 0.0)
        cum = np.cumsum(self.density[live])
        j = np.searchsorted(cum, q * cum[-1], side="left")
        return self.nodes[live][np.minimum(j, live.size - 1)]

    def hdi(self, level: float) -> tuple[float, float]:
        """The shortest interval [a, b] between levels holding probability ``level`` at least
        (of two as short, the one holding more); ``level`` in (0, 1) (GPMSAError otherwise)."""
        level = check_level(level)
        cum = np.concatenate([[0.0], np.cumsum(self.density)])
        best = (np.inf, 0.0, 0, self.nodes.size - 1)
        for i in range(self.nodes.size):
            for j in range(i, self.nodes.size):
                mass = cum[j + 1] - cum[i]
                if mass >= level * (1.0 - 1e-12):
                    width = self.nodes[j] - self.nodes[i]
                    if (width, -mass) < (best[0], -best[1]):
                        best = (width, mass, i, j)
                    break
        return float(self.nodes[best[2]]), float(self.nodes[best[3]])

    def sample(self, rng: np.random.Generator, size: int) -> np.ndarray:
        """Independent draws of the level."""
        return self._ppf(rng.random(size))


@functools.lru_cache(maxsize=16)
def _float_hdi_probabilities(level: float) -> np.ndarray:
    """The lower tail probabilities `GridMarginal.hdi` tries at a float ``level``, then the
    same plus ``level``; kept (read-only: every call shares them)."""
    p = np.linspace(0.0, 1.0 - level, HDI_STEPS)
    out = np.concatenate([p, p + level])
    out.flags.writeable = False
    return out


def _values_without_nan(value) -> np.ndarray:
    """``value`` as a float array for a marginal's ``cdf``; GPMSAError for a NaN (whose CDF
    would read as 1)."""
    x = np.asarray(value, dtype=float)
    if np.isnan(x).any():
        raise GPMSAError(f"value must not be NaN, got {value!r}")
    return x


def _named_arrays(value, what: str, kind: str, ndim: int, wrong_shape: str) -> dict:
    """``value`` as name -> finite float arrays of ``ndim`` dimensions, none empty; GPMSAError
    naming ``what`` (a dict name -> ``kind``) and the entry, ``wrong_shape`` (a template with
    ``{shape}``) saying what an entry of another shape should have been."""
    if not isinstance(value, dict):
        raise GPMSAError(f"{what} must be a dict name -> {kind}, got {type(value).__name__}")
    out = {}
    for name, draws in value.items():
        if not isinstance(name, str):
            raise GPMSAError(f"{what}: parameter names must be strings, got {name!r}")
        arr = as_float(draws, f"{what}[{name!r}]")
        arr = np.atleast_2d(arr) if ndim == 2 else arr
        if arr.ndim != ndim or arr.size == 0:
            raise GPMSAError(f"{what}[{name!r}] must be {wrong_shape.format(shape=arr.shape)}")
        check_finite(arr, f"{what}[{name!r}]")
        out[name] = arr
    return out


def _checked_samples(samples) -> dict[str, np.ndarray]:
    """``samples`` as name -> float draws (n_draws,) of a scalar parameter; GPMSAError for
    anything but a dict of string names to non-empty 1-D arrays of finite real numbers (a
    vector parameter is one name per element, as ``betaV[0]``, ``betaV[1]``)."""
    wrong = ("the draws (n_draws,) of one scalar parameter, at least one, got shape {shape} "
             "(name each element of a vector: 'b[0]', ...)")  # fmt: skip
    out = _named_arrays(samples, "samples", "draws", 1, wrong)
    counts = {name: arr.size for name, arr in out.items()}
    if len(set(counts.values())) > 1:  # draw i of every parameter is one joint draw
        raise GPMSAError(
            f"samples must hold the same number of draws of every parameter (draw i of each "
            f"is one joint draw), got {counts}"
        )
    return out


def _checked_chains(chains, samples: dict[str, np.ndarray] | None) -> dict[str, np.ndarray] | None:
    """``chains`` as name -> float draws (n_chains, n_draws) for every parameter of the
    posterior (the names of ``samples``; None: not known yet), each the samples of that name
    split into chains, or None; GPMSAError naming what is wrong."""
    if chains is None:
        return None
    names = None if samples is None else tuple(samples)
    out = _named_arrays(chains, "chains", "(n_chains, n_draws)", 2,
                        "(n_chains, n_draws), got {shape}")  # fmt: skip
    missing = sorted(set(names or ()) - set(out))
    if missing:
        raise GPMSAError(f"chains lacks {missing}: give the chains of every parameter or none")
    shapes = {arr.shape for arr in out.values()}
    if len(shapes) > 1:
        listed = ", ".join(f"{name}: {arr.shape}" for name, arr in out.items())
        raise GPMSAError(
            f"chains of every parameter must have one shape (n_chains, n_draws), got {listed}"
        )
    for name, arr in out.items():
        drawn = None if samples is None else samples.get(name)
        if drawn is not None and not np.array_equal(arr.reshape(-1), drawn):
            raise GPMSAError(
                f"chains[{name!r}] of shape {arr.shape} are not samples[{name!r}] "
                f"({drawn.size} draws) split into chains: give the chains the samples were "
                "pooled from (samples = chains.reshape(-1)), or no chains"
            )
    return out


def _checked_info(info) -> dict:
    """``info`` as a new dict (None: empty); GPMSAError unless it is a dict with string keys
    whose "names", where given, is a list of parameter names (strings)."""
    if info is None:
        return {}
    if not isinstance(info, dict):
        raise GPMSAError(f"info must be a dict (how the posterior was computed), got "
                         f"{type(info).__name__}")  # fmt: skip
    if bad := [k for k in info if not isinstance(k, str)]:
        raise GPMSAError(f"info: keys must be strings, got {bad[0]!r}")
    names = info.get("names")
    if names is not None and (
        isinstance(names, str)
        or not isinstance(names, list | tuple)
        or not all(isinstance(n, str) for n in names)
    ):
        raise GPMSAError(f"info['names'] must be a list of parameter names (strings), got "
                         f"{names!r}")  # fmt: skip
    return dict(info)


def _checked_grids(grids, names) -> dict[str, GridMarginal]:
    """``grids`` as a new dict name -> GridMarginal (None: empty); GPMSAError for anything else,
    or for a name that is not a parameter of the posterior (``names``; None: not known yet)."""
    if grids is None:
        return {}
    if not isinstance(grids, dict):
        raise GPMSAError(f"grids must be a dict name -> GridMarginal, got {type(grids).__name__}")
    for name, grid in grids.items():
        if not isinstance(name, str):
            raise GPMSAError(f"grids: parameter names must be strings, got {name!r}")
        if not isinstance(grid, GridMarginal | LevelMarginal):
            raise GPMSAError(f"grids[{name!r}] must be a GridMarginal, got "
                             f"{type(grid).__name__} (a categorical parameter's: a "
                             "LevelMarginal)")  # fmt: skip
        if names is not None and name not in names:
            raise GPMSAError(f"grids[{name!r}] is not a parameter of the posterior, which has "
                             f"{tuple(names)}")  # fmt: skip
    return dict(grids)


def held_names(info: dict) -> set[str]:
    """The names ``info["held"]`` lists (``calibrate(..., fixed=)``, ``calibration_posterior``
    of a fit with ``fixed=``, a study's settings: held at their values), its strings only
    (a file may hold other entries); none without it."""
    held = info.get("held")
    return {h for h in held if isinstance(h, str)} if isinstance(held, list | tuple) else set()


def recorded_units(info: dict) -> dict[str, str]:
    """name -> unit that ``info["units"]`` records (calibrate, Calibrator and a study write a
    dict name -> unit, so that figures label their axes "name (unit)"), read as ``SimData``
    reads units: a string, or a number (a table's column label) as its text; an entry None or
    "" is no unit, and so is a missing record. GPMSAError naming ``info['units']`` for a record
    that is not such a dict, or an entry that is not such a label (a list, bytes, NaN), which a
    label would show as its repr."""
    units = info.get("units")
    if units is None:
        return {}
    if not isinstance(units, Mapping):
        raise GPMSAError(
            f"info['units'] must be a dict parameter name -> unit (str), as calibrate records "
            f"it, got {type(units).__name__} {units!r:.60}: record {{name: unit}}, or give the "
            "unit to Posterior.plot(name, unit=...)"
        )
    out = {}
    for name, unit in units.items():
        if isinstance(name, str) and unit is not None and not (isinstance(unit, str) and not unit):
            out[name] = _label_text(unit, repr(name), "info['units']", "unit")
    return out


class Posterior:
    """Posterior of a calibration, native units.

    Args:
        samples: name -> draws (n_draws,) for scalar parameters, or None when ``draw`` gives them.
        grids: name -> GridMarginal, the exact grid representation of a parameter's marginal (the
            fast path; a LevelMarginal, a probability per level, for a categorical one);
            summaries of that name come from it, not from draws.
        draw: a callable returning the samples dict, called once on first access of ``samples``
            (the fast path draws lazily so that an update costs nothing it does not need).
        chains: name -> (n_chains, n_draws) the MCMC draws per chain (for ``to_arviz`` and traces).
        info: how the posterior was computed (method, settings, timings): a dict with string
            keys; "names", where given, lists the parameter names (the names of lazily drawn
            samples, before they are drawn).

    ``samples`` and ``draw``: exactly one of them. Every argument is checked here (GPMSAError
    naming it).
    """

    def __init__(
        self,
        samples: dict[str, np.ndarray] | None = None,
        *,
        grids: dict[str, GridMarginal] | None = None,
        draw: Callable[[], dict[str, np.ndarray]] | None = None,
        chains: dict[str, np.ndarray] | None = None,
        info: dict | None = None,
    ) -> None:
        if samples is None and draw is None:
            raise GPMSAError("a Posterior needs samples or a draw callable")
        if samples is not None and draw is not None:
            raise GPMSAError("give a Posterior samples or a draw callable, not both (draw would "
                             "never be called)")  # fmt: skip
        if draw is not None and not callable(draw):
            raise GPMSAError(f"draw must be a callable returning the samples dict, got "
                             f"{type(draw).__name__}")  # fmt: skip
        self._samples = None if samples is None else _checked_samples(samples)
        self._draw = draw
        if draw is not None:  # one thread draws; others reading ``samples`` meanwhile wait
            self._drawing = threading.RLock()  # re-entered by a draw that reads ``samples``
            self._in_draw = False
        self.info = _checked_info(info)
        known = tuple(self._samples) if self._samples is not None else self.info.get("names")
        self.grids = _checked_grids(grids, known)
        self.chains = _checked_chains(chains, self._samples)

    def __getstate__(self) -> dict:
        """For pickle (a Posterior sent to another process): lazily drawn samples are drawn
        now, so that the draw callable (often a closure) is not pickled."""
        state = self.__dict__.copy()
        if state.get("_draw") is not None:
            state["_samples"], state["_draw"] = self.samples, None
        state.pop("_drawing", None)
        state.pop("_in_draw", None)
        return state

    @property
    def samples(self) -> dict[str, np.ndarray]:
        """Named draws, native units: name -> (n_draws,). Drawn lazily: once, by the first
        thread that reads them (others reading them meanwhile wait, and get the same dict)."""
        if self._samples is None:
            with self._drawing:
                if self._samples is None:
                    if self._in_draw:  # this thread's draw callable reads them
                        raise GPMSAError(
                            "the draw callable of this Posterior reads its samples (samples, "
                            "mean, sd, ... of the posterior it draws): it must return the "
                            "samples without reading the posterior"
                        )
                    self._in_draw = True
                    try:
                        self._samples = self._drawn()
                    finally:
                        self._in_draw = False
        return self._samples

    def _drawn(self) -> dict[str, np.ndarray]:
        """The draw callable's samples, checked (and the chains, where given, against them)."""
        drawn = _checked_samples(self._draw())
        missing = [n for n in (*(self.info.get("names") or ()), *self.grids)
                   if n not in drawn]  # fmt: skip
        if missing:
            raise GPMSAError(
                f"the draw callable returned samples of {tuple(drawn)}, but the posterior "
                f"has {sorted(set(missing))} (info['names'] or grids) too: draw every "
                "parameter"
            )
        if self.chains is not None:  # chains given with the draw callable: checked against it
            _checked_chains(self.chains, drawn)
        return drawn

    @property
    def names(self) -> tuple[str, ...]:
        """Parameter names (calibration parameters first, then lamOs and others)."""
        if self._samples is None and self.info.get("names"):
            return tuple(self.info["names"])
        return tuple(self.samples)

    def _check(self, name: str) -> None:
        if not isinstance(name, str):
            raise GPMSAError(f"name must be a parameter name (str), got {name!r}; this posterior "
                             f"has {self.names}")  # fmt: skip
        if name not in self.grids and name not in self.names:
            raise GPMSAError(f"unknown parameter {name!r}; this posterior has {self.names}")

    def mean(self, name: str) -> float:
        """Posterior mean of ``name``."""
        self._check(name)
        if name in self.grids:
            return self.grids[name].mean()
        draws = self.samples[name]
        mean = float(np.mean(draws))
        if draws.size and not draws.min() <= mean <= draws.max():  # equal draws: their value
            return float(np.clip(mean, draws.min(), draws.max()))
        return mean

    def sd(self, name: str) -> float:
        """Posterior standard deviation of ``name``."""
        self._check(name)
        if name in self.grids:
            return self.grids[name].sd()
        draws = self.samples[name]
        if len(draws) < 2:
            raise GPMSAError(f"the sd of {name!r} needs at least 2 draws, the posterior has 1")
        if draws.min() == draws.max():  # a held parameter: exactly 0 (np.std can give 1e-16)
            return 0.0
        return float(np.std(draws, ddof=1))

    @overload
    def quantile(self, name: str, q: float | np.floating) -> float: ...
    @overload
    def quantile(self, name: str, q: np.ndarray | Sequence[float]) -> np.ndarray: ...
    def quantile(
        self, name: str, q: float | np.floating | np.ndarray | Sequence[float]
    ) -> float | np.ndarray:
        """Posterior quantile(s) of ``name`` at probability q in [0, 1]: a number, or an array
        of them (vectorised: an array of quantiles of the same shape). A categorical
        parameter's (``info["levels"]``) is the lower quantile, a level: the smallest whose
        CDF reaches q."""
        self._check(name)
        q_arr = check_probabilities(q, "q")
        if name in self.grids:
            out = self.grids[name]._ppf(q_arr)
        else:  # a categorical parameter's (info["levels"]): the lower quantile, a level
            discrete = self._level_codes(name) is not None
            out = np.quantile(self.samples[name], q_arr,
                              method="inverted_cdf" if discrete else "linear")  # fmt: skip
        return float(out) if np.ndim(out) == 0 else out

    def interval(self, name: str, level: float = 0.9) -> tuple[float, float]:
        """Central credible interval of ``name`` with probability ``level`` in (0, 1)."""
        level = check_level(level)
        lo, hi = self.quantile(name, [(1 - level) / 2, (1 + level) / 2])
        return float(lo), float(hi)

    def hdi(self, name: str, level: float = 0.9) -> tuple[float, float]:
        """Highest-density interval of ``name`` with probability ``level`` in (0, 1): the
        shortest interval holding it (`GridMarginal.hdi` on a grid, ``arviz.hdi`` on draws).
        Unlike the central interval it reaches a bound of the domain where the mass piles up
        there."""
        level = check_level(level)
        self._check(name)
        if name in self.grids:
            return self.grids[name].hdi(level)
        draws = self.samples[name]
        return diagnostics.hdi(draws, level)

    def prob_above(self, name: str, value: float) -> float:
        """P(name > value) under the posterior (e.g. P(GD > GDmax) for a risk posture);
        ``value``: one finite number (a list or an array of several is refused)."""
        self._check(name)
        value = as_real(value, "value")
        if not np.isfinite(value):
            raise GPMSAError(f"value must be finite, got {value}")
        if name in self.grids:
            return float(1.0 - self.grids[name].cdf(value))
        return float(np.mean(self.samples[name] > value))

    def summary(self, level: float = 0.9) -> dict[str, dict[str, float]]:
        """name -> {mean, sd, q_lo, median, q_hi, n_draws, exact_grid, held} (the interval at
        ``level``; MCMC posteriors add the bulk ESS and the rank-normalised split R-hat, NaN
        where the chains are too short or constant). q_lo and q_hi are named by their
        percentages (`quantile_keys`): "q5" and "q95" for level 0.9. "held": True for a
        parameter held with ``fixed=`` (``info["held"]`` names it and every draw is its value:
        sd 0, ESS and R-hat NaN), as ``Study.summary`` marks one."""
        level = check_level(level)
        lo_key, hi_key = quantile_keys(level)
        held = held_names(self.info)
        out = {}
        for name in self.names:
            lo, hi = self.interval(name, level)
            one_draw = name not in self.grids and np.size(self.samples[name]) < 2
            out[name] = {
                "mean": self.mean(name),
                "sd": float("nan") if one_draw else self.sd(name),
                lo_key: lo,
                "median": float(self.quantile(name, 0.5)),
                hi_key: hi,
                "n_draws": int(np.size(self.samples[name])),
                "exact_grid": name in self.grids,
            }
            if self.chains is not None:
                chains = np.atleast_2d(self.chains[name])
                out[name]["ess"] = diagnostics.ess(chains)
                out[name]["rhat"] = diagnostics.rhat(chains)
            out[name]["held"] = name in held and self._constant(name)
        return out

    def _constant(self, name: str) -> bool:
        """Whether every draw of ``name`` is one value (a grid marginal's never is)."""
        if name in self.grids:
            return False
        draws = np.asarray(self.samples[name])
        return bool(draws.size > 0 and draws.min() == draws.max())

    def to_arviz(self):
        """ArviZ InferenceData of the draws (arviz imported lazily), per chain where they are
        kept; each parameter's unit that ``info["units"]`` records (`recorded_units`) as its
        variable's "units" attribute (none for a record that is not such a dict)."""
        from gpmsa.mcmc.diagnostics import to_inference_data

        try:
            units = recorded_units(self.info)
        except GPMSAError:  # a record plot() refuses: the draws are kept all the same
            units = {}
        if self.chains is not None:
            draws = {k: np.asarray(v) for k, v in self.chains.items()}
        else:
            draws = {k: np.asarray(v)[None, :] for k, v in self.samples.items()}
        return to_inference_data(draws, units=units)

    def plot(self, name: str, bins: int = 50, unit: str | None = None) -> Figure:
        """Histogram of ``bins`` bars (with the grid density when there is one) and trace of
        ``name``: a Figure. A categorical parameter (a `LevelMarginal`, or ``info["levels"]``
        of draws) gets a bar per level, its draws' share: a probability, not a density.

        ``unit`` (a str) labels the axes (None: ``info["units"][name]`` where calibrate or
        Calibrator recorded the emulator's units, read by `recorded_units`)."""
        from matplotlib.figure import Figure

        self._check(name)
        bins = check_count(bins, "bins")
        check_memory(BYTES_PER_HISTOGRAM_BIN * bins, f"Posterior.plot: a histogram of {bins} bins")
        if unit is not None and not isinstance(unit, str):
            raise GPMSAError(f"unit must be a text label (str) or None, got {unit!r}")
        if unit is None:
            unit = recorded_units(self.info).get(name, "")
        label = f"{name} ({unit})" if unit else name
        fig = Figure(figsize=(9.0, 3.5))
        ax_h, ax_t = fig.subplots(1, 2)
        draws = np.asarray(self.samples[name])
        g = self.grids.get(name)
        codes = None if g is not None else self._level_codes(name)
        if isinstance(g, LevelMarginal):  # a categorical parameter: a probability per level
            freq = np.array([np.mean(draws == v) for v in g.nodes])
            ax_h.bar(g.nodes, freq, width=0.4, color="0.75", label="draws")
            ax_h.plot(g.nodes, g.density, "o", color="C0", label="exact (levels)")
        elif codes is not None:  # its draws (calibrate, a study): their share per level
            freq = np.array([np.mean(draws == v) for v in codes])
            ax_h.bar(codes, freq, width=0.4, color="0.75", label="draws")
        else:
            edges = diagnostics.histogram_bins(draws, bins)
            ax_h.hist(draws, bins=edges, density=True, color="0.75", label="draws")
        if isinstance(g, GridMarginal):
            ax_h.plot(g.nodes, g.density, color="C0", label="exact (grid)")
        if not isinstance(g, LevelMarginal) and codes is None:  # (a categorical one's mean
            ax_h.axvline(self.mean(name), color="C3", lw=1, label="mean")  # lies between levels)
        ax_h.set_xlabel(label)
        if isinstance(g, LevelMarginal) or codes is not None:
            ax_h.set_ylabel("probability")
        else:
            ax_h.set_ylabel(f"density (1/{unit})" if unit else "density")
        ax_h.legend(fontsize="small")
        chains = self.chains[name] if self.chains is not None else draws[None, :]
        for c, chain in enumerate(np.atleast_2d(chains)):
            ax_t.plot(chain, lw=0.5, color=f"C{c}")
        ax_t.set_xlabel("draw")
        ax_t.set_ylabel(label)
        fig.tight_layout()
        return fig

    def _level_codes(self, name: str) -> np.ndarray | None:
        """A categorical parameter's level codes (``info["levels"][name]``: finite numbers),
        increasing; None for another parameter or a record that holds no such list."""
        levels = self.info.get("levels")
        codes = levels.get(name) if isinstance(levels, dict) else None
        try:
            codes = np.unique(np.asarray(codes, dtype=float))
        except (TypeError, ValueError):
            return None
        return codes if codes.size and np.all(np.isfinite(codes)) else None

    def __repr__(self) -> str:
        """One line: the first 3 parameters' ``name=mean±sd`` (each name cut: `repr_name`),
        how many more ("+17 more"), and the method."""
        shown = 3
        try:
            parts = [self._describe(n) for n in self.names[:shown]]
        except Exception:  # a repr never raises (e.g. a failing draw callable)
            parts = ["?"]
        if len(self.names) > shown:
            parts.append(f"+{len(self.names) - shown} more")
        parts = parts or ["no parameters"]
        return f"Posterior({', '.join(parts)}, method={self.info.get('method', '?')})"

    def _describe(self, name: str) -> str:
        """``name=mean±sd`` (the mean alone where the sd is undefined: one draw)."""
        text = f"{repr_name(name)}={self.mean(name):.4g}"
        try:
            return f"{text}±{self.sd(name):.3g}"
        except GPMSAError:
            return text
