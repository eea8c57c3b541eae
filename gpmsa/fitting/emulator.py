"""The fitted GPM/SA emulator: training data, transforms, basis, posterior draws, predictions.

Its file record lives here too: ``Emulator.to_record``/``from_record`` map the emulator to and
from the (manifest, arrays) pair that the file container (``gpmsa.io.container``) writes and
reads; ``Emulator.save`` and ``load`` join the two.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import sys
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from types import MappingProxyType

import numpy as np
from scipy.linalg import cho_solve, solve_triangular

from gpmsa import _threads
from gpmsa._fp_state import underflow_as_zero
from gpmsa._progress import progress_bar
from gpmsa._threads import one_thread
from gpmsa.errors import EmulatorFileError, GPMSAError
from gpmsa.fitting.validation import (
    DISCREPANCY_ARRAY,
    EMULATOR_PARAMS,
    KRON_ARRAY,
    REQUIRED,
    SMALLEST_PRECISION,
    STD_FIELDS,
    check_manifest,
    check_record,
    kron_groups,
    split_bases,
)
from gpmsa.io.container import (
    FORMAT,
    check_expected_sha256,
    check_path,
    content_hash,
    jsonable,
    read_raw,
    refuse_to_replace,
    verify_content,
    write_raw,
)
from gpmsa.limits import check_memory
from gpmsa.mcmc.diagnostics import read_back, read_back_convergence
from gpmsa.model import categorical as categorical_mod
from gpmsa.model import kronecker
from gpmsa.model.correlation import correlation
from gpmsa.model.data import (
    SimData,
    array_text,
    as_float,
    as_matrix,
    by_column_names,
    check_count,
    check_flag,
    check_level,
    check_same_rows,
    evenly_spaced,
    quantile_keys,
    repr_names,
)
from gpmsa.model.likelihood import lower_cholesky
from gpmsa.model.mean_basis import GLS, MeanBasis
from gpmsa.model.mean_basis import KINDS as MEAN_BASIS_KINDS
from gpmsa.model.nugget import not_positive_definite
from gpmsa.model.priors import GammaPrior, Priors, as_group_priors
from gpmsa.model.transforms import Standardizer, check_extrapolation

__all__ = [
    "EMULATOR_PARAMS",
    "REQUIRED",
    "STD_FIELDS",
    "Emulator",
    "LooResult",
    "load",
]


NO_DRAWS = "(built by Emulator.from_params, or read from a file without draws)"
"""Why an emulator has no retained posterior draws, for the messages that need them."""

PREDICT_BLOCK_VALUES = 2**21
"""`Emulator.predict` and `predict_mean` take the points in blocks whose (points, m) work arrays
hold about this many values (16 MiB each): at 100,000 points and 1,000 runs the peak is tens of
MB, not GBs (`predict_block_rows`)."""


def predict_block_rows(m: int) -> int:
    """Points per block of a dense emulator's prediction with m runs: ``PREDICT_BLOCK_VALUES``
    / m, rounded down to a multiple of 64 (at least 64)."""
    return max(64, PREDICT_BLOCK_VALUES // max(m, 1) // 64 * 64)


def _blocks(n: int, rows: int):
    """Slices of ``rows`` consecutive of n points; a last block of one point joins the one
    before it: the product of a one-row block with the solve's weights goes through another BLAS
    kernel than a row of a larger block (OpenBLAS: another summation order, other last bits)."""
    start = 0
    while start < n:
        stop = n if n - (start + rows) == 1 else start + rows
        yield slice(start, stop)
        start = stop


def _spread_of_means(means: np.ndarray) -> np.ndarray:
    """``means.var(axis=0)`` (the draws' means (draws, N, l_sim)), to the last bit, by blocks of
    points: the squared deviations are never held for all points at once."""
    if means.size <= PREDICT_BLOCK_VALUES:
        return means.var(axis=0)
    center = means.mean(axis=0)
    out = np.empty(means.shape[1:])
    step = max(2, PREDICT_BLOCK_VALUES // (means.shape[0] * means.shape[2]))
    for part in _blocks(means.shape[1], step):
        dev = means[:, part] - center[part]
        np.multiply(dev, dev, out=dev)
        out[part] = np.add.reduce(dev, axis=0) / means.shape[0]
    return out


@dataclass(frozen=True, eq=False)
class LooResult:
    """Exact leave-one-out predictions of the simulation runs (native units).

    mean, var (m, l_sim): predictive mean and variance of run i given all others; z (m, l_sim):
    standardised residuals (y - mean) / sqrt(var); rmse (l_sim,); coverage95: share of |z| < 1.96.
    """

    mean: np.ndarray
    var: np.ndarray
    z: np.ndarray
    rmse: np.ndarray
    coverage95: float

    def __repr__(self) -> str:
        m, l_sim = np.shape(self.mean)[:2] if np.ndim(self.mean) == 2 else (0, 0)
        return (f"LooResult({m} runs x {l_sim} outputs, rmse={span_text(self.rmse)}, "
                f"coverage95={self.coverage95:.3g})")  # fmt: skip


def span_text(values) -> str:
    """For a result's repr: one value as ``0.0123``, several as their range ``[0.0101, 0.0302]``."""
    values = np.ravel(values)
    if values.size == 1:
        return f"{values[0]:.3g}"
    return f"[{np.min(values):.3g}, {np.max(values):.3g}]"


_ARRAYS = ("x_unit", "t_unit", "y", "K", "w", "lam_sim", "index", "log_post")
"""The Emulator's array attributes, read-only after construction (``Emulator._freeze``)."""

_MAPPINGS = ("params", "draws", "calibration")
"""Its name -> array attributes, read-only mappings of read-only arrays (None stays None)."""


def _read_only_copy(value: np.ndarray | None) -> np.ndarray | None:
    """A read-only copy of ``value`` (None: None); ``value`` itself stays writable."""
    if value is None:
        return None
    out = np.array(value, copy=True)
    out.setflags(write=False)
    return out


def _read_only_mapping(value: Mapping[str, np.ndarray] | None) -> Mapping | None:
    """A read-only mapping of read-only copies of ``value``'s arrays (None: None)."""
    if value is None:
        return None
    return MappingProxyType({k: _read_only_copy(v) for k, v in value.items()})


def _param_shapes(p: int, q: int, p_u: int) -> dict[str, tuple[int, ...]]:
    return {"betaU": (p + q, p_u), "lamUz": (p_u,), "lamWs": (p_u,), "lamWOs": (1,)}


MIN_LAMUZ = 1e-8
"""Smallest lamUz an emulator takes: at 1e-12 the predictive variance at the runs was 7% off,
at 1e-16 negative, at 1e-30 -1.5e14 (the prior variance's rounding swamps it); fits keep lamUz
above its prior's bound, 0.3."""


def _check_params(params: Mapping, shapes: dict) -> dict[str, np.ndarray]:
    """``params`` as arrays of ``shapes``; an array of another shape is taken only where it
    differs by axes of length 1 ((1, p_u) for (p_u,), as SEPIA stores them), never reordered
    (a transposed betaU is refused)."""
    if not isinstance(params, Mapping):
        raise GPMSAError(f"params must be a dict name -> array, got {type(params).__name__}")
    out = {}
    for name, shape in shapes.items():
        if name not in params:
            raise GPMSAError(f"params needs {name!r} (shape {shape}); got keys {sorted(params)}")
        val = as_float(params[name], f"params[{name!r}]")
        if [d for d in val.shape if d != 1] != [d for d in shape if d != 1]:
            raise GPMSAError(f"params[{name!r}] must have shape {shape}, got {val.shape}")
        val = val.reshape(shape)
        if not np.all(np.isfinite(val)) or np.any(val <= 0):
            raise GPMSAError(
                f"params[{name!r}] must be finite and > 0, got {array_text(val.ravel())}"
            )
        if name.startswith("lam") and not np.all(val > SMALLEST_PRECISION):
            raise GPMSAError(  # (1 / lam, a variance, would overflow at the first prediction)
                f"params[{name!r}] = {array_text(val.ravel())}: a precision whose variance "
                f"1 / {name} overflows float64; GPM/SA's precisions lie far above this"
            )
        if name == "lamUz" and np.any(val < MIN_LAMUZ):
            raise GPMSAError(
                f"params['lamUz'] = {array_text(val.ravel())}: below {MIN_LAMUZ:g} the GP's prior "
                "variance 1 / lamUz (in units of the outputs' variance) is too large for float64 "
                "to resolve the predictive variance near the runs (GPM/SA bounds lamUz at 0.3)"
            )
        out[name] = val
    return out


class Emulator:
    """A GPM/SA emulator (unit-scale inputs, standardised outputs inside; native units outside).

    Attributes: standardizer, x_unit (m, p), t_unit (m, q), y (m, l_sim) native, K (l_sim, p_u),
    w (m, p_u), lam_sim (p_u,), index (l_sim,), (l_sim, d) or None, params (point estimate: betaU
    (p+q, p_u), lamUz, lamWs (p_u,), lamWOs (1,)), draws (name -> (n_draws, *shape), retained
    posterior draws; empty for ``from_params``), log_post (n_draws,), priors (data-corrected),
    x_names, t_names, y_names, x_units, t_units, y_units, domain (name -> (lo, hi) native),
    metadata (user dict, saved), settings (how it was fitted), diagnostics (acceptance, ESS,
    R-hat), calibration (theta and lamOs draws of a joint sim+obs fit, else None), convergence
    (R-hat, one chain's split R-hat, and bulk ESS of every sampled parameter and the elements
    flagged, see ``gpmsa.mcmc.diagnostics.convergence``; None for ``from_params``, for older
    files and for one-chain files from before one chain was judged), levels (per column of
    [x, t]: a categorical input's training levels, else None), mean_basis (the weights' GP mean
    basis, None: zero mean); docs/categorical-and-constraints.md; index_names, index_units
    (``SimData(index_names=, index_units=)``: labels of the output index's columns, or None);
    discrepancy_bases (a joint fit given a list of per-experiment discrepancy bases: the
    normalised (l_j, p_v) basis of each experiment, as the fit used them, ``gpmsa.model.basis.
    discrepancy_bases``; else None); separable (a separable design's factor structure, a
    ``gpmsa.model.kronecker.Separable``, from ``SimData(separable=)``; else None). The arrays
    are read-only copies, params, draws and calibration read-only mappings, and no attribute
    but ``metadata`` can be replaced (``model_sha256`` holds).
    """

    def __init__(
        self,
        *,
        standardizer: Standardizer,
        x_unit: np.ndarray,
        t_unit: np.ndarray,
        y: np.ndarray,
        K: np.ndarray,
        w: np.ndarray,
        index: np.ndarray | None,
        params: dict[str, np.ndarray],
        priors: Priors,
        names: dict[str, tuple[str, ...]],
        units: dict[str, tuple[str, ...]],
        draws: dict[str, np.ndarray] | None = None,
        log_post: np.ndarray | None = None,
        metadata: dict | None = None,
        settings: dict | None = None,
        diagnostics: dict | None = None,
        calibration: dict[str, np.ndarray] | None = None,
        convergence: dict | None = None,
        levels: categorical_mod.Levels | None = None,
        mean_basis: MeanBasis | None = None,
        discrepancy_bases: tuple[np.ndarray, ...] | None = None,
        separable: tuple[tuple[int, ...], ...] | None = None,
        index_names: tuple[str, ...] | None = None,
        index_units: tuple[str, ...] | None = None,
    ):
        self.standardizer = standardizer
        self.x_unit, self.t_unit, self.y, self.K, self.w = x_unit, t_unit, y, K, w
        self.lam_sim = np.sum(K**2, axis=0)
        self.index = index
        self.params = _check_params(params, _param_shapes(self.p, self.q, self.p_u))
        self.priors = priors
        self.x_names, self.t_names, self.y_names = names["x"], names["t"], names["y"]
        self.x_units, self.t_units, self.y_units = units["x"], units["t"], units["y"]
        self.index_names, self.index_units = index_names, index_units
        self.draws = draws if draws is not None else {}
        self.log_post = log_post if log_post is not None else np.zeros(0)
        self.metadata = metadata  # a dict (copied) or None (``__setattr__`` checks it)
        self.settings = dict(settings or {})
        self.diagnostics = dict(diagnostics or {})
        self.calibration = calibration
        self.convergence = convergence
        self.levels = (None,) * (self.p + self.q) if levels is None else tuple(levels)
        self.mean_basis = mean_basis
        self.discrepancy_bases = None if discrepancy_bases is None else tuple(discrepancy_bases)
        self.separable = None  # a separable design's factor structure (``SimData(separable=)``)
        if separable is not None:
            if self.mean_basis is not None:
                kronecker.refuse("a mean_basis")
            names = self.x_names + self.t_names
            self.separable = kronecker.structure(self.zt, separable, names)
        self._factors: dict[int, list] = {}
        self._freeze()

    def _freeze(self) -> None:
        """The arrays that define the predictions and ``model_sha256`` as read-only copies (an
        in-place change raises numpy's ValueError "assignment destination is read-only"; the
        caller's arrays stay writable), ``params``, ``draws`` and ``calibration`` as read-only
        mappings of them, the standardizer as one with read-only arrays."""
        for name in _ARRAYS:
            object.__setattr__(self, name, _read_only_copy(getattr(self, name)))
        for name in _MAPPINGS:
            object.__setattr__(self, name, _read_only_mapping(getattr(self, name)))
        if self.discrepancy_bases is not None:
            bases = tuple(_read_only_copy(D) for D in self.discrepancy_bases)
            object.__setattr__(self, "discrepancy_bases", bases)
        std = self.standardizer
        object.__setattr__(self, "standardizer", dataclasses.replace(
            std, **{k: _read_only_copy(getattr(std, k)) for k in STD_FIELDS},
            **({"y_sd": _read_only_copy(std.y_sd)} if std.columnwise else {}),
        ))  # fmt: skip
        object.__setattr__(self, "_sealed", True)

    def __setattr__(self, name: str, value) -> None:
        """Only ``metadata`` (the user's dict, not part of the model) may be replaced once
        constructed: the predictions, ``model_sha256`` and the cached factors depend on the rest.
        ``metadata`` as the constructor takes it: a dict (copied), or None for none."""
        if name == "metadata":
            if value is not None and not isinstance(value, dict):
                raise GPMSAError(f"metadata must be None or a dict, got {type(value).__name__}")
            value = dict(value or {})
        elif self.__dict__.get("_sealed", False):
            raise AttributeError(
                f"Emulator.{name} cannot be replaced: an emulator is read-only (its predictions, "
                f"cached factors and model_sha256 depend on it); build another with "
                f"gpmsa.Emulator.from_params or gpmsa.fit, or use emu.with_calibration_priors"
            )
        object.__setattr__(self, name, value)

    def __delattr__(self, name: str) -> None:
        """Attributes cannot be deleted (as ``__setattr__``)."""
        raise AttributeError(f"Emulator.{name} cannot be deleted: an emulator is read-only")

    def __getstate__(self) -> dict:
        """For pickle and ``copy`` (a worker process gets the emulator): the read-only mappings
        as dicts, which pickle."""
        state = dict(self.__dict__)
        for name in _MAPPINGS:
            if state[name] is not None:
                state[name] = dict(state[name])
        return state

    def __setstate__(self, state: dict) -> None:
        """Unpickled or copied: read-only again, as constructed (an emulator pickled before
        ``discrepancy_bases`` existed has none)."""
        self.__dict__.update(state)
        self.__dict__.setdefault("discrepancy_bases", None)
        self.__dict__.setdefault("separable", None)
        self.__dict__.setdefault("index_names", None)
        self.__dict__.setdefault("index_units", None)
        self._freeze()

    # --- construction -------------------------------------------------------------------------
    @classmethod
    def from_params(
        cls,
        sim_data: SimData,
        params: dict,
        priors: Priors | None = None,
        metadata: dict | None = None,
        *,
        n_pc: int | float | None = None,
        mean_basis=None,
        basis=None,
    ) -> Emulator:
        """An emulator at given unit-scale parameter values (no MCMC).

        ``params``: betaU (p+q, p_u), lamUz (p_u,), lamWs (p_u,), lamWOs (1,); arrays of the
        same sizes in other shapes (e.g. (1, p_u) as SEPIA stores them) are accepted.
        ``mean_basis``, ``basis``: as ``gpmsa.fit``'s.
        """
        from gpmsa.model.problem import prepare

        metadata = check_metadata(metadata)
        if isinstance(params, Mapping) and (unknown := sorted(set(params) - set(EMULATOR_PARAMS))):
            raise GPMSAError(
                f"params has unknown keys {unknown}: an emulator's parameters are "
                f"{list(EMULATOR_PARAMS)}"
            )
        prep = prepare(sim_data, priors=priors, n_pc=n_pc, mean_basis=mean_basis, basis=basis)
        settings = {"source": "from_params", "basis": "pca" if basis is None else "given"}
        return cls._from_prepared(sim_data, prep, params, metadata=metadata, settings=settings)

    @classmethod
    def _from_prepared(cls, sim: SimData, prep, params, **kw) -> Emulator:
        prob = prep.problem
        return cls(
            standardizer=prep.standardizer, x_unit=prob.x_sim, t_unit=prob.t_sim, y=sim.y,
            K=prep.K, w=prob.w, index=sim.index, params=params, priors=prob.priors,
            names={"x": sim.x_names, "t": sim.t_names, "y": sim.y_names},
            units={"x": sim.x_units, "t": sim.t_units, "y": sim.y_units},
            levels=sim.levels, mean_basis=prob.mean_basis,
            separable=None if prob.separable is None else prob.separable.groups,
            index_names=sim.index_names, index_units=sim.index_units, **kw,
        )  # fmt: skip

    # --- shapes and domain --------------------------------------------------------------------
    @property
    def m(self) -> int:
        """Number of simulation runs."""
        return self.x_unit.shape[0]

    @property
    def p(self) -> int:
        """Number of known inputs."""
        return self.x_unit.shape[1]

    @property
    def q(self) -> int:
        """Number of calibration parameters."""
        return self.t_unit.shape[1]

    @property
    def p_u(self) -> int:
        """Number of basis vectors."""
        return self.K.shape[1]

    @property
    def l_sim(self) -> int:
        """Length of one output."""
        return self.K.shape[0]

    @property
    def zt(self) -> np.ndarray:
        """Unit-scale design (m, p + q)."""
        return np.hstack([self.x_unit, self.t_unit])

    @property
    def domain(self) -> dict[str, tuple[float, float]]:
        """The unit domain of every input, native units: name -> (lo, hi); the design's range,
        or the range the user gave (``given_ranges``)."""
        s = self.standardizer
        out = {
            n: (float(a), float(b)) for n, a, b in zip(self.x_names, s.x_min, s.x_max, strict=True)
        }
        out.update(
            {
                n: (float(a), float(b))
                for n, a, b in zip(self.t_names, s.t_min, s.t_max, strict=True)
            }
        )
        return out

    @property
    def given_ranges(self) -> tuple[str, ...]:
        """The inputs whose unit domain is the range the user gave (``SimData(x_range=,
        t_range=)``), not the design's min/max; ``domain`` holds it."""
        return self.standardizer.ranged(self.x_names + self.t_names)

    @property
    def categorical(self) -> dict[str, tuple[int, ...]]:
        """The categorical inputs: name -> training levels (native integer codes)."""
        names = self.x_names + self.t_names
        return {n: lv for n, lv in zip(names, self.levels, strict=True) if lv is not None}

    @property
    def categorical_mask(self) -> np.ndarray | None:
        """Boolean mask (p + q,) of the categorical inputs, None when there are none."""
        return categorical_mod.mask(self.levels)

    @property
    def n_draws(self) -> int:
        """Number of retained posterior draws."""
        return self.log_post.shape[0]

    # --- prediction ---------------------------------------------------------------------------
    def _factor(self, params: dict[str, np.ndarray]) -> list[tuple]:
        """Per component: (Cholesky factor of Sigma_W_j, Sigma_W_j^-1 w_j, None), or with a
        mean basis (L, Sigma_W_j^-1 (w_j - H c_j), the ``GLS`` fit c_j)."""
        what = "this operation (calibration, cross-validation, full prediction, sensitivity)"
        kronecker.check_dense(self, what)
        out = []
        zt = self.zt
        cat = self.categorical_mask
        H = None if self.mean_basis is None else self.mean_basis.matrix(zt)
        check_memory(
            8.0 * self.m * self.m * (2 * self.p_u + self.p + self.q + 2),
            f"the emulator's factorisation ({self.m} runs x {self.p_u} components)",
        )
        for j in range(self.p_u):
            S = correlation(zt, None, params["betaU"][:, j], cat) / params["lamUz"][j]
            nug = 1.0 / (self.lam_sim[j] * params["lamWOs"][0]) + 1.0 / params["lamWs"][j]
            S[np.diag_indices(self.m)] += nug
            L = lower_cholesky(S) if np.all(np.isfinite(S)) else None
            if L is None:
                raise GPMSAError(
                    not_positive_definite(
                        j, params, self.lam_sim, self.m, "at these emulator parameters"
                    )
                )
            L = np.tril(L)
            gls = None if H is None else GLS.of(L, self.w[:, j], H)
            alpha = cho_solve((L, True), self.w[:, j]) if gls is None else gls.alpha
            if not np.all(np.isfinite(alpha)):
                raise GPMSAError("Sigma_W is numerically singular at these parameters")
            out.append((L, alpha, gls))
        return out

    def _cached(self, key: int, build):
        """``self._factors[key]``, built by ``build()`` on first use: by one thread, while
        others that need it wait (``_threads.LAZY``: an emulator shared read-only by threads
        factors once); the cache holds only complete factors."""
        out = self._factors.get(key)
        if out is None:
            with _threads.LAZY:
                out = self._factors.get(key)
                if out is None:
                    out = self._factors[key] = build()
        return out

    def _point_factor(self):
        return self._cached(-1, lambda: self._factor(self.params))

    def _predict_factors(self, params, point: bool = False) -> list:
        """The factors ``_predict_std`` takes: the dense ``_factor`` (``_point_factor`` at the
        point estimate), or a separable emulator's ``kronecker.KronFactor`` per component."""
        if self.separable is None:
            return self._point_factor() if point else self._factor(params)
        if not point:
            return kronecker.emulator_factors(self, params)
        return self._cached(-2, lambda: kronecker.emulator_factors(self, self.params))

    def _inputs(self, x, t, *, extrapolate: bool = False) -> np.ndarray:
        """Unit-scale z (N, p + q) of native x and t, under the library's extrapolation rule
        (``check_extrapolation``): outside the domain an ExtrapolationWarning, beyond
        ``EXTRAPOLATION_MARGIN`` of a column's width a GPMSAError naming x or t, the column, its
        values and the domain, unless ``extrapolate`` (then the warning). The warning names the
        user's line: the first frame outside gpmsa, however deep the library's own calls run
        (``predict`` called by ``plots.emulator_fit`` too)."""
        check_same_rows({"x": x, "t": t}, {"x": self.x_names, "t": self.t_names})
        if x is None and self.p == 0:  # no known inputs: one row of none, broadcast against t
            x = np.empty((1, 0))
        x = as_float(by_column_names(x, self.x_names, "x"), "x")  # ragged: named here
        t = as_float(by_column_names(t, self.t_names, "t"), "t")
        x = x.reshape(1) if self.p == 1 and x.ndim == 0 else x  # a number: one point
        t = t.reshape(1) if self.q == 1 and t.ndim == 0 else t
        if self.p == 0:
            x = as_matrix(x, "x", ncols=0, no_columns=True)
        elif np.ndim(x) != 1 or self.p != 1:
            x = as_matrix(x, "x", ncols=self.p)
        else:
            x = as_matrix(x, "x")
        t = as_matrix(t, "t", ncols=self.q) if np.ndim(t) != 1 or self.q != 1 else as_matrix(t, "t")
        if x.shape[0] != t.shape[0]:
            if x.shape[0] == 1:
                x = np.repeat(x, t.shape[0], axis=0)
            elif t.shape[0] == 1:
                t = np.repeat(t, x.shape[0], axis=0)
            else:
                raise GPMSAError(
                    f"x and t need the same number of rows, got {x.shape} and {t.shape}"
                )
        names = self.x_names + self.t_names
        native = np.hstack([x, t])
        categorical_mod.check_levels(native, self.levels, names, "predict()")
        s = self.standardizer
        z = np.hstack([s.x_to_unit(x), s.t_to_unit(t)])
        if z.size and (z.min() < 0.0 or z.max() > 1.0):  # outside the domain: the rule
            check_extrapolation(
                native, z, names, np.concatenate([s.x_min, s.t_min]),
                np.concatenate([s.x_max, s.t_max]), ("x",) * self.p + ("t",) * self.q,
                extrapolate,
            )  # fmt: skip
        return z

    def _predict_std(self, z: np.ndarray, params, factors, resid: bool, *, var: bool = True):
        """Standardised predictive mean and variance (N, l_sim) at unit-scale z; ``var=False``:
        the variance None, its triangular solves skipped (the mean's operations unchanged).
        The points go through in blocks of `predict_block_rows`, so that the (points, m)
        correlations and solves stay bounded at many points. Every operation is row by row (a
        point's correlations, its dot product with the weights, its column of the solves), so a
        point's values are those of one call at all points up to the BLAS's summation order: a
        BLAS may order a row's dot product by the row's place in the call (OpenBLAS: in groups
        of rows, which blocks of a multiple of 64 rows keep; with several threads, at the
        boundaries of its threads' shares), a last-bit difference at a few points."""
        if self.separable is not None:  # through the factors: no m x m matrix
            return kronecker.predict_std(self, z, params, factors, resid, var=var)
        rows = predict_block_rows(self.m)
        if z.shape[0] <= rows:
            return self._predict_block(z, params, factors, resid, var=var)
        mean = np.empty((z.shape[0], self.l_sim))
        out = np.empty((z.shape[0], self.l_sim)) if var else None
        for part in _blocks(z.shape[0], rows):
            m, v = self._predict_block(z[part], params, factors, resid, var=var)
            mean[part] = m
            if var:
                out[part] = v
        return mean, out

    def _predict_block(self, z: np.ndarray, params, factors, resid: bool, *, var: bool = True):
        """`_predict_std` of a dense emulator at the points z in one piece."""
        mean = np.zeros((z.shape[0], self.l_sim))
        out = np.zeros((z.shape[0], self.l_sim)) if var else None
        cat = self.categorical_mask
        h = None if self.mean_basis is None else self.mean_basis.matrix(z)
        for j, (L, a, gls) in enumerate(factors):
            r = correlation(z, self.zt, params["betaU"][:, j], cat) / params["lamUz"][j]
            mw = r @ a
            if gls is not None:  # the GLS mean
                mw = mw + h @ gls.coef
            mean += np.outer(mw, self.K[:, j])
            if var:
                v = solve_triangular(L, r.T, lower=True)
                vw = 1.0 / params["lamUz"][j] - np.sum(v**2, axis=0)
                if gls is not None:  # the variance of its coefficients
                    vw = vw + gls.variance(h, v)
                if resid:
                    vw = vw + 1.0 / params["lamWs"][j]
                out += np.outer(vw, self.K[:, j] ** 2)
        if var and resid:
            out += 1.0 / params["lamWOs"][0]
        return mean, out

    def _check_predict_memory(self, x, t, n_draws: int = 0) -> None:
        """ResourceLimitError where a prediction at the points of x and t would need more than
        the limit: a block of points' (points, m) work arrays (a separable emulator: each
        point's correlations to the factors' points and the contraction's (points, m / m_1)),
        the inputs and outputs, and with ``n_draws`` draws their means (n_draws, points,
        l_sim)."""
        try:  # the size before converting; a ragged input is named by _inputs
            n = max(np.shape(x)[0] if np.ndim(x) else 1, np.shape(t)[0] if np.ndim(t) else 1)
        except ValueError:
            n = 1
        if self.separable is None:
            work = 4.0 * min(n, predict_block_rows(self.m)) * self.m
        else:  # kronecker.predict_std: no (points, m) array
            sizes = self.separable.sizes
            work = n * (3.0 * sum(sizes) + 2.0 * self.m / sizes[0])
        draws = f", {n_draws} draws, their means kept: n_draws= takes fewer" if n_draws else ""
        check_memory(
            8.0 * (work + n * (6.0 * self.l_sim + 4.0 * (self.p + self.q)))
            + 8.0 * n_draws * n * self.l_sim,
            f"predict() at {n} points ({self.m} runs, {self.l_sim} outputs{draws})",
        )

    def _predict_point(self, x, t, resid: bool, *, extrapolate: bool = False, var: bool = True):
        """``predict(x, t, resid=resid, extrapolate=extrapolate)`` at the point estimate (native
        mean and variance); ``var=False``: the variance None (``predict_mean``)."""
        self._check_predict_memory(x, t)
        z = self._inputs(x, t, extrapolate=extrapolate)
        m, v = self._predict_std(z, self.params, self._predict_factors(None, True), resid, var=var)
        s = self.standardizer
        return s.y_from_std(m), None if v is None else s.var_from_std(v)

    def _predict_draws(
        self, x, t, n_draws: int | None, resid: bool, *, extrapolate: bool = False,
        var: bool = True, progress: bool = False, desc: str = "predict",
    ):  # fmt: skip
        """``predict(x, t, draws=True, n_draws=n_draws, resid=resid, extrapolate=extrapolate,
        progress=progress)``; ``var=False``: the variance None (``predict_mean``); ``desc``:
        the bar's description."""
        if self.draws:
            self._check_predict_memory(x, t, len(evenly_spaced(self.n_draws, n_draws)))
        z = self._inputs(x, t, extrapolate=extrapolate)
        s = self.standardizer
        if not self.draws:
            raise GPMSAError(
                f"this emulator has no posterior draws {NO_DRAWS}; pass draws=False to use its "
                "point estimate"
            )
        idx = evenly_spaced(self.n_draws, n_draws)
        # each draw's mean kept in one array (the law of total variance needs them all); their
        # variances kept too where small or one value a draw (numpy's mean over the draws sums
        # such a column pairwise), else summed as they come (numpy's order over an outer axis)
        means = np.empty((len(idx), z.shape[0], self.l_sim))
        keep = means.size <= PREDICT_BLOCK_VALUES or z.shape[0] * self.l_sim == 1
        vars_ = np.empty_like(means) if var and keep else None
        var_sum = None
        # many small solves: one thread
        with one_thread(), progress_bar(progress, len(idx), desc) as bar:
            for k, i in enumerate(idx):
                prm = {name: self.draws[name][i] for name in EMULATOR_PARAMS}
                means[k], v = self._predict_std(z, prm, self._predict_factors(prm), resid, var=var)
                if vars_ is not None:
                    vars_[k] = v
                elif var and var_sum is None:
                    var_sum = v
                elif var:
                    var_sum += v
                bar.update(1)
        mean = means.mean(axis=0)
        if not var:
            return s.y_from_std(mean), None
        var_mean = vars_.mean(axis=0) if vars_ is not None else var_sum / len(idx)
        var_ = var_mean + _spread_of_means(means)
        return s.y_from_std(mean), s.var_from_std(var_)

    @underflow_as_zero
    def predict(
        self, x, t, *, draws: bool = False, n_draws: int | None = None, resid: bool = True,
        extrapolate: bool = False, progress: bool = False,
    ) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
        """Predictive mean and variance (N, l_sim) of the simulator output in native units.

        x (N, p) known inputs and t (N, q) parameters, native units (a single row broadcasts;
        pandas tables of N > 1 rows must carry the same row labels: rows pair by position). An
        emulator without known inputs (p = 0) takes x None (or (N, 0)): ``predict(None, t)``.
        ``draws=False``: at the point estimate ``params``; ``draws=True``: averaged over the
        retained posterior draws (or ``n_draws`` of them, evenly spaced from the first to the
        last: ``evenly_spaced``), combining the variances by the law of total variance.
        ``resid`` adds the nugget 1/lamWs and the residual variance 1/lamWOs (the spread of a new
        simulation run about the smooth emulator). The mean alone: `predict_mean`.
        Inputs outside the emulator's ``domain``: an ExtrapolationWarning; beyond it by more
        than ``EXTRAPOLATION_MARGIN`` (10 %) of a column's width a GPMSAError naming x or t,
        the column, its values and the domain, unless ``extrapolate=True`` (then the warning),
        as ``gpmsa.calibrate`` takes x_obs. ``progress=True`` shows a tqdm bar over the draws
        on stderr ("predict"; ``draws=True`` only: the point estimate has no loop).
        """
        draws, resid = check_flag(draws, "draws"), check_flag(resid, "resid")
        extrapolate = check_flag(extrapolate, "extrapolate")
        progress = check_flag(progress, "progress")
        if n_draws is not None:  # also where draws=False leaves it unused
            check_count(n_draws, "n_draws")
        if not draws:
            return self._predict_point(x, t, resid, extrapolate=extrapolate)
        return self._predict_draws(x, t, n_draws, resid, extrapolate=extrapolate,
                                   progress=progress)  # fmt: skip

    @underflow_as_zero
    def predict_mean(
        self, x, t, *, draws: bool = False, n_draws: int | None = None, extrapolate: bool = False,
        progress: bool = False,
    ) -> np.ndarray:  # fmt: skip
        """Predictive mean (N, l_sim) in native units: ``predict(x, t, draws=draws,
        n_draws=n_draws, extrapolate=extrapolate)[0]`` to the last bit, without computing the
        variance (its triangular solves, about half of ``predict``'s time at many points). The
        mean does not depend on ``resid``; the arguments and their checks are ``predict``'s
        (``progress``: its bar, described "predict_mean").
        """
        draws = check_flag(draws, "draws")
        extrapolate = check_flag(extrapolate, "extrapolate")
        progress = check_flag(progress, "progress")
        if n_draws is not None:  # also where draws=False leaves it unused
            check_count(n_draws, "n_draws")
        if not draws:
            return self._predict_point(x, t, False, extrapolate=extrapolate, var=False)[0]
        return self._predict_draws(x, t, n_draws, False, extrapolate=extrapolate, var=False,
                                   progress=progress, desc="predict_mean")[0]  # fmt: skip

    # --- checks -------------------------------------------------------------------------------
    @underflow_as_zero
    def loo(self) -> LooResult:
        """Exact leave-one-out cross-validation at the point estimate (Cholesky of Sigma_W).

        For component j with precision P = S^-1 (zero mean), or with a mean basis H the
        projected precision P = S^-1 - S^-1 H (H^T S^-1 H)^-1 H^T S^-1 (the GLS coefficients
        refitted without run i): mean_i = w_i - [P w]_i / P_ii, var_i = 1 / P_ii (the nugget
        included); outputs through K. For l_sim > 1 the held-out run's outputs y_i = K w_i + e_i:
        1/P_ii is the variance of its projected weights, which holds the projection noise
        1/(lam_sim lamWOs); that is taken out and the residual 1/lamWOs added once (the dense
        conditional of y_i given the other runs' outputs, to rounding).
        """
        mean_w = np.zeros((self.m, self.p_u))
        var_w = np.zeros((self.m, self.p_u))
        if self.separable is None:
            fac = [(a, _precision_diagonal(L, gls)) for L, a, gls in self._point_factor()]
        else:  # diag(Sigma_W^-1) through the factors
            fac = [(f.alpha, f.precision_diagonal()) for f in self._predict_factors(None, True)]
        for j, (a, d) in enumerate(fac):
            mean_w[:, j] = self.w[:, j] - a / d
            var_w[:, j] = 1.0 / d
        mean = mean_w @ self.K.T
        var = output_variance(var_w, self.K, self.lam_sim, self.params["lamWOs"][0])
        s = self.standardizer
        mean, var = s.y_from_std(mean), s.var_from_std(var)
        z = (self.y - mean) / np.sqrt(var)
        rmse = np.sqrt(np.mean((self.y - mean) ** 2, axis=0))
        return LooResult(mean, var, z, rmse, float(np.mean(np.abs(z) < 1.959964)))

    def to_arviz(self):
        """ArviZ InferenceData of the retained draws (chains as fitted)."""
        from gpmsa.mcmc.diagnostics import to_inference_data

        n_ch = int(self.settings.get("n_chains", 1)) or 1
        if self.n_draws == 0:
            raise GPMSAError(f"this emulator has no posterior draws {NO_DRAWS}")
        per, left = divmod(self.n_draws, n_ch)
        if left:
            raise GPMSAError(
                f"settings['n_chains'] = {n_ch} does not divide the {self.n_draws} draws; "
                "each chain keeps as many draws"
            )
        draws = {k: v[: per * n_ch].reshape(n_ch, per, *v.shape[1:]) for k, v in self.draws.items()}
        if self.calibration:
            for k, v in self.calibration.items():
                draws[k] = v[: per * n_ch].reshape(n_ch, per, *v.shape[1:])
        return to_inference_data(draws, self.log_post[: per * n_ch].reshape(n_ch, per))

    def with_calibration_priors(
        self, *, theta_mean=None, theta_sd=None, lamOs=None, lamVz=None, rhoV_a=None, rhoV_b=None
    ) -> Emulator:
        """A copy of this emulator whose calibrations use other priors: theta's truncated normal
        (``theta_mean``, ``theta_sd``, unit scale: numbers, shared by every calibration
        parameter, or sequences of one per parameter in ``t_names``' order, as ``Priors``
        takes them), the observation precision ``lamOs`` and the
        discrepancy precision ``lamVz`` (``gpmsa.GammaPrior``s, before any data correction;
        ``lamVz`` also a sequence of them, one per discrepancy precision group, as
        ``Priors.lamVz``) and the discrepancy's correlation prior Beta(``rhoV_a``, ``rhoV_b``) on
        rho = exp(-betaV/4) (numbers, or sequences of one per group, as ``Priors.rhoV_a``; give
        both where the emulator has none); None keeps the emulator's. ``gpmsa.calibrate``,
        ``gpmsa.Calibrator`` and the predictions then use them; the emulator's own parameters,
        draws and their priors are unchanged. The priors are part of ``model_sha256`` (a
        posterior of the copy refuses the original) and of the saved file. A joint fit's
        calibration draws, made under the old priors, are not copied (calibrate the copy;
        ``full_prediction`` then takes ``posterior=``). E.g. a known sensor noise sd s (native
        units) on a scalar output: ``lamOs=GammaPrior(a, a * (s / y_sd) ** 2)`` centres lamOs on
        (y_sd / s)^2 with relative sd 1/sqrt(a)."""
        given = {"theta_mean": theta_mean, "theta_sd": theta_sd, "lamOs": lamOs, "lamVz": lamVz,
                 "rhoV_a": rhoV_a, "rhoV_b": rhoV_b}  # fmt: skip
        given = {k: v for k, v in given.items() if v is not None}
        if "lamOs" in given and not isinstance(given["lamOs"], GammaPrior):
            raise GPMSAError(f"lamOs must be a gpmsa.GammaPrior, got {given['lamOs']!r:.80}")
        if "lamVz" in given:
            given["lamVz"] = as_group_priors(given["lamVz"], "lamVz")
        priors = dataclasses.replace(self.priors, **given)  # checked by Priors' own rules
        priors.theta_moments(self.q)  # per-element theta priors: one per calibration parameter
        state = self.__getstate__()
        state["priors"] = priors
        if given and state["calibration"] is not None:  # a joint fit's draws, made under the old
            state["calibration"] = None
            state["discrepancy_bases"] = None  # kept for those draws alone
        state.pop("model_sha256", None)  # the cached digest of the original
        out = object.__new__(Emulator)
        out.__setstate__(state)
        return out

    def theta_summary(self, level: float = 0.95) -> dict[str, dict[str, float]]:
        """Posterior of the calibration parameters (native units) from a joint sim+obs fit (a
        categorical one's quantiles are levels, as ``Posterior.quantile`` gives them).

        name -> {mean, sd, "q2.5", "q50", "q97.5"} (the draws' 2.5 %, 50 % and 97.5 %
        quantiles, whatever ``level``: the keys it has always had) and, as
        ``Posterior.summary(level)`` names them, "median" and the ends of the central interval
        at ``level`` named by their percentages ("q5" and "q95" for 0.9; `quantile_keys`) and
        "n_draws"; each equals ``calibration_posterior(emu).summary(level)``'s entry, which
        adds the ESS and R-hat and "held". ``level``: as ``Posterior.summary``'s (a number in
        (0, 1)), but 0.95 by default, so that its interval's keys are "q2.5" and "q97.5"."""
        if not self.calibration:
            raise GPMSAError("no calibration draws: fit was run without obs=")
        level = check_level(level)
        lo_key, hi_key = quantile_keys(level)
        th = self.calibration["theta_native"]
        out = {}
        for k, name in enumerate(self.t_names):
            col = th[:, k]
            levels = self.levels[self.p + k] is not None  # a categorical one's: levels
            method = "inverted_cdf" if levels else "linear"
            q = np.quantile(col, [0.025, 0.5, 0.975], method=method)
            out[name] = {"mean": float(col.mean()), "sd": float(col.std(ddof=1)),
                         "q2.5": float(q[0]), "q50": float(q[1]), "q97.5": float(q[2])}  # fmt: skip
            lo, hi = np.quantile(col, [(1 - level) / 2, (1 + level) / 2], method=method)
            added = {lo_key: float(lo), "median": float(q[1]), hi_key: float(hi),
                     "n_draws": int(col.size)}  # fmt: skip
            for key, value in added.items():  # the old keys as they were (level 0.95's ends)
                out[name].setdefault(key, value)
        return out

    # --- the file record ----------------------------------------------------------------------
    def to_record(self) -> tuple[dict, dict[str, np.ndarray]]:
        """The emulator as the file's content: (manifest fields, arrays); docs/emulator-file.md.

        The manifest holds names, units, domain, model, priors, settings, metadata and
        diagnostics, JSON-able (non-finite floats become null); the arrays are float64.
        Raises GPMSAError when ``metadata`` is not JSON-able.
        """
        if self.mean_basis is not None and self.mean_basis.kind not in MEAN_BASIS_KINDS:
            raise GPMSAError(
                "an emulator with a callable mean_basis cannot be saved (a file holds no code); "
                f"fit with one of the named mean bases {MEAN_BASIS_KINDS} to save it"
            )
        arrays = self._record_arrays()
        manifest = {
            "names": {"x": list(self.x_names), "t": list(self.t_names), "y": list(self.y_names)},
            "units": {"x": list(self.x_units), "t": list(self.t_units), "y": list(self.y_units)},
            "domain": {k: list(v) for k, v in self.domain.items()},
            "model": {
                "m": self.m,
                "p": self.p,
                "q": self.q,
                "p_u": self.p_u,
                "l_sim": self.l_sim,
                "correlation": "R(a,b) = exp(-sum_k beta_k d_k(a_k, b_k)) on unit-scale inputs, "
                "d_k = (a_k - b_k)^2, or 1/4 * 1[a_k != b_k] for a categorical input",
                "noise": "w_j ~ GP(0, R/lamUz_j) + nugget 1/lamWs_j; residual outside the basis "
                "has precision lamWOs * lam_sim_j; outputs standardised by y_mean, y_sd",
                "point_estimate": self.settings.get("point", "given"),
                "categorical": {k: list(v) for k, v in self.categorical.items()},
                "mean_basis": None if self.mean_basis is None else self.mean_basis.kind,
            },  # fmt: skip
            "priors": self.priors.to_dict(),
            "settings": self.settings,
            "metadata": self.metadata,
            "diagnostics": self.diagnostics,
        }
        ranged = self.given_ranges
        if ranged:  # only then: a file without given ranges is written as before
            manifest["model"]["input_ranges"] = list(ranged)
        if self.standardizer.y_given:  # only then, as input_ranges: other files as before
            manifest["model"]["y_given"] = list(self.standardizer.y_given)
        for key in ("index_names", "index_units"):  # only where given, as y_given
            if getattr(self, key) is not None:
                manifest["model"][key] = list(getattr(self, key))
        _check_metadata(self.metadata, "metadata")
        if self.convergence is not None:
            manifest["convergence"] = self.convergence
        manifest = jsonable(manifest)
        try:
            json.dumps(manifest["metadata"], allow_nan=False)
        except (TypeError, ValueError, RecursionError) as exc:
            raise GPMSAError(
                f"Emulator.metadata must be JSON-able (str, numbers, lists, dicts): {exc}"
            ) from exc
        return manifest, arrays

    def _record_arrays(self) -> dict[str, np.ndarray]:
        """The arrays of the file's record (``to_record``), float64 and contiguous."""
        s = self.standardizer
        arrays = {
            "x_unit": self.x_unit, "t_unit": self.t_unit, "y": self.y, "K": self.K, "w": self.w,
            "x_min": s.x_min, "x_max": s.x_max, "t_min": s.t_min, "t_max": s.t_max,
            "y_mean": s.y_mean, "y_sd": s.y_sd if s.columnwise else np.array([s.y_sd]),
            "grid": s.grid,
            "log_post": self.log_post,
        }  # fmt: skip
        if self.index is not None:
            arrays["index"] = self.index
        for k, v in self.params.items():
            arrays[f"param_{k}"] = v
        for k, v in self.draws.items():
            arrays[f"draw_{k}"] = v
        for k, v in (self.calibration or {}).items():
            arrays[f"cal_{k}"] = v
        if self.discrepancy_bases is not None:  # stacked; settings.obs_lengths splits them
            arrays[DISCREPANCY_ARRAY] = np.vstack(self.discrepancy_bases)
        if self.separable is not None:  # only then: other files as before
            arrays[KRON_ARRAY] = self.separable.factor_of_column()
        return {k: np.ascontiguousarray(v, dtype=np.float64) for k, v in arrays.items()}

    @functools.cached_property
    def model_sha256(self) -> str:
        """SHA-256 (64 hex digits) of what defines this emulator's predictions and calibrations:
        every array its file holds (training runs, basis, weights, standardisation, point
        estimate, retained draws, a joint fit's calibration draws; as float64), its input and
        output names, categorical levels, mean basis and priors. Not its metadata, settings,
        diagnostics, units or output index labels (``index_names``, ``index_units``), nor
        (unlike a file's ``content_sha256``, which ``gpmsa.load``'s ``sha256=`` checks) the
        time of writing or the library version: an emulator read back
        by ``gpmsa.load`` has the ``model_sha256`` of the one saved. A calibration records it
        (Posterior info "emulator_sha256") so that predictions refuse another emulator with its
        draws. Computed once, on first use (0.4 ms for the shipped band emulator's 0.3 MB of
        arrays): what it digests is read-only (``_freeze``)."""
        mb = self.mean_basis
        basis = None if mb is None else mb.kind
        if mb is not None and mb.kind not in MEAN_BASIS_KINDS:  # a callable: by its identity
            fn = mb.fn
            basis = f"{mb.kind}:{getattr(fn, '__module__', '')}.{getattr(fn, '__qualname__', '')}"
            basis += f"@{id(fn):x}"
        defining = {
            "names": {"x": list(self.x_names), "t": list(self.t_names), "y": list(self.y_names)},
            "categorical": {k: list(v) for k, v in self.categorical.items()},
            "mean_basis": basis,
            "priors": self.priors.to_dict(),
        }
        return content_hash(self._record_arrays(), jsonable(defining))

    @classmethod
    def from_record(cls, manifest: dict, arrays: dict[str, np.ndarray]) -> Emulator:
        """The emulator of a file's (manifest, arrays), as ``read_raw`` returns them.

        Raises EmulatorFileError naming what is missing or inconsistent (shapes, priors, domain).
        """
        try:
            check_record(manifest, arrays)
        except GPMSAError as exc:
            raise EmulatorFileError(str(exc)) from exc
        try:
            names = {k: tuple(manifest["names"][k]) for k in ("x", "t", "y")}
            ranged = manifest["model"].get("input_ranges", [])  # check_fields checked it
            std = Standardizer(
                **{k: arrays[k] for k in STD_FIELDS}, y_sd=_y_sd(arrays["y_sd"]),
                x_ranged=tuple(n in ranged for n in names["x"]),
                t_ranged=tuple(n in ranged for n in names["t"]),
                y_given=tuple(manifest["model"].get("y_given", ())),  # check_fields checked it
            )  # fmt: skip
            units = {k: tuple(manifest["units"][k]) for k in ("x", "t", "y")}
            draws = {k[5:]: v for k, v in arrays.items() if k.startswith("draw_")}
            cal = {k[4:]: v for k, v in arrays.items() if k.startswith("cal_")} or None
            shapes = {k: v.shape[1:] for k, v in {**(cal or {}), **draws}.items()}
            convergence = read_back_convergence(manifest.get("convergence"), shapes)
            flagged = convergence.get("flagged") if isinstance(convergence, dict) else None
            emu = cls(
                standardizer=std, x_unit=arrays["x_unit"], t_unit=arrays["t_unit"],
                y=arrays["y"], K=arrays["K"], w=arrays["w"], index=arrays.get("index"),
                params={k: arrays[f"param_{k}"] for k in EMULATOR_PARAMS},
                priors=Priors.from_dict(manifest["priors"]), names=names, units=units,
                draws=draws, log_post=arrays["log_post"], metadata=manifest["metadata"],
                settings=manifest["settings"],
                diagnostics=read_back(manifest["diagnostics"], shapes, flagged),  # NaN, inf
                calibration=cal, convergence=convergence,  # check_fields checked it
                levels=_levels(manifest, names), mean_basis=_mean_basis(manifest, names),
                discrepancy_bases=split_bases(arrays, manifest["settings"]),
                separable=kron_groups(arrays),
                **{k: tuple(v) for k in ("index_names", "index_units")
                   if (v := manifest["model"].get(k)) is not None},  # check_fields checked them
            )  # fmt: skip
            _check_consistent(emu)
            domain = {k: list(v) for k, v in emu.domain.items()}
            if manifest.get("domain") != domain:
                raise ValueError(
                    f"domain: {str(manifest.get('domain'))[:200]} differs from the arrays' {domain}"
                )
        except EmulatorFileError:
            raise
        except (GPMSAError, KeyError, TypeError, ValueError, IndexError) as exc:
            raise EmulatorFileError(f"inconsistent content ({type(exc).__name__}: {exc})") from exc
        return emu

    def save(self, path: str | Path) -> Path:
        """Write the emulator file (see docs/emulator-file.md); returns the path.

        Refuses (GPMSAError, before writing anything) an emulator that ``load`` would refuse:
        invalid content, non-finite metadata, or sizes beyond ``gpmsa.limits``. An existing
        emulator file is replaced in one step, never left half-written; a study file is not
        replaced (GPMSAError): its study would no longer load. (A study's model file is an
        emulator file: replaced, its study refuses it on loading, the sha256 differing.) Nor is
        a non-empty file that is not a gpmsa file (a user's CSV or notes: GPMSAError).
        """
        path = check_path(path)
        refuse_to_replace(path, FORMAT)
        manifest, arrays = self.checked_record(path)
        return write_raw(path, manifest, arrays)

    def checked_record(self, path: str | Path) -> tuple[dict, dict[str, np.ndarray]]:
        """``to_record`` checked as ``load`` checks a file; GPMSAError (refusing to write
        ``path``) for a record that ``load`` would refuse."""
        manifest, arrays = self.to_record()
        try:
            check_record(manifest, arrays)
        except EmulatorFileError as exc:
            raise GPMSAError(f"refusing to write {path}, it could not be read back: {exc}") from exc
        return manifest, arrays

    def __repr__(self) -> str:
        """One line: the runs, the first names of x and t (each cut, the rest counted: "+14
        more"), the outputs, the components and the retained draws."""
        outputs = f"{self.l_sim} output{'' if self.l_sim == 1 else 's'}"
        return (
            f"Emulator(m={self.m}, x={repr_names(self.x_names)}, t={repr_names(self.t_names)}, "
            f"y={outputs}, p_u={self.p_u}, draws={self.n_draws})"
        )


def _precision_diagonal(L: np.ndarray, gls: GLS | None) -> np.ndarray:
    """Diagonal (m,) of S^-1 (S = L L^T), or with a GLS mean of its projection
    S^-1 - B (H^T S^-1 H)^-1 B^T, B = S^-1 H = L^-T A: the precision of each run's weight
    given the others, the mean's coefficients integrated out."""
    Linv = solve_triangular(L, np.eye(L.shape[0]), lower=True)
    d = np.sum(Linv**2, axis=0)
    if gls is not None:
        B = solve_triangular(L, gls.A, lower=True, trans="T")
        d = d - np.sum(B * cho_solve(gls.Q, B.T).T, axis=1)
    return d


def load(path: str | Path, *, sha256: str | None = None) -> Emulator:
    """Read an emulator file written by ``Emulator.save`` (any older schema; never unpickles).

    Only regular files are read; sizes are checked before anything is decompressed and every
    field of the content is validated (``gpmsa.fitting.validation``). ``sha256``: the expected
    ``content_sha256`` (``gpmsa info`` prints it), received from the file's author over a
    trusted channel; a file whose content differs is refused.

    Raises EmulatorFileError naming the problem (and the field) for a damaged, edited,
    inconsistent, foreign or newer file.
    """
    return build(path, *read_checked(path, sha256=sha256))


def read_checked(path: str | Path, *, sha256: str | None = None) -> tuple[dict, dict]:
    """``load``'s first half: the emulator file's manifest and arrays, read and checked as
    ``load`` checks them (the zip, the declared content, the content hash, ``sha256``), no
    Emulator built; EmulatorFileError as ``load`` raises it."""
    expected = check_expected_sha256(sha256)
    manifest, arrays = read_raw(path, check_manifest)
    verify_content(manifest, expected, path)
    return manifest, arrays


def build(path: str | Path, manifest: dict, arrays: dict) -> Emulator:
    """``load``'s second half: the Emulator of ``read_checked(path)``'s record;
    EmulatorFileError naming ``path`` for inconsistent content."""
    try:
        return Emulator.from_record(manifest, arrays)
    except EmulatorFileError as exc:
        raise EmulatorFileError(f"{path}: {exc}") from exc


def _levels(manifest: dict, names: dict) -> categorical_mod.Levels:
    """Per input column, the levels the file declares (None: continuous)."""
    cat = manifest["model"].get("categorical", {})
    return tuple(tuple(cat[n]) if n in cat else None for n in names["x"] + names["t"])


def _mean_basis(manifest: dict, names: dict) -> MeanBasis | None:
    kind = manifest["model"].get("mean_basis")
    return None if kind is None else MeanBasis(kind, len(names["x"]) + len(names["t"]))


def _y_sd(y_sd: np.ndarray) -> float | np.ndarray:
    """The Standardizer's ``y_sd`` of a file's array: shape (1,) the one sd (a float); (l_sim,)
    with l_sim > 1 one per output element (``SimData(y_scale="columnwise")``)."""
    return float(y_sd[0]) if y_sd.size == 1 else y_sd


def _check_consistent(emu: Emulator) -> None:
    m, p, q, l_sim, p_u = emu.m, emu.p, emu.q, emu.l_sim, emu.p_u
    checks = {
        "t_unit": (emu.t_unit.shape, (m, q)), "y": (emu.y.shape, (m, l_sim)),
        "w": (emu.w.shape, (m, p_u)), "x_min": (emu.standardizer.x_min.shape, (p,)),
        "t_min": (emu.standardizer.t_min.shape, (q,)),
        "y_mean": (emu.standardizer.y_mean.shape, (l_sim,)),
        "names.x": ((len(emu.x_names),), (p,)), "names.t": ((len(emu.t_names),), (q,)),
    }  # fmt: skip
    for what, (got, want) in checks.items():
        if tuple(got) != tuple(want):
            raise ValueError(f"{what} has shape {got}, expected {want}")
    for k, v in emu.draws.items():
        if v.shape[1:] != emu.params[k].shape or v.shape[0] != emu.n_draws:
            raise ValueError(f"draws of {k} have shape {v.shape}")


def check_metadata(metadata) -> dict:
    """``metadata`` (None or a dict) as a dict; GPMSAError unless a file can hold it
    (``_check_metadata``)."""
    if metadata is None:
        return {}
    if not isinstance(metadata, dict):
        raise GPMSAError(f"metadata must be None or a dict, got {type(metadata).__name__}")
    _check_metadata(metadata, "metadata")
    return dict(metadata)


def output_variance(var_w: np.ndarray, K: np.ndarray, lam_sim: np.ndarray, lam_wos: float):
    """Held-out outputs' variance (standardised) from the held-out projected weights' variance
    ``var_w`` (n, p_u): for l_sim > 1 the weights' own part (less the projection noise
    1/(lam_sim lamWOs) that a held-out w-hat holds) through K, plus the residual 1/lamWOs; for
    one output the weights' variance through K (its projection noise is the residual)."""
    if K.shape[0] == 1:
        return var_w @ (K**2).T
    return (var_w - 1.0 / (lam_sim * lam_wos)) @ (K**2).T + 1.0 / lam_wos


METADATA_INT_DIGITS = sys.int_info.default_max_str_digits
"""Most decimal digits of an integer in metadata: Python's default limit of int/str conversion
(4300), which a reader's json.loads applies (a raised limit on the writer's machine is not the
reader's)."""
_INT_BOUND = 10**METADATA_INT_DIGITS


def _check_metadata(value, where: str, depth: int = 0) -> None:
    """Metadata a file can hold: dicts with string keys, lists, tuples, strings, bools, integers
    of at most ``METADATA_INT_DIGITS`` digits, finite floats and None (NaN would come back as
    null). JSON has no tuple: a tuple comes back as a list (numpy scalars as Python numbers)."""
    if depth > 64:
        raise GPMSAError(f"{where}: nests deeper than 64 levels")
    if value is None or isinstance(value, (str, bool, np.integer, np.bool_)):
        return
    if isinstance(value, int):
        if -_INT_BOUND < value < _INT_BOUND:
            return
        raise GPMSAError(
            f"{where}: an integer of more than {METADATA_INT_DIGITS} digits (about "
            f"{int(value.bit_length() * 0.30103)}), more than a reader's JSON parser accepts; "
            "store it as a str"
        )
    if isinstance(value, (float, np.floating)):
        if isinstance(value, np.floating) and value.dtype.itemsize > 8:
            raise GPMSAError(
                f"{where}: a {value.dtype.name} does not fit a JSON number (float64); convert "
                "it with float()"
            )
        if not np.isfinite(value):
            raise GPMSAError(
                f"{where} = {value}: metadata must be finite (NaN and inf are not JSON and would "
                "not come back)"
            )
        return
    if isinstance(value, dict):
        for k, v in value.items():
            if not isinstance(k, str):
                raise GPMSAError(f"{where}: keys must be strings, got {k!r}")
            _check_metadata(v, f"{where}[{k!r}]", depth + 1)
        return
    if isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            _check_metadata(v, f"{where}[{i}]", depth + 1)
        return
    raise GPMSAError(
        f"{where}: Emulator.metadata must be JSON-able (str, numbers, lists, dicts), got "
        f"{type(value).__name__}"
    )
