"""The full calibrated prediction at new x: simulator eta, discrepancy delta, observation y.

This is SEPIA's ``SepiaFullPrediction`` (GPM/SA's ``gPredict`` in 'uvpred' mode). GPM/SA's
observation model (Higdon et al. 2008) on the standardised scale is

    y(x) = K u(x, theta) + D v(x) + e,   e ~ N(0, I / lamOs),

with u_j ~ GP(0, R(.; betaU_j) / lamUz_j) plus the nugget 1/lamWs_j (the emulator's GP, which also
produced the simulation runs' weights w) and v_k ~ GP(0, R(x; betaV) / lamVz) independently per
discrepancy basis vector. For each posterior draw of (theta, lamOs, betaV, lamVz and the emulator
parameters) the weights (v, u) at the new x are Gaussian given everything observed: the runs'
weights w and the observations' reduced data (the GLS weights of y_obs on [D, K], with covariance
Sigma_obs / lamOs). Conditioning is done in two steps, on w (per component, the emulator's
Cholesky factor) and then on the reduced observations (dense, small). Realizations give

    eta = y_mean + y_sd K u          the simulator at the posterior theta,
    delta = y_sd D v                 the discrepancy,
    zeta = eta + delta               the real process,
    y = zeta + y_sd e                a new observation (its noise, GPM/SA's default I / lamOs),

on the native scale and on one output grid; ``u`` and ``v`` are the basis-space values.
Categorical inputs and a mean basis are taken as ``Emulator.predict`` takes them (`_conditional`;
docs/categorical-and-constraints.md).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.linalg import cho_solve, solve_triangular

from gpmsa._fp_state import underflow_as_zero
from gpmsa._progress import progress_bar
from gpmsa._threads import one_thread
from gpmsa.calibration.observations import check_x, layout_digest
from gpmsa.calibration.posterior import Posterior
from gpmsa.errors import GPMSAError, numbers_text
from gpmsa.limits import check_memory
from gpmsa.model import index_points
from gpmsa.model.basis import (
    SCALE_TOL,
    basis_digest,
    basis_scale,
    describe_discrepancy,
    discrepancy_basis,
    discrepancy_kind,
    given_bases,
    interpolate_basis,
    is_basis_list,
    scaled_as,
)
from gpmsa.model.constraints import round_levels
from gpmsa.model.correlation import correlation
from gpmsa.model.data import (
    ObsData,
    as_float,
    by_index_names,
    check_count,
    check_finite,
    check_flag,
    check_level,
    evenly_spaced,
)
from gpmsa.model.discrepancy import groups_of, params_at, sample_names
from gpmsa.model.index_points import is_points, n_points
from gpmsa.model.problem import reduce_obs
from gpmsa.predictive._common import (
    EMULATOR_PARAMS,
    check_posterior_emulator,
    extended,
    gp_factors,
    gpmsa_model_only,
    lacks_text,
    mvn_factor,
    paired_draws,
    posterior_lamos,
    posterior_theta,
    realization_interval,
    realization_quantile,
    rng_of,
    unit_inputs,
)

AS_FITTED = "as fitted"
"""``discrepancy`` default of ``full_prediction``: the basis the joint fit recorded."""

QUANTITIES = ("eta", "delta", "zeta", "y")


@dataclass(frozen=True, eq=False)
class FullPrediction:
    """Draws of the calibrated prediction at new x (SEPIA's full prediction).

    Attributes:
        x: (N, p) the inputs, native units; grid: (l,) the output grid of eta, delta, zeta, y.
        draw_index: (S,) the posterior draws used, in order.
        theta: (S, q) their calibration parameters, native (a categorical one its level
            codes); lamOs: (S,) their noise precisions.
        mu: (S, N, p_v + p_u) per draw, the conditional mean of the basis weights (v then u,
            standardised scale); cov: (S, N, p_v + p_u, p_v + p_u) their covariance at each point.
        u: (S * n_rlz, N, p_u), v: (S * n_rlz, N, p_v) realizations of the weights (row
            s * n_rlz + r: realization r of draw s).
        eta, delta, y: (S * n_rlz, N, l) the realizations on the native scale (see the module
            docstring); ``zeta`` = eta + delta.
        K: (l, p_u) and D: (l, p_v) the bases on ``grid``; y_mean: (l,), y_sd: the
            standardisation (a float; scaled columnwise, (l,) each element's sd on ``grid``).
        x_names, x_units: (p,) the known inputs' names and units (for figures; empty: unknown).
        index_names, index_units: the output index's labels (``SimData(index_names=,
            index_units=)``; None: none given), for figures.
    """

    x: np.ndarray
    grid: np.ndarray
    draw_index: np.ndarray
    theta: np.ndarray
    lamOs: np.ndarray
    mu: np.ndarray
    cov: np.ndarray
    u: np.ndarray
    v: np.ndarray
    eta: np.ndarray
    delta: np.ndarray
    y: np.ndarray
    K: np.ndarray
    D: np.ndarray
    y_mean: np.ndarray
    y_sd: float | np.ndarray
    x_names: tuple[str, ...] = ()
    x_units: tuple[str, ...] = ()
    index_names: tuple[str, ...] | None = None
    index_units: tuple[str, ...] | None = None

    @property
    def zeta(self) -> np.ndarray:
        """(S * n_rlz, N, l) realizations of the real process eta + delta (no noise)."""
        return self.eta + self.delta

    @property
    def p_v(self) -> int:
        """Number of discrepancy basis vectors (0: no discrepancy)."""
        return self.D.shape[1]

    def _check(self, what: str) -> None:
        """GPMSAError unless ``what`` is one of ``QUANTITIES`` (a str: an array or list, whose
        ``in`` test numpy would refuse or answer elementwise, is named as such)."""
        if not isinstance(what, str) or what not in QUANTITIES:
            got = f"{what!r}"[:80] + ("" if isinstance(what, str) else f" ({type(what).__name__})")
            raise GPMSAError(f"what must be one of {QUANTITIES} (one str), got {got}")

    def _moments_std(self, what: str) -> tuple[np.ndarray, np.ndarray]:
        """Per draw mean and variance (S, N, l), standardised scale, of one quantity."""
        p_v, l = self.p_v, n_points(self.grid)
        if what == "eta":
            B = np.hstack([np.zeros((l, p_v)), self.K])
        elif what == "delta":
            B = np.hstack([self.D, np.zeros((l, self.K.shape[1]))])
        else:
            B = np.hstack([self.D, self.K])
        mean = self.mu @ B.T
        var = np.einsum("lc,sncd,ld->snl", B, self.cov, B, optimize=True)
        if what == "y":
            var = var + (1.0 / self.lamOs)[:, None, None]
        return mean, var

    def mean(self, what: str = "y") -> np.ndarray:
        """(N, l) predictive mean of ``what`` ("eta", "delta", "zeta" or "y"), native units."""
        self._check(what)
        m, _ = self._moments_std(what)
        offset = 0.0 if what == "delta" else self.y_mean
        return m.mean(axis=0) * self.y_sd + offset

    def var(self, what: str = "y") -> np.ndarray:
        """(N, l) predictive variance of ``what``, native units^2 (law of total variance)."""
        self._check(what)
        m, v = self._moments_std(what)
        return (v.mean(axis=0) + m.var(axis=0)) * self.y_sd**2

    def quantile(self, q: float | np.ndarray | Sequence[float], what: str = "y") -> np.ndarray:
        """Predictive quantile(s) of ``what`` (as `mean`), native units, at probability q in
        [0, 1] (a number, or an array of them): the empirical quantiles of its S * n_rlz
        realizations (numpy's linear rule, so Monte-Carlo estimates), shape (N, l) for a number
        and ``np.shape(q) + (N, l)`` for an array; ``interval(what, level)`` gives those at
        (1 -+ level) / 2. GPMSAError naming q for one outside [0, 1], NaN or not a number."""
        self._check(what)
        if isinstance(q, str) and q in QUANTITIES:  # quantile("eta") for quantile(q, "eta")
            raise GPMSAError(
                f"q must be a probability in [0, 1] (or an array of them), got {q!r}: the "
                f"quantity comes second, quantile(q, what={q!r})"
            )
        return realization_quantile(getattr(self, what), q)

    def interval(self, what: str = "y", level: float = 0.9) -> tuple[np.ndarray, np.ndarray]:
        """Central interval (N, l) of ``what`` (as `mean`), probability ``level``, native units,
        from the realizations' quantiles (`quantile` at (1 -+ level) / 2; a warning when there
        are too few for its tails: `realization_interval`)."""
        self._check(what)
        level = check_level(level)
        fix = "full_prediction's n_draws or n_rlz"
        return realization_interval(getattr(self, what), level, fix)

    def __repr__(self) -> str:
        s = np.shape(self.theta)[0]
        rlz = np.shape(self.eta)[0] // s if s else 0
        return (f"FullPrediction({np.shape(self.x)[0]} points x {n_points(self.grid)} outputs, "
                f"{s} draws x {rlz} realizations, p_u={np.shape(self.K)[1]}, "
                f"p_v={self.p_v})")  # fmt: skip


def _posterior_sets(emulator, posterior, n_draws, paired: bool | None = None):
    """Indices and per-draw parameter dicts (unit theta) from a joint fit or a Posterior; the
    emulator parameters paired draws or the point estimate (``paired``; None: the joint fit's
    draws, a Posterior's point estimate)."""
    paired = posterior is None if paired is None else paired
    if posterior is None:  # (full_prediction checked that the emulator holds the draws)
        cal = emulator.calibration
        if paired and not emulator.draws:
            raise GPMSAError("the emulator kept no posterior draws of its own parameters")
        n = cal["theta"].shape[0]
        p = emulator.p

        def get(i):
            prm = {k: np.asarray(emulator.draws[k][i]) if paired else emulator.params[k]
                   for k in EMULATOR_PARAMS}  # fmt: skip
            prm["theta"] = np.asarray(cal["theta"][i], dtype=float).reshape(-1)
            prm["lamOs"] = float(np.ravel(cal["lamOs"][i])[0])
            if "betaV" in cal:
                prm["lamVz"] = np.asarray(cal["lamVz"][i], dtype=float).reshape(-1)
                prm["betaV"] = np.asarray(cal["betaV"][i], dtype=float).reshape(
                    p, prm["lamVz"].size
                )
            return prm

    else:  # a gpmsa.Posterior (checked by full_prediction)
        names = tuple(emulator.t_names)
        samples = posterior.samples
        missing = [k for k in (*names, "lamOs") if k not in samples]
        if missing:
            raise GPMSAError(lacks_text(missing, tuple(samples)))
        theta = posterior_theta(
            emulator, np.column_stack([np.asarray(samples[k], dtype=float) for k in names])
        )
        lam_os = posterior_lamos(posterior)
        pos = paired_draws(emulator, posterior, "full_prediction") if paired else None
        n = theta.shape[0]
        p = emulator.p
        n_grp = groups_of(samples, p)
        bnames, lnames = sample_names(p, n_grp) if n_grp else ([], [])
        for k in (*bnames, *lnames):
            if not np.all(np.asarray(samples[k]) > 0):
                raise GPMSAError(f"the posterior's {k} draws must be > 0")

        def get(i):
            prm = {k: emulator.params[k] if pos is None else np.asarray(emulator.draws[k][pos[i]])
                   for k in EMULATOR_PARAMS}  # fmt: skip
            prm["theta"] = theta[i]
            prm["lamOs"] = float(lam_os[i])
            if n_grp:
                prm["betaV"], prm["lamVz"] = params_at(samples, p, n_grp, i)
            return prm

    idx = evenly_spaced(n, n_draws)
    return idx, [get(i) for i in idx]


def _pred_grid(emulator, obs: ObsData, grid):
    """The output grid of the prediction: ``grid``, else the observations' common grid."""
    std = emulator.standardizer
    if emulator.l_sim == 1:
        if grid is not None:
            raise GPMSAError("a scalar output has no output grid; leave grid=None")
        return std.grid
    if grid is not None and is_points(std.grid):
        g = as_float(by_index_names(grid, emulator.index_names, "grid"), "grid")
        if g.ndim == 1 and g.size == std.grid.shape[1]:
            g = g[None, :]  # one point
        check_finite(g, "grid")
        if g.shape[0] == 0:
            raise GPMSAError("grid must hold at least one point")
        # its columns checked; a point outside the hull refused
        index_points.weights(std.grid, g, "grid", emulator.index_names)
        return g
    if grid is not None:
        g = as_float(grid, "grid")
        if g.ndim > 1 and sum(n > 1 for n in g.shape) > 1:
            raise GPMSAError(f"grid must be one row of output-grid points, got shape {g.shape}")
        g = g.reshape(-1)
        check_finite(g, "grid")
        lo, hi = std.grid.min(), std.grid.max()
        if g.size == 0 or not index_points.within(g, lo, hi):
            lo, hi = numbers_text(lo, hi, *((g.min(), g.max()) if g.size else ()))[:2]
            raise GPMSAError(
                f"{index_points.named('grid', emulator.index_names)} must be non-empty and lie "
                f"within the simulation grid [{lo}, {hi}]"
            )
        return g
    grids = [std.grid if g is None else g for g in obs.output_grids(emulator.index_names)]
    same = all(g.shape == grids[0].shape and np.array_equal(g, grids[0]) for g in grids)
    return grids[0] if same else std.grid


def _pred_discrepancy(kind, obs_grids: list, std, grid: np.ndarray, scalar: bool, bases=None):
    """D (l, p_v) on the prediction grid with the normalisation the fit used for the data
    (``obs_grids``: the experiments' index grids, `ObsData.output_grids`; ``bases``: the
    reduction's per-experiment bases, ``ObsProblem.D``)."""
    if kind is None:
        return np.zeros((n_points(grid), 0))
    if scalar:
        return np.ones((1, 1))
    obs_grids = [std.grid if g is None else g for g in obs_grids]
    if is_basis_list(kind):
        return _experiment_basis(bases, obs_grids, grid)
    if not isinstance(kind, str):
        if not all(g.shape == grid.shape and np.array_equal(g, grid) for g in obs_grids):
            raise GPMSAError(
                "a discrepancy basis given as an array is known on the observations' grid only: "
                "every experiment must share that grid, and grid= must be it (or None); on any "
                "other grid pass the same basis functions evaluated at grid='s points as "
                "grid_discrepancy= (one row per point)"
            )
        return discrepancy_basis(kind, grid)
    # "constant"/"linear": the first column is 1 before normalisation; keep the data's scale.
    # (the scale as computed, not rounded: an index of ~1e12 gives a 'linear' scale ~5e-13).
    # The fit lets the largest |index| differ by 1e-12 relative (`_check_discrepancy_scales`),
    # which moves the scale by at most as much; the margin covers the scales' own rounding
    scales = np.array([float(discrepancy_basis(kind, g)[0, 0]) for g in obs_grids])
    if not np.allclose(scales, scales[0], rtol=1e-12 + 16 * np.finfo(np.float64).eps, atol=0.0):
        raise GPMSAError(
            f"the experiments' grids give the {kind!r} discrepancy basis different scales; "
            "full_prediction needs them to share one"
        )
    D = discrepancy_basis(kind, grid)
    return D * (scales[0] / D[0, 0])


def _given_on_grid(kind, given, grid: np.ndarray, scalar: bool, kept: bool,
                   fitted: float | None) -> np.ndarray:  # fmt: skip
    """``given`` (grid.size, p_v): the basis functions of the calibration's array or list
    ``kind`` on the prediction grid, divided as the fit divided the observations' bases
    (``kept``: ``kind`` is the joint fit's kept, normalised list; ``fitted``: the divisor the
    fit recorded, None where it recorded none)."""
    if scalar or kind is None or isinstance(kind, str):
        raise GPMSAError(
            "grid_discrepancy= goes with a discrepancy basis given as an array or a list, on a "
            "multivariate output ('constant' and 'linear' are known on any grid)"
        )
    raw = given_bases(kind)
    divisor = _grid_divisor(kind, raw, kept, fitted)
    p_v = raw[0].shape[1]
    D = as_float(given, "grid_discrepancy")
    if D.ndim == 1 and p_v == 1:
        D = D[:, None]
    n = n_points(grid)
    if D.shape != (n, p_v):
        hint = "; SEPIA stores D as (p_v, l): pass its transpose" if (
            D.shape == (p_v, n)) else ""  # fmt: skip
        raise GPMSAError(
            f"grid_discrepancy must be ({n}, {p_v}): one row per point of the "
            f"prediction grid, one column per discrepancy basis vector; got {D.shape}{hint}"
        )
    check_finite(D, "grid_discrepancy")
    return scaled_as(raw, D) if divisor is None else D / divisor


def _grid_divisor(kind, raw: list[np.ndarray], kept: bool, fitted: float | None) -> float | None:
    """The fit's divisor of ``grid_discrepancy=`` (`_given_on_grid`): None where ``kind`` is
    the basis as given to the fit (its own normalisation, `scaled_as`, is the fit's), the
    recorded one with the kept list; GPMSAError where neither is known to hold: the kept list
    without a record, or a basis at another scale (a normalised copy, or a multiple)."""
    if fitted is None:
        if kept:
            raise GPMSAError(
                "grid_discrepancy= is divided by the scale that normalised the fit's bases, "
                "which this emulator (or posterior=) does not record (settings['discrepancy_"
                "scale'], absent from files written before it was recorded; Emulator."
                "discrepancy_bases are normalised): pass the list given to the fit again as "
                "discrepancy="
            )
        return None
    fitted = float(fitted)
    if kept:
        return fitted
    own = basis_scale(raw)
    if math.isclose(own, fitted, rel_tol=SCALE_TOL):
        return None
    what = "list" if is_basis_list(kind) else "array"
    remedy = ("leave discrepancy= at its default (the joint fit's kept bases, with its scale) or "
              "pass the list given to the fit" if what == "list"
              else "pass the array given to the fit")  # fmt: skip
    raise GPMSAError(
        f"grid_discrepancy= is divided by the scale that normalised the basis given to the fit "
        f"({fitted:.6g}, settings['discrepancy_scale']), but discrepancy= ("
        f"{describe_discrepancy(kind)}) normalises by {own:.6g}: it is that basis at another "
        f"scale (a normalised copy, e.g. of Emulator.discrepancy_bases, or a multiple), so "
        f"grid_discrepancy= could be meant at either scale: {remedy}"
    )


def _experiment_basis(bases, obs_grids: list[np.ndarray], grid: np.ndarray) -> np.ndarray:
    """Per-experiment bases (a list, normalised jointly): the basis of the experiments whose
    index grid is ``grid`` (SEPIA's full prediction likewise takes one experiment's D_obs,
    ``obs_ref``); GPMSAError where no experiment has that grid, or those that do differ."""
    on = [j for j, g in enumerate(obs_grids) if g.shape == grid.shape and np.array_equal(g, grid)]
    if not on:
        sizes = ", ".join(f"{j}: {n_points(g)} values" for j, g in enumerate(obs_grids[:6]))
        raise GPMSAError(
            "per-experiment discrepancy bases (a list) are known on their experiments' index "
            "grids only: pass grid= one experiment's grid (obs.grids[j]; experiments "
            f"{sizes}{', ...' if len(obs_grids) > 6 else ''}), whose basis gives delta, or "
            "experiment=j; on any other grid pass the basis functions evaluated at grid='s "
            "points as grid_discrepancy= (one row per point, as given to the fit)"
        )
    D = bases[on[0]]
    if any(not np.array_equal(bases[j], D) for j in on[1:]):
        raise GPMSAError(
            f"experiments {on} share this grid but their discrepancy bases differ, so delta on "
            "it is not one function: pass experiment=j (SEPIA's obs_ref) for experiment j's "
            "basis, or predict on a grid that one of them alone has"
        )
    return D


def _experiment_prediction(kind, obs_grids: list, std, grid, experiment, bases, index_names):
    """(grid, D) of ``full_prediction(..., experiment=j)``: experiment j's index grid (of
    ``obs_grids``, `ObsData.output_grids`) and its per-experiment basis (``bases``: the
    reduction's, normalised as the fit's); GPMSAError for
    another kind of discrepancy, j outside the experiments, or a ``grid`` that is not j's."""
    if not is_basis_list(kind):
        raise GPMSAError(
            "experiment= chooses among per-experiment discrepancy bases (a list), got "
            f"discrepancy={describe_discrepancy(kind)}: leave experiment out (grid= chooses "
            "the output grid)"
        )
    j = check_count(experiment, "experiment", 0, len(obs_grids) - 1)
    own = std.grid if obs_grids[j] is None else obs_grids[j]
    if grid is not None:
        g = as_float(by_index_names(grid, index_names, "grid"), "grid")
        g = g if is_points(own) else g.reshape(-1)
        if g.shape != own.shape or not np.array_equal(g, own):
            raise GPMSAError(
                f"experiment={j} predicts on its grid (obs.grids[{j}], {n_points(own)} values), "
                "where its basis is known: leave grid= out"
            )
    return own, bases[j]


def _check_fitted_discrepancy(emulator, discrepancy) -> None:
    """GPMSAError when ``discrepancy`` is not the basis the joint fit recorded (its settings'
    "discrepancy": None, "constant", "linear", "given" for an array or "list" for
    per-experiment bases, which the basis digest compares further)."""
    settings = getattr(emulator, "settings", None) or {}
    if "discrepancy" not in settings:
        return
    fitted = settings["discrepancy"]
    if discrepancy_kind(discrepancy) != fitted:
        shown = {"given": "an array", "list": "a list of per-experiment bases"}
        given = shown.get(discrepancy_kind(discrepancy), repr(discrepancy))
        was = shown.get(fitted, repr(fitted))
        raise GPMSAError(
            f"discrepancy={given} differs from the joint fit's discrepancy ({was}); the draws "
            "belong to that basis: leave discrepancy= at its default"
            + (" (or pass the fit's array again)" if fitted == "given" else "")
        )


def _check_fitted_obs(settings: dict, obs: ObsData) -> None:
    """GPMSAError when ``obs`` has other experiments (their count or lengths) or other values
    than the joint fit's, where the fit recorded them (its ``settings``, or the info of its
    `calibration_posterior`: "obs_lengths", "obs_sha256"; files written before the digest are
    checked by their lengths alone)."""
    fitted = settings.get("obs_lengths")
    lengths = [int(e.size) for e in obs.experiments]
    if fitted is not None and lengths != list(fitted):
        raise GPMSAError(
            f"obs has {len(lengths)} experiment(s) of lengths {lengths}, but the joint fit's had "
            f"{len(fitted)} of lengths {list(fitted)}: pass the ObsData the fit used"
        )
    digest = settings.get("obs_sha256")
    if digest is not None and obs.digest() != digest:
        raise GPMSAError(
            "obs holds other observations (x, y, grids or precisions) than the joint fit's: pass "
            "the ObsData the fit used (its experiments in the same order)"
        )


def _check_calibrated_obs(
    posterior, obs: ObsData, x_names, y_names, grid: np.ndarray, index_names=None
) -> None:
    """GPMSAError when ``posterior`` recorded the values of its observations (``gpmsa.calibrate``:
    info "obs_values_sha256") and ``obs`` holds other ones. Its x is compared with its columns
    in the order of ``x_names`` and y with its columns in the order of ``y_names``
    (`ObsData.values_digest`), as ``gpmsa.calibrate`` read them: the same table, columns in any
    order, is the same observations. Likewise their index grids and
    precisions (info "obs_layout_sha256", `layout_digest` against the simulation ``grid``)."""
    info = getattr(posterior, "info", None) or {}
    digest = info.get("obs_values_sha256")
    if digest is not None and obs.values_digest(x_names, y_names) != digest:
        raise GPMSAError(
            "obs holds other observations (x or y) than the calibration that drew posterior=: "
            "pass the ObsData given to gpmsa.calibrate or Calibrator.update, its experiments in "
            "the same order (or its x_obs and y_obs as ObsData(x=x_obs, y=y_obs))"
        )
    layout = info.get("obs_layout_sha256")
    grids = obs.output_grids(index_names)  # an index table's columns by name
    if layout is not None and layout_digest(grids, obs.output_precisions(y_names), grid) != layout:
        raise GPMSAError(
            "obs places its observations on other index grids or gives them other precisions "
            "than the calibration that drew posterior=: pass the ObsData given to "
            "gpmsa.calibrate or Calibrator.update (arrays given there: ObsData(x=x_obs, "
            "y=y_obs), without index or precision)"
        )


def _recorded_discrepancy(emulator, posterior: Posterior | None):
    """The discrepancy basis kind the joint fit (``posterior`` None) or the calibration behind
    ``posterior`` recorded (None: none), or the per-experiment bases the joint fit kept
    (``Emulator.discrepancy_bases``); GPMSAError where it must be passed again: a basis given
    as an array, a list of them for a Posterior, a Posterior that recorded the basis's
    digest but not its kind (made before the kind was kept), or one with discrepancy draws
    and no record at all (made by hand or read back from ArviZ)."""
    record = (emulator.settings if posterior is None else posterior.info) or {}
    kind = record.get("discrepancy")
    source = "the joint fit" if posterior is None else "the calibration"
    if kind is None and posterior is not None and "discrepancy_sha256" in record:
        raise GPMSAError(
            "with this posterior= pass the discrepancy basis the calibration used (None, "
            "'constant', 'linear' or the array): it records the basis's digest, not its kind"
        )
    drawn = posterior is not None and any(n.split("[")[0] == "lamVz" for n in posterior.names)
    if drawn and "discrepancy" not in record:
        raise GPMSAError(
            "posterior= has discrepancy draws (betaV, lamVz) but records no discrepancy basis "
            "(a Posterior made by hand or read back from ArviZ keeps no info): pass the "
            "calibration's discrepancy= ('constant', 'linear', the array or the list)"
        )
    if isinstance(kind, str) and kind == "given":
        raise GPMSAError(
            f"{source} used a discrepancy basis given as an array; pass it again as discrepancy="
        )
    if isinstance(kind, str) and kind == "list":
        kept = getattr(emulator, "discrepancy_bases", None)
        if posterior is not None and not _kept_for(emulator, record):
            kept = None
        if kept is None:
            raise GPMSAError(
                f"{source} used per-experiment discrepancy bases (a list); pass the list again "
                "as discrepancy="
            )
        return kept
    return kind


def _kept_for(emulator, record: dict) -> bool:
    """Whether the joint fit's kept per-experiment bases (``Emulator.discrepancy_bases``) are
    the list a posterior's calibration used (``record``: its info): the same normalised basis
    and groups (``discrepancy_sha256``) divided by the same number (``discrepancy_scale``), as
    ``calibration_posterior(emu)`` records them (a ``calibrate`` run on the joint fit's
    emulator with the list given to the fit too); the emulator itself is checked by the
    caller (``emulator_sha256``)."""
    settings = emulator.settings or {}
    digest, scale = settings.get("discrepancy_sha256"), settings.get("discrepancy_scale")
    return (
        digest is not None
        and scale is not None
        and record.get("discrepancy_sha256") == digest
        and record.get("discrepancy_scale") is not None
        and float(record["discrepancy_scale"]) == float(scale)
    )


@underflow_as_zero
def full_prediction(
    emulator,
    obs: ObsData,
    x,
    *,
    posterior: Posterior | None = None,
    discrepancy=AS_FITTED,
    discrepancy_groups=AS_FITTED,
    draws: bool | None = None,
    n_draws: int | None = None,
    n_rlz: int = 1,
    grid=None,
    seed=None,
    experiment: int | None = None,
    extrapolate: bool = False,
    grid_discrepancy=None,
    progress: bool = False,
) -> FullPrediction:
    """The calibrated prediction at new x: eta(x, theta), delta(x) and y(x), draw by draw.

    Args:
        emulator: a gpmsa.Emulator; from a joint fit (``gpmsa.fit(data, obs, ...)``) its
            calibration draws are used, paired with its emulator-parameter draws.
        obs: the ObsData the calibration used (the prediction conditions on it).
        x: (N, p) new known inputs, native units. Outside the training range: a warning; more
            than ``EXTRAPOLATION_MARGIN`` (10 %) of the range outside: GPMSAError naming the
            column (``extrapolate=True``: the warning).
        posterior: instead of the joint fit's draws, a Posterior of gpmsa.calibrate (theta,
            lamOs, and betaV, lamVz with a discrepancy) with the emulator at its point estimate
            (``draws=True``: at the emulator draws recorded with each theta);
            ``obs`` must then hold the calibration's x_obs and y_obs (where the Posterior
            recorded them: info "obs_values_sha256"), and ``emulator`` be the one it was drawn
            with (where it recorded it: info "emulator_sha256", ``Emulator.model_sha256``).
        discrepancy: the discrepancy basis of the calibration: None, "constant", "linear", an
            (l_obs, p_v) array or a list of per-experiment bases; the default takes the choice
            the joint fit, or the calibration behind ``posterior``, recorded (an array must be
            passed again, and a list too with ``posterior``; a joint fit keeps its list,
            ``Emulator.discrepancy_bases``).
        discrepancy_groups: the precision group of each discrepancy basis vector (as
            ``gpmsa.fit``'s); the default takes the one the joint fit or ``gpmsa.calibrate``
            recorded (none recorded: one group).
        draws: the emulator parameters (betaU, lamUz, lamWs, lamWOs) of each draw: True, the
            draw drawn jointly with its theta (a joint fit's own; with ``posterior``, as
            ``calibrated_predict(..., draws=True)`` pairs them: ``calibration_posterior`` of
            this joint fit, ``gpmsa.calibrate(..., emulator_params="draws")`` or a
            ``Calibrator(..., emulator_params="draws")`` update, another refused, GPMSAError);
            False, the point estimate; None (default): a joint fit's
            paired draws without ``posterior``, the point estimate with it.
        n_draws: at most this many posterior draws, evenly spaced (None: all).
        n_rlz: realizations per draw.
        grid: output grid of the prediction within the simulation grid, in any order (default:
            the observations' grid when all experiments share one, else the simulation grid).
            With per-experiment discrepancy bases (a list) one experiment's index grid: delta
            there is that experiment's basis's (as SEPIA's ``obs_ref``).
        seed: int, numpy Generator or None.
        experiment: with per-experiment bases, the experiment (0-based) whose basis gives
            delta, on its index grid (SEPIA's ``obs_ref``): needed where experiments share a
            grid with different bases (``[D_0, zeros]`` on one grid); None: ``grid``'s.
        extrapolate: as ``gpmsa.calibrate``'s: allow ``obs``'s x (which the calibration
            warned of) and ``x`` outside the emulator's x domain by more than
            ``EXTRAPOLATION_MARGIN`` (10 %) of a column's width, ``x`` with an
            ExtrapolationWarning; False: GPMSAError naming the column (a calibration made with
            ``extrapolate=True`` is predicted from with it too).
        grid_discrepancy: with a discrepancy basis given as an array or a list, the same basis
            functions evaluated on the prediction grid (``grid``, or its default), (l, p_v)
            as given to the fit, before normalisation (SEPIA's ``D_sim``): delta there, the
            fit's normalisation applied (the divisor it recorded, settings
            "discrepancy_scale", with its kept ``discrepancy_bases`` or the basis given to
            it; the basis at another scale, a normalised copy or a multiple, GPMSAError; a
            file without the record needs the basis given to the fit). None: the basis on the
            observations' grid only.
        progress: show a tqdm bar over the draws on stderr ("full_prediction").

    Returns:
        FullPrediction (native units; ``u``, ``v``, ``mu``, ``cov`` in the basis space).

    Example:
        >>> import numpy as np, gpmsa
        >>> rng = np.random.default_rng(0)
        >>> x, t = rng.uniform(size=(25, 1)), rng.uniform(size=(25, 1))
        >>> data = gpmsa.SimData(x=x, t=t, y=x + t, x_names=["x"], t_names=["t"])
        >>> obs = gpmsa.ObsData(x=[[0.2], [0.5], [0.8]], y=[[0.7], [1.1], [1.3]])
        >>> emu = gpmsa.fit(data, obs, n_iter=50, tune=False, seed=0, discrepancy="constant")
        >>> pred = gpmsa.full_prediction(emu, obs, [[0.3], [0.6]], seed=1)
        >>> pred.eta.shape, pred.delta.shape, pred.y.shape   # (draws, points, outputs)
        ((40, 2, 1), (40, 2, 1), (40, 2, 1))
        >>> bool(np.all(pred.var("y") > pred.var("zeta")))
        True
    """
    gpmsa_model_only(emulator, "full_prediction")
    if not isinstance(obs, ObsData):
        raise GPMSAError(f"obs must be the gpmsa.ObsData of the calibration, got "
                         f"{type(obs).__name__}")  # fmt: skip
    if posterior is not None and not isinstance(posterior, Posterior):
        raise GPMSAError(f"posterior must be a gpmsa.Posterior, got {type(posterior).__name__}")
    n_rlz = check_count(n_rlz, "n_rlz")
    extrapolate = check_flag(extrapolate, "extrapolate")
    draws = None if draws is None else check_flag(draws, "draws")
    progress = check_flag(progress, "progress")
    rng = rng_of(seed)
    std, K = emulator.standardizer, emulator.K
    scalar = emulator.l_sim == 1
    if posterior is None and not getattr(emulator, "calibration", None):  # before any check
        raise GPMSAError(  # against a joint fit's record, which a simulation-only fit lacks
            "full_prediction needs calibration draws: fit jointly (gpmsa.fit(data, obs, "
            "discrepancy=...)) or pass posterior= from gpmsa.calibrate"
        )
    if isinstance(discrepancy, str) and discrepancy == AS_FITTED:
        discrepancy = _recorded_discrepancy(emulator, posterior)
    elif posterior is None:
        _check_fitted_discrepancy(emulator, discrepancy)
    if posterior is None:
        _check_fitted_obs(getattr(emulator, "settings", None) or {}, obs)
    else:
        check_posterior_emulator(emulator, posterior)
        _check_fitted_obs(getattr(posterior, "info", None) or {}, obs)  # a joint fit's draws
        _check_calibrated_obs(posterior, obs, emulator.x_names, emulator.y_names, std.grid,
                              emulator.index_names)  # fmt: skip
    levels = tuple(emulator.levels)
    obs_grids = obs.output_grids(emulator.index_names)  # a table's columns by name
    x_nat, xu = unit_inputs(x, emulator.x_names, std.x_min, std.x_max, "x", levels[: emulator.p],
                            extrapolate)  # fmt: skip
    paired = posterior is None if draws is None else draws
    idx, sets = _posterior_sets(emulator, posterior, n_draws, paired)
    record = (
        posterior.info if posterior is not None else getattr(emulator, "settings", None)
    ) or {}
    if isinstance(discrepancy_groups, str) and discrepancy_groups == AS_FITTED:
        discrepancy_groups = record.get("discrepancy_groups") if discrepancy is not None else None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the calibration already warned about its x_obs
        check_x(emulator, obs.inputs(emulator.x_names), extrapolate, "obs")  # far: refused
        ob, _ = reduce_obs(obs, std, K, discrepancy, emulator.x_names, levels, emulator.y_names,
                           discrepancy_groups, x_checked=True,
                           index_names=emulator.index_names)  # fmt: skip
    p_v = ob.p_v
    if ("betaV" in sets[0]) != (p_v > 0):
        raise GPMSAError(
            f"the draws {'have' if 'betaV' in sets[0] else 'lack'} discrepancy parameters but "
            f"discrepancy={describe_discrepancy(discrepancy)} gives {p_v} discrepancy basis "
            "vectors"
        )
    drawn = sets[0]["lamVz"].size if p_v else 1
    if drawn != ob.n_groups:
        raise GPMSAError(
            f"the draws have {drawn} discrepancy precision group(s) but discrepancy_groups="
            f"{discrepancy_groups!r} gives {ob.n_groups}: pass the calibration's groups"
        )
    if p_v:  # per-group lamVz priors, one per group
        emulator.priors.lamvz_priors(ob.n_groups)
    fitted = record.get("discrepancy_sha256")  # the joint fit's or calibrate's basis
    recorded = record.get("discrepancy_groups")  # absent beside a digest: one group
    given = None if ob.v_groups is None else list(ob.v_groups)
    if fitted is not None and recorded != given:
        raise GPMSAError(
            f"discrepancy_groups={given} (None: one group) differs from the calibration's "
            f"{recorded}: pass its groups (the default takes them)"
        )
    if fitted is not None and basis_digest(ob.D, ob.v_groups) != fitted:
        raise GPMSAError(
            "the discrepancy basis differs from the one the draws were made with, or its "
            "precision groups do (their recorded SHA-256, normalised on the observations' "
            "grids): pass the calibration's discrepancy= (the same kind, array or list) and "
            "discrepancy_groups="
        )
    if grid_discrepancy is not None:
        if experiment is not None:
            raise GPMSAError("grid_discrepancy= and experiment= both choose delta's basis: "
                             "give one")  # fmt: skip
        kept = getattr(emulator, "discrepancy_bases", None)
        g = _pred_grid(emulator, obs, grid)
        D_pred = _given_on_grid(discrepancy, grid_discrepancy, g, scalar,
                                kept is not None and discrepancy is kept,
                                record.get("discrepancy_scale"))  # fmt: skip
    elif experiment is None:
        g = _pred_grid(emulator, obs, grid)
        D_pred = _pred_discrepancy(discrepancy, obs_grids, std, g, scalar, ob.D)
    else:
        g, D_pred = _experiment_prediction(discrepancy, obs_grids, std, grid, experiment, ob.D,
                                           emulator.index_names)  # fmt: skip
    K_pred = interpolate_basis(K, std.grid, g) if not scalar else K
    N, p_u = xu.shape[0], emulator.p_u
    n_c = p_v + p_u
    S = len(sets)
    check_memory(  # the draws (latents, eta, delta, y, noise) and per draw the joint covariance
        8.0 * S * (n_rlz * N * (n_c + 4 * n_points(g)) + N * n_c * n_c) + 8.0 * 4 * (n_c * N) ** 2,
        f"full_prediction(n_rlz={n_rlz}) at {N} points x {S} draws x {n_points(g)} outputs",
    )
    mu = np.empty((S, N, n_c))
    cov_pt = np.empty((S, N, n_c, n_c))
    lat = np.empty((S, n_rlz, N, n_c))
    with one_thread(), progress_bar(progress, S, "full_prediction") as bar:
        point = None if paired else gp_factors(emulator, emulator.params)
        for i, prm in enumerate(sets):
            fac = point if point is not None else gp_factors(emulator, prm)
            m_i, C_i = _conditional(emulator, ob, prm, fac, xu, p_v, scalar)
            blocks = C_i.reshape(n_c, N, n_c, N)
            cov_pt[i] = np.einsum("cidi->icd", blocks)
            mu[i] = m_i.reshape(n_c, N).T
            A = mvn_factor(C_i)
            r = m_i + rng.standard_normal((n_rlz, n_c * N)) @ A.T
            lat[i] = r.reshape(n_rlz, n_c, N).transpose(0, 2, 1)
            bar.update(1)
    lat = lat.reshape(S * n_rlz, N, n_c)
    v, u = lat[:, :, :p_v], lat[:, :, p_v:]
    lamOs = np.array([prm["lamOs"] for prm in sets])
    sd = std.sd_on(g)  # one sd, or scaled columnwise each element's on g
    eta = (u @ K_pred.T) * sd + std.mean_on(g)
    delta = (v @ D_pred.T) * sd
    noise = rng.standard_normal(eta.shape) / np.sqrt(np.repeat(lamOs, n_rlz))[:, None, None]
    y = eta + delta + noise * sd
    theta = std.t_from_unit(np.array([prm["theta"] for prm in sets]))
    # categorical draws: exactly the level codes (as the posterior's and a joint fit's)
    round_levels(theta, [lv is not None for lv in levels[emulator.p :]])
    return FullPrediction(
        x=x_nat, grid=g, draw_index=idx, theta=theta, lamOs=lamOs, mu=mu, cov=cov_pt,
        u=u, v=v, eta=eta, delta=delta, y=y, K=K_pred, D=D_pred, y_mean=std.mean_on(g),
        y_sd=sd, x_names=tuple(emulator.x_names), x_units=tuple(emulator.x_units),
        index_names=emulator.index_names, index_units=emulator.index_units,
    )  # fmt: skip


def _conditional(emulator, ob, prm, fac, xu_new, p_v, scalar):
    """Mean (n_c N,) and covariance of the weights [v comps; u comps] at the new x (comp-major).

    Prior (per component, over the n observed and N new points): v_k ~ GP(0, R(x; betaV[:, g]) /
    lamVz[g]), g the precision group of basis vector k;
    u_j | w ~ the emulator GP given the runs (nugget 1/lamWs_j on every point; ``fac``: per
    component `gp_factors`' Cholesky factor of Sigma_W_j, Sigma_W_j^-1 w_j and GLS fit); then
    condition on the observations' reduced data z = H [v_obs; u_obs] + N(0, Sigma_obs / lamOs),
    H the identity (vector output) or the sum of the blocks (scalar output: z = u + v + e).
    Categorical inputs take their kernel in u's correlation and, the x ones, in v's (as the
    joint fit's likelihood). With a mean basis h, u_j | w has the GLS mean h c_j + r^T alpha and
    the coefficients' covariance G^T (H^T Sigma_W_j^-1 H)^-1 G, G = h^T - H^T Sigma_W_j^-1 r,
    over the observed and new points together (``Emulator.predict``'s variance; the c_j, flat
    prior, integrated out given w, then conditioned on the observations with the rest).
    """
    n, N, p_u = ob.n, xu_new.shape[0], emulator.p_u
    n_c = p_v + p_u
    P = n + N
    x_all = np.vstack([ob.x, xu_new])
    theta = np.tile(prm["theta"], (P, 1))
    xt_all = np.hstack([x_all, theta])
    means = np.zeros((n_c, P))
    covs = np.empty((n_c, P, P))
    cat = emulator.categorical_mask if extended(emulator) else None
    basis = emulator.mean_basis
    h = None if basis is None else basis.matrix(xt_all)
    if p_v:
        lam_vz, beta_v = prm["lamVz"], prm["betaV"]
        x_cat = None if cat is None else cat[: emulator.p]
        cv = [correlation(x_all, None, beta_v[:, g], x_cat) / lam_vz[g]
              for g in range(lam_vz.size)]  # fmt: skip
        for c, g in enumerate(ob.block_groups):
            covs[c] = cv[g]
    for j, (L, alpha, gls) in enumerate(fac):
        lam = prm["lamUz"][j]
        beta = prm["betaU"][:, j]
        r = correlation(xt_all, emulator.zt, beta, cat) / lam
        B = solve_triangular(L, r.T, lower=True)
        c = correlation(xt_all, None, beta, cat) / lam - B.T @ B
        if gls is not None:  # the GLS coefficients' covariance
            G = h.T - gls.A.T @ B
            c += G.T @ cho_solve(gls.Q, G)
        c[np.diag_indices(P)] += 1.0 / prm["lamWs"][j]
        covs[p_v + j] = c
        means[p_v + j] = r @ alpha
        if gls is not None:
            means[p_v + j] += h @ gls.coef
    o, s = slice(0, n), slice(n, P)
    # H maps the stacked observed latents (n_c n) to the data z.
    if scalar:
        C = sum(covs[c][o, o] for c in range(n_c)) + ob.sig_obs / prm["lamOs"]
        z_res = ob.z - sum(means[c][o] for c in range(n_c))
        cross = np.vstack([covs[c][s, o] for c in range(n_c)])  # (n_c N, n)
    else:
        d = n_c * n
        C = ob.sig_obs / prm["lamOs"]
        cross = np.zeros((n_c * N, d))
        for c in range(n_c):
            C[c * n : (c + 1) * n, c * n : (c + 1) * n] += covs[c][o, o]
            cross[c * N : (c + 1) * N, c * n : (c + 1) * n] = covs[c][s, o]
        z_res = ob.z - means[:, o].reshape(-1)
    L = np.linalg.cholesky(C)
    G = solve_triangular(L, cross.T, lower=True)  # L^-1 cross^T
    a = solve_triangular(L, z_res, lower=True)
    mean = means[:, s].reshape(-1) + G.T @ a
    prior = np.zeros((n_c * N, n_c * N))
    for c in range(n_c):
        prior[c * N : (c + 1) * N, c * N : (c + 1) * N] = covs[c][s, s]
    return mean, prior - G.T @ G
