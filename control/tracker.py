"""Sequential Bayes filter over GD: window likelihoods under a change-point / random-walk prior.

The state is the posterior of the current GD as masses on a grid uniform in log(GD). Each step:

1. predict over the distance ``ds`` travelled since the last step: a Gaussian random walk in
   log(GD) with standard deviation ``drift_per_sqrt_m * sqrt(ds)`` (slow drift of the roughness),
   then a change point with probability ``1 - exp(-ds / mean_segment_m)``, after which GD is
   redrawn from the prior (``TrackerSettings.prior``: uniform on the emulator's domain, the
   paper's eq. 3, or log-uniform);
2. update: multiply by the new window's likelihood of GD raised to a power in (0, 1]. Windows that
   share samples are not independent: the BCR either feeds one tracker only disjoint windows at
   full power (``method="filter"``), or feeds it every overlapping window with its likelihood
   tempered by the fraction of samples that are new since the tracker's last update
   (``method="tempered"``), so each sample's evidence counts about once (`control.bcr`).

``mean_segment_m = 0`` turns the filter into the paper's one-window estimator: every step starts
from the prior.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import gaussian_filter1d
from scipy.special import logsumexp

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
from gpmsa.errors import numbers_text

PRIORS = ("uniform", "log_uniform")


MAX_GRID = 100_000
"""Most nodes of a GDTracker's grid."""


@dataclass(frozen=True)
class TrackerSettings:
    """Settings of the GD filter.

    Attributes:
        mean_segment_m: expected distance between roughness changes, m (change-point hazard
            1/mean_segment_m per metre). 0 means no memory: each estimate uses its window only.
        drift_per_sqrt_m: random-walk standard deviation of log(GD) per sqrt(metre).
        n_grid: grid points, uniform in log(GD) over the domain.
        prior: the prior of GD on the domain, also the law GD is redrawn from at a change point:
            "uniform" (the paper's eq. 3) or "log_uniform" (uniform in log GD: the scale-invariant
            prior of a scale parameter).
    """

    mean_segment_m: float = 25.0
    drift_per_sqrt_m: float = 0.01
    n_grid: int = 400
    prior: str = "uniform"

    def __post_init__(self) -> None:
        require_reals(self, ("mean_segment_m", "drift_per_sqrt_m"))
        require_integers(self, ("n_grid",))
        if not (np.isfinite(self.mean_segment_m) and self.mean_segment_m >= 0):
            raise ControlError(f"mean_segment_m must be finite and >= 0, got {self.mean_segment_m}")
        if not (np.isfinite(self.drift_per_sqrt_m) and self.drift_per_sqrt_m >= 0):
            raise ControlError(
                f"drift_per_sqrt_m must be finite and >= 0, got {self.drift_per_sqrt_m}"
            )
        if not is_choice(self.prior, PRIORS):
            raise ControlError(f"prior must be one of {PRIORS}, got {self.prior!r}")
        if not 16 <= self.n_grid <= MAX_GRID:
            raise ControlError(f"n_grid must lie in [16, {MAX_GRID}], got {self.n_grid}")


class GDTracker:
    """Grid filter for GD on [lo, hi] (native units); see the module docstring."""

    def __init__(self, domain: tuple[float, float], settings: TrackerSettings | None = None):
        pair = tuple(domain) if isinstance(domain, tuple | list | np.ndarray) else ()
        if len(pair) != 2 or not all(is_real(d) for d in pair):
            raise ControlError(f"domain must be a pair (lo, hi) of real numbers, got {domain!r}")
        lo, hi = (float(d) for d in pair)
        if not (np.isfinite(lo) and np.isfinite(hi) and 0 < lo < hi):
            raise ControlError(f"domain must satisfy 0 < lo < hi, both finite, got {domain}")
        self.settings = TrackerSettings() if settings is None else settings
        check_instance(self.settings, "settings", TrackerSettings)
        self.log_grid = np.linspace(np.log(lo), np.log(hi), self.settings.n_grid)
        self.grid = np.exp(self.log_grid)
        if not np.all(np.diff(self.grid) > 0):  # nodes rounded together: no trapezoid weights
            raise ControlError(
                f"domain {(lo, hi)} is too narrow for {self.settings.n_grid} distinct grid nodes: "
                "widen it or lower TrackerSettings.n_grid"
            )
        # node mass = density x trapezoid weight (the end nodes hold half a cell), as the
        # posterior reads it: uniform in GD (density 1) or log-uniform (density 1 / GD)
        self._log_weights = np.log(trapezoid_weights(self.grid))
        log_density = 0.0 * self.log_grid if self.settings.prior == "uniform" else -self.log_grid
        self.log_prior = log_density + self._log_weights
        self.log_prior -= logsumexp(self.log_prior)
        self.reset()

    def reset(self) -> None:
        """Forget everything: back to the prior."""
        self.log_mass = self.log_prior.copy()

    @underflow_as_zero
    def predict(self, ds_m: float) -> None:
        """Propagate the state over ds_m metres travelled (random walk, then change point)."""
        if not (is_real(ds_m) and ds_m >= 0):
            raise ControlError(f"ds_m must be a real number >= 0, got {ds_m!r}")
        s = self.settings
        if s.mean_segment_m == 0 or np.isinf(ds_m):
            self.reset()
            return
        # the walk moves density (mass per trapezoid weight): a flat density stays flat
        log_density = self.log_mass - self._log_weights
        mass = np.exp(log_density - log_density.max())
        sigma_idx = s.drift_per_sqrt_m * np.sqrt(ds_m) / (self.log_grid[1] - self.log_grid[0])
        # beyond ten grids wide the reflected walk is flat on the grid: no wider kernel is needed
        sigma_idx = min(sigma_idx, 10.0 * self.log_grid.size)
        if sigma_idx > 0.05:
            mass = gaussian_filter1d(mass, sigma_idx, mode="reflect", truncate=5.0)
        mass = mass * np.exp(self._log_weights)
        mass /= mass.sum()
        hazard = -np.expm1(-ds_m / s.mean_segment_m)
        mass = (1 - hazard) * mass + hazard * np.exp(self.log_prior)
        self.log_mass = np.log(np.maximum(mass, 1e-300))

    @underflow_as_zero
    def update(self, grid: np.ndarray, loglik: np.ndarray, power: float = 1.0) -> None:
        """Multiply in a likelihood given on any sorted grid of native GD (interpolated in log GD).

        Args:
            grid: (k,) increasing GD values where loglik is known (e.g. the Calibrator's grid),
                spanning the tracker's domain.
            loglik: (k,) log-likelihood values (any additive constant).
            power: tempering exponent in (0, 1]: the likelihood enters as likelihood**power
                (the fraction of the window's samples that are new to this tracker).
        """
        if not (is_real(power) and 0 < power <= 1):
            raise ControlError(f"power must be a real number in (0, 1], got {power!r}")
        grid = float_array(grid, "grid")
        loglik = float_array(loglik, "loglik")
        if grid.ndim != 1 or grid.shape != loglik.shape or grid.size < 2:
            raise ControlError(f"grid/loglik must be 1-D of equal length, got {grid.shape}")
        if not (np.all(np.isfinite(grid)) and grid[0] > 0 and np.all(np.diff(grid) > 0)):
            raise ControlError(f"grid must hold increasing, finite, positive GD values, got {grid}")
        if not np.all(np.isfinite(loglik)):
            raise ControlError("loglik must be finite")
        self._check_covers(grid)
        ll = power * np.interp(self.log_grid, np.log(grid), loglik - loglik.max())
        log_mass = self.log_mass + ll
        self.log_mass = log_mass - logsumexp(log_mass)

    def _check_covers(self, grid: np.ndarray) -> None:
        """ControlError unless the likelihood's ``grid`` spans the tracker's domain (to 1e-9 of
        log GD): beyond its ends the interpolation would hold the end values, a flat likelihood
        the data never gave."""
        lo, hi = self.log_grid[0], self.log_grid[-1]
        tol = 1e-9 * (hi - lo)
        if np.log(grid[0]) > lo + tol or np.log(grid[-1]) < hi - tol:
            first, last, low, high = numbers_text(grid[0], grid[-1], self.grid[0], self.grid[-1])
            raise ControlError(
                f"grid spans GD [{first}, {last}] but the tracker's domain is "
                f"[{low}, {high}]: give the likelihood on a grid that "
                "covers the domain (outside its grid it would be read as flat)"
            )

    def posterior(self, name: str = "GD", n_draws: int = 4000) -> Posterior:
        """The current posterior of GD as a gpmsa Posterior holding the exact grid marginal
        under ``name``.

        The node masses become a density through the grid's trapezoid weights, so the mean and
        sd are the mass-weighted sums; ``samples`` (for histograms) are ``n_draws`` inverse-CDF
        draws with a fixed seed, made only when read.
        """
        check_posterior_name(name)
        check_n_draws(n_draws)
        marginal = GridMarginal.from_log_density(
            self.grid, self.log_mass - self._log_weights, np.exp(self._log_weights)
        )
        return Posterior(
            grids={name: marginal},
            draw=lambda: {name: marginal.sample(np.random.default_rng(0), n_draws)},
            info={"method": "filter", "names": (name,)},
        )
