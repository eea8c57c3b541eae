"""Bayesian online change-point filter over GD: a posterior on (run length, GD) on a grid.

Adams and MacKay (2007) track the run length r since the last change point; here the joint state
P(r, GD | blocks so far) is kept exactly on a grid (run lengths in blocks, each with the distance
it spans; GD uniform in log GD), so that the filter can use a segment-length law with memory and
a jump law that depends on the GD before the change. One step per block, ds metres long:

1. predict: a run of d metres ends within the next ds metres with the hazard
   h(d) = 1 - S(d + ds) / S(d) of a gamma segment-length law (shape k, mean L; k = 1 is the
   memoryless 1 - exp(-ds / L)), d the metres the run spans so far; the mass that ends starts
   a new run (placed at the step's start: it spans the ds metres, as the first run spans its
   first step) with GD redrawn by the jump law T(GD -> GD'): the prior on GD' (log-uniform on
   the domain by default), times a log-normal factor of the ratio GD'/GD (sd ``jump_sd``;
   None: no factor), and zero for |log(GD'/GD)| < ``min_jump`` (a change smaller than that is
   not a change);
2. update: every run length's GD posterior is multiplied by the block's likelihood.

On steady ground the long run holds the mass and pools every block since the change; after a
change the short runs take over within a few blocks. The marginal over r is the GD posterior; the
run-length posterior gives the probability of a recent change.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.special import gammaincc

from control.errors import ControlError
from control.validation import (
    check_instance,
    check_n_draws,
    check_posterior_name,
    float_array,
    is_choice,
    is_real,
    require_integers,
    require_reals,
)
from gpmsa._fp_state import underflow_as_zero
from gpmsa.calibration.posterior import GridMarginal, Posterior, trapezoid_weights

PRIORS = ("log_uniform", "uniform")


@dataclass(frozen=True)
class ChangePointSettings:
    """Settings of the change-point filter (see the module docstring).

    Attributes:
        mean_segment_m: expected distance between roughness changes L, m.
        segment_shape: gamma shape k of the segment length (1: memoryless; 2: short segments
            less likely, hazard rising from 0 to k / L).
        min_jump: smallest |log(GD_new / GD_old)| counted as a change.
        jump_sd: sd of log(GD_new / GD_old) at a change (None: GD_new from the prior alone).
        prior: law of GD at the start and the base of the jump law: "log_uniform" (the
            scale-invariant prior of a scale parameter), "uniform" (the paper's eq. 3), or a
            function of GD (an array of grid values) returning the log prior density there (any
            additive constant; finite where the prior has mass, -inf outside).
        max_runs: run lengths kept (older ones are merged into the last).
    """

    mean_segment_m: float = 40.0
    segment_shape: float = 2.0
    min_jump: float = 0.15
    jump_sd: float | None = 0.5
    prior: str | Callable[[np.ndarray], np.ndarray] = "log_uniform"
    max_runs: int = 300

    def __post_init__(self) -> None:
        require_reals(
            self, ("mean_segment_m", "segment_shape", "min_jump", "jump_sd"), optional=("jump_sd",)
        )
        require_integers(self, ("max_runs",))
        if not (np.isfinite(self.mean_segment_m) and self.mean_segment_m > 0):
            raise ControlError(f"mean_segment_m must be finite and > 0, got {self.mean_segment_m}")
        if not (np.isfinite(self.segment_shape) and self.segment_shape > 0):
            raise ControlError(f"segment_shape must be finite and > 0, got {self.segment_shape}")
        if not (np.isfinite(self.min_jump) and self.min_jump >= 0):
            raise ControlError(f"min_jump must be finite and >= 0, got {self.min_jump}")
        if self.jump_sd is not None and not (np.isfinite(self.jump_sd) and self.jump_sd > 0):
            raise ControlError(f"jump_sd must be None or finite and > 0, got {self.jump_sd}")
        if not (callable(self.prior) or is_choice(self.prior, PRIORS)):
            raise ControlError(f"prior must be one of {PRIORS} or a function, got {self.prior!r}")
        if self.max_runs < 2:  # an integer: require_integers above
            raise ControlError(f"max_runs must be an integer >= 2, got {self.max_runs}")


class ChangePointFilter:
    """The filter on a fixed GD grid (native units, increasing, positive); see the module doc."""

    _survival: tuple[np.ndarray, np.ndarray] | None = None  # (dist, S(dist)): `_survival_now`
    _survival_next: np.ndarray | None = None  # S(dist + ds) of the step under way (`_hazard`)

    def __init__(self, gd: np.ndarray, settings: ChangePointSettings | None = None) -> None:
        gd = _increasing_positive(
            gd, "gd", 3, "an increasing 1-D grid of >= 3 positive, finite values"
        )
        s = ChangePointSettings() if settings is None else settings
        check_instance(s, "settings", ChangePointSettings)
        self.settings = s
        self.gd = gd
        self._weights = trapezoid_weights(gd)
        self.prior = _prior_mass(gd, self._weights, s.prior)
        lg = np.log(gd)
        jump = lg[None, :] - lg[:, None]
        T = self.prior[None, :] * (np.abs(jump) >= s.min_jump)
        with np.errstate(over="ignore", under="ignore"):  # far jumps underflow to 0 as intended
            if s.jump_sd is not None:
                T = T * np.exp(-0.5 * (jump / s.jump_sd) ** 2)
            rows = T.sum(axis=1, keepdims=True)
            if np.any(rows <= 0):
                raise ControlError(
                    f"min_jump = {s.min_jump} with jump_sd = {s.jump_sd} leaves no GD to jump "
                    f"to from some node of the domain [{gd[0]:g}, {gd[-1]:g}]"
                )
            self._jump = T / rows
        self._scale = s.mean_segment_m / s.segment_shape
        self.reset()

    def reset(self) -> None:
        """Back to the prior: no data, run length 0."""
        # (R, G) joint P(r, GD); metres each run length spans, the latest step included
        self._set(self.prior[None, :].copy(), np.zeros(1))
        self._has_data = False

    def _set(self, mass: np.ndarray, dist: np.ndarray) -> None:
        """Take the state (mass, dist). Each step makes new arrays and never changes them (they
        are made read-only), so that `state` can share them and a summary, once computed,
        holds until the next step."""
        mass.flags.writeable = dist.flags.writeable = False
        self._mass, self._dist = mass, dist
        self._summed = None  # `_gd_mass`
        self._within: dict[float, float] = {}  # `prob_change_within` per distance

    def _hazard(self, ds: float) -> np.ndarray:
        """P(a run of d metres ends within the next ds metres), per run length (R,)."""
        k, theta = self.settings.segment_shape, self._scale
        if k == 1.0:
            return np.full(self._dist.size, -np.expm1(-ds / theta))
        s0 = self._survival_now()
        s1 = gammaincc(k, (self._dist + ds) / theta)
        self._survival_next = s1  # (`_survival_of`: most of the next step's s0)
        with np.errstate(invalid="ignore", divide="ignore"):
            h = 1.0 - s1 / s0
        tail = -np.expm1(-ds / theta)  # the hazard's limit for long runs
        return np.clip(np.where(s0 > 1e-250, h, tail), 0.0, 1.0)

    def _survival_now(self) -> np.ndarray:
        """S(d) of the segment-length law at the distances d each run spans (R,): kept from the
        step that made them (`_survival_of`), else computed."""
        kept = self._survival
        if kept is not None and kept[0] is self._dist:
            return kept[1]
        return gammaincc(self.settings.segment_shape, self._dist / self._scale)

    def _survival_of(self, dist: np.ndarray, merged: bool) -> None:
        """Keep S(``dist``) for the next step, ``dist`` the distances a step made from this
        state's (a new run first, then each run's + ds, the last one ``merged`` or not), from
        the S(d + ds) that `_hazard` computed: the same numbers, half the gammaincc calls."""
        k, theta = self.settings.segment_shape, self._scale
        ahead, self._survival_next = self._survival_next, None
        if k == 1.0 or ahead is None or ahead.size + 1 < dist.size:
            return
        survival = np.empty(dist.size)
        survival[0] = gammaincc(k, dist[0] / theta)
        survival[1:] = ahead[: dist.size - 1]
        if merged:  # the merged last run's mean distance
            survival[-1] = gammaincc(k, dist[-1] / theta)
        survival.flags.writeable = False
        self._survival = (dist, survival)

    # predict, relocate and update: masses far from the data underflow to 0 as intended,
    # whatever the caller's np.seterr (one errstate per call, ~1 us; none per run length)
    @underflow_as_zero
    def predict(self, ds_m: float) -> None:
        """Propagate over ds_m metres (change points; GD unchanged within a run)."""
        self._set(*self._predicted(ds_m))

    @underflow_as_zero
    def relocate(self, ds_m: float) -> None:
        """Propagate over ds_m metres moved without data (a robot moved while down): as
        ``predict``, but a run that ended there is followed by GD from the prior, not by a
        jump from the last GD (the ground it ended on is unrelated to the last, and a long
        move holds many changes, not the one ``predict`` allows per step), and starts here, as
        after ``reset`` (where the move ended says nothing of how long ago the ground changed).
        A filter that has seen no block is reset: it holds the prior, a run starting here."""
        if not self._has_data:
            _check_distance(ds_m)
            self.reset()
            return
        self._set(*self._predicted(ds_m, from_prior=True))

    def _predicted(self, ds_m: float, from_prior: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """(mass, dist) after ds_m metres, the filter unchanged. Runs beyond ``max_runs`` are
        merged into the last row at their mass-weighted mean distance, which keeps growing.
        No distance (``ds_m == 0``, a standstill) is no hazard: the state stays as it is (a
        run-length row of no mass per step would push real runs into the merged last row)."""
        _check_distance(ds_m)
        if not self._has_data:  # before any block the prior already is "a new segment"
            return self._mass, self._dist + ds_m
        if ds_m == 0:
            return self._mass, self._dist
        h = self._hazard(ds_m)
        # (h[:, None] * mass).sum(axis=0): the same products summed in the same order (row by
        # row; bit for bit on 3,000 random masses, numpy 2.4), in one pass without the (R, G)
        # product: a third of the time
        ended = np.einsum("r,rg->g", h, self._mass)
        mass = np.empty((self._mass.shape[0] + 1, self.gd.size))
        # the new run: the mass that ended, redrawn (by a jump, or from the prior)
        mass[0] = ended.sum() * self.prior if from_prior else ended @ self._jump
        np.multiply(self._mass, (1.0 - h)[:, None], out=mass[1:])
        dist = np.concatenate([[0.0], self._dist]) + ds_m  # a new run holds the step, as the first
        if from_prior:  # a new segment here, as after `reset`: a move's end tells not its age
            dist[0] = 0.0
        R = self.settings.max_runs
        merged = mass.shape[0] > R
        if merged:
            tail = mass[R - 1 :].sum(axis=1)
            if tail.sum() > 0:
                dist[R - 1] = float(tail @ dist[R - 1 :] / tail.sum())
            mass[R - 1] += mass[R:].sum(axis=0)
            mass, dist = mass[:R], dist[:R]
        mass /= mass.sum()  # (a new array: in place)
        self._survival_of(dist, merged)
        return mass, dist

    @underflow_as_zero
    def update(self, loglik: np.ndarray, ds_m: float) -> None:
        """One block ds_m metres long with log-likelihood ``loglik`` on the grid (G,). All or
        nothing: a refused block leaves the filter as it was."""
        loglik = np.asarray(loglik)  # (numbers only: the dtype is checked before isfinite)
        if (loglik.dtype.kind not in "iuf" or loglik.shape != self.gd.shape
                or not np.all(np.isfinite(loglik))):  # fmt: skip
            raise ControlError(f"loglik must hold {self.gd.size} finite values")
        loglik = loglik.astype(float, copy=False)
        mass, dist = self._predicted(ds_m)
        mass = mass * np.exp(loglik - loglik.max())[None, :]
        total = mass.sum()
        if not total > 0:
            raise ControlError(
                "the block's likelihood has no mass where the filter's prediction has: their "
                "product underflows on every grid node (the block contradicts the prior or the "
                "estimate so far)"
            )
        mass /= total  # (the product above is a new array: in place)
        self._set(mass, dist)
        self._has_data = True

    def state(self) -> tuple:
        """The filter's state (for `restore`): its arrays are read-only, and later steps make
        new ones, so the state stays as taken."""
        return self._mass, self._dist, self._has_data

    def restore(self, state: tuple) -> None:
        """Return to a state taken by `state` (e.g. to undo a block found suspect later).
        ControlError for anything else (e.g. a state of a filter on another GD grid)."""
        try:
            mass, dist, has_data = state
            mass, dist = np.array(mass, dtype=float), np.array(dist, dtype=float)
        except (TypeError, ValueError) as exc:
            raise ControlError(
                f"state must be one taken by ChangePointFilter.state(): {exc}"
            ) from None
        if not (
            dist.ndim == 1 and dist.size >= 1 and mass.shape == (dist.size, self.gd.size)
            and isinstance(has_data, bool | np.bool_)
        ):  # fmt: skip
            raise ControlError(
                f"state must be one taken by ChangePointFilter.state() of a filter on this GD "
                f"grid: run-length masses ({dist.size if dist.ndim == 1 else 'R'}, "
                f"{self.gd.size}), their distances and a has_data flag, got masses of shape "
                f"{mass.shape}, distances of shape {dist.shape} and has_data {has_data!r:.40}"
            )
        self._set(mass, dist)
        self._has_data = bool(has_data)

    @property
    def has_data(self) -> bool:
        """Whether any block has updated the filter since its reset."""
        return self._has_data

    @property
    def gd_mass(self) -> np.ndarray:
        """Posterior mass of GD per grid node (G,)."""
        return self._gd_mass().copy()

    def _gd_mass(self) -> np.ndarray:
        """`gd_mass`, computed once a step (read-only: it is shared)."""
        if self._summed is None:
            self._summed = self._mass.sum(axis=0)
            self._summed.flags.writeable = False
        return self._summed

    def prob_change_within(self, distance_m: float) -> float:
        """P(the current segment began within the last ``distance_m`` metres)."""
        if not (is_real(distance_m) and distance_m >= 0):  # (NaN fails the comparison)
            raise ControlError(f"distance_m must be a distance >= 0, m, got {distance_m!r}")
        if not self._has_data:
            return float("nan")
        key = float(distance_m)
        if key not in self._within:  # (computed once a step: the BCR asks for every phase)
            self._within[key] = float(min(1.0, self._mass[self._dist <= key].sum()))
        return self._within[key]

    def mass_by_run(self, edges_m) -> np.ndarray:
        """GD mass per run-length class: row i holds the runs that began more than
        ``edges_m[i-1]`` and at most ``edges_m[i]`` metres ago (row 0 from 0, so that its mass is
        `prob_change_within` of ``edges_m[0]``; the last row beyond ``edges_m[-1]``); the rows
        sum to `gd_mass`. ``edges_m``: increasing, positive, finite, m. Needs a block (before
        any, the filter holds the prior and no run length, as `prob_change_within` says)."""
        if not self._has_data:
            raise ControlError("mass_by_run: no block has been used yet")
        edges = _increasing_positive(
            edges_m, "edges_m", 1, "increasing, positive, finite distances (m)"
        )
        cls = np.searchsorted(edges, self._dist, side="left")  # run length -> class
        out = np.zeros((edges.size + 1, self.gd.size))
        np.add.at(out, cls, self._mass)
        return out

    def expected_run_m(self) -> float:
        """Posterior mean of the distance since the last change, m."""
        with np.errstate(under="ignore"):  # runs of (near) no mass
            return float(self._mass.sum(axis=1) @ self._dist)

    def posterior(self, name: str = "GD", n_draws: int = 4000) -> Posterior:
        """The GD posterior as a gpmsa Posterior holding the grid marginal under ``name``;
        ``samples`` are ``n_draws`` draws with a fixed seed, made only when read."""
        return _grid_posterior(self.gd, self._weights, self._gd_mass(), name, n_draws)


def mixture_posterior(
    filters: list[ChangePointFilter], weights, name: str = "GD", n_draws: int = 4000
) -> Posterior:
    """The mixture of the GD posteriors of filters on one GD grid, with (positive) weights."""
    if not isinstance(filters, list | tuple):
        raise ControlError(f"filters must be a list of ChangePointFilters, got {filters!r:.60}")
    for i, f in enumerate(filters):
        check_instance(f, f"filters[{i}]", ChangePointFilter)
    try:
        w = np.asarray(weights, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ControlError(
            f"weights must be one finite positive number per filter: {exc}"
        ) from None
    if not filters or w.shape != (len(filters),) or not np.all(np.isfinite(w) & (w > 0)):
        raise ControlError(
            f"mixture_posterior needs one finite positive weight per filter: {len(filters)} "
            f"filter(s), weights {w.tolist()}"
        )
    if any(not np.array_equal(f.gd, filters[0].gd) for f in filters[1:]):
        raise ControlError("mixture_posterior needs filters on one GD grid")
    with np.errstate(under="ignore"):  # (the BCR's own call is inside BCR.update's)
        return _mixture_posterior(filters, w, name, n_draws)


def _mixture_posterior(
    filters: list[ChangePointFilter], w: np.ndarray, name: str = "GD", n_draws: int = 4000
) -> Posterior:
    """`mixture_posterior` of filters and weights (an array) known to fit (the BCR's own)."""
    mass = (w[:, None] * np.array([f._gd_mass() for f in filters])).sum(axis=0) / w.sum()
    return _grid_posterior(filters[0].gd, filters[0]._weights, mass, name, n_draws)


def _grid_posterior(gd, weights, mass, name: str, n_draws: int) -> Posterior:
    check_posterior_name(name)
    check_n_draws(n_draws)
    with np.errstate(divide="ignore"):
        log_density = np.log(mass) - np.log(weights)
    marginal = GridMarginal.from_log_density(gd, log_density, weights)
    return Posterior(
        grids={name: marginal},
        draw=lambda: {name: marginal.sample(np.random.default_rng(0), n_draws)},
        info={"method": "changepoint", "names": (name,)},
    )


def _increasing_positive(values, name: str, min_size: int, what: str) -> np.ndarray:
    """``values`` as a 1-D float array of >= ``min_size`` increasing, positive, finite values;
    otherwise a ControlError saying it must be ``what``."""
    a = float_array(values, name)
    if not (
        a.ndim == 1 and a.size >= min_size and np.all(np.isfinite(a)) and a[0] > 0
        and np.all(np.diff(a) > 0)
    ):  # fmt: skip
        raise ControlError(f"{name} must be {what}, got {a}")
    return a


def _check_distance(ds_m) -> None:
    """ControlError unless ``ds_m`` is a finite distance >= 0, m."""
    if not (is_real(ds_m) and np.isfinite(ds_m) and ds_m >= 0):
        raise ControlError(f"ds_m must be finite and >= 0, got {ds_m!r}")


def _prior_mass(gd: np.ndarray, weights: np.ndarray, prior) -> np.ndarray:
    """Prior mass per grid node: the density (1/GD for log-uniform, 1 for uniform, or exp of
    the user's log density) times the node's trapezoid weight, normalised."""
    if callable(prior):
        given = prior(gd.copy())  # its own errors propagate as raised
        try:
            raw = np.asarray(given)
        except (TypeError, ValueError) as exc:  # e.g. a ragged list
            raise ControlError(f"prior(gd) must return real log densities: {exc}") from None
        # numbers only (as gpmsa's log_prior): a mask is no log density, nor is text
        log_density = raw.astype(float) if raw.dtype.kind in "iuf" else None
        if log_density is None:
            got = "None" if given is None else f"{raw.dtype.name} values"
            hint = (
                " (a mask? return 0.0 where allowed, -inf elsewhere)" if raw.dtype == bool else ""
            )
            raise ControlError(f"prior(gd) must return real log densities, got {got}{hint}")
        if log_density.shape != gd.shape or np.any(np.isnan(log_density)):
            raise ControlError(
                f"prior(gd) must return {gd.size} log densities (no NaN), got shape "
                f"{log_density.shape}"
            )
        if np.any(log_density == np.inf) or not np.any(np.isfinite(log_density)):
            raise ControlError("prior(gd) must be finite somewhere and never +inf")
        with np.errstate(under="ignore"):  # far below its peak the density is 0
            density = np.exp(log_density - np.max(log_density[np.isfinite(log_density)]))
    else:
        density = 1.0 / gd if prior == "log_uniform" else np.ones_like(gd)
    with np.errstate(under="ignore"):  # (and so is the mass)
        mass = density * weights
        if np.count_nonzero(mass > 0) < 2:  # e.g. -inf but at one node, or an underflow
            node = float(gd[int(np.argmax(mass))])
            raise ControlError(
                f"prior(gd) puts all its mass on one grid node (GD {node:g}): a change would "
                "have nowhere to go; give a log density that is finite on more of the grid and "
                "varies by far less than 700 across it"
            )
        return mass / mass.sum()
