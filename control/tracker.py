"""Sequential Bayes filter over GD: window likelihoods under a change-point / random-walk prior.

The state is the posterior of the current GD as masses on a grid uniform in log(GD). Each step:

1. predict over the distance ``ds`` travelled since the last step: a Gaussian random walk in
   log(GD) with standard deviation ``drift_per_sqrt_m * sqrt(ds)`` (slow drift of the roughness),
   then a change point with probability ``1 - exp(-ds / mean_segment_m)``, after which GD is
   redrawn from the prior (uniform on the emulator's domain, the paper's eq. 3);
2. update: multiply by the new window's likelihood of GD (windows fed to one tracker must not
   overlap, so that their likelihoods are independent; `control.bcr` sees to that).

``mean_segment_m = 0`` turns the filter into the paper's one-window estimator: every step starts
from the prior.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import gaussian_filter1d
from scipy.special import logsumexp

from control.errors import ControlError
from control.grid_posterior import GridPosterior


@dataclass(frozen=True)
class TrackerSettings:
    """Settings of the GD filter.

    Attributes:
        mean_segment_m: expected distance between roughness changes, m (change-point hazard
            1/mean_segment_m per metre). 0 means no memory: each estimate uses its window only.
        drift_per_sqrt_m: random-walk standard deviation of log(GD) per sqrt(metre).
        n_grid: grid points, uniform in log(GD) over the domain.
    """

    mean_segment_m: float = 25.0
    drift_per_sqrt_m: float = 0.01
    n_grid: int = 400

    def __post_init__(self) -> None:
        if not (np.isfinite(self.mean_segment_m) and self.mean_segment_m >= 0):
            raise ControlError(f"mean_segment_m must be finite and >= 0, got {self.mean_segment_m}")
        if not (np.isfinite(self.drift_per_sqrt_m) and self.drift_per_sqrt_m >= 0):
            raise ControlError(
                f"drift_per_sqrt_m must be finite and >= 0, got {self.drift_per_sqrt_m}"
            )
        if self.n_grid < 16:
            raise ControlError(f"n_grid must be >= 16, got {self.n_grid}")


class GDTracker:
    """Grid filter for GD on [lo, hi] (native units); see the module docstring."""

    def __init__(self, domain: tuple[float, float], settings: TrackerSettings | None = None):
        lo, hi = (float(d) for d in domain)
        if not (np.isfinite(lo) and np.isfinite(hi) and 0 < lo < hi):
            raise ControlError(f"domain must satisfy 0 < lo < hi, got {domain}")
        self.settings = settings or TrackerSettings()
        self.log_grid = np.linspace(np.log(lo), np.log(hi), self.settings.n_grid)
        self.grid = np.exp(self.log_grid)
        # Uniform prior on GD: mass of a log-grid cell is proportional to GD.
        self.log_prior = np.log(self.grid) - logsumexp(np.log(self.grid))
        self.reset()

    def reset(self) -> None:
        """Forget everything: back to the prior."""
        self.log_mass = self.log_prior.copy()

    def predict(self, ds_m: float) -> None:
        """Propagate the state over ds_m metres travelled (random walk, then change point)."""
        if not ds_m >= 0:
            raise ControlError(f"ds_m must be >= 0, got {ds_m}")
        s = self.settings
        if s.mean_segment_m == 0 or np.isinf(ds_m):
            self.reset()
            return
        mass = np.exp(self.log_mass - self.log_mass.max())
        sigma_idx = s.drift_per_sqrt_m * np.sqrt(ds_m) / (self.log_grid[1] - self.log_grid[0])
        if sigma_idx > 0.05:
            mass = gaussian_filter1d(mass, sigma_idx, mode="reflect", truncate=5.0)
        mass /= mass.sum()
        hazard = -np.expm1(-ds_m / s.mean_segment_m)
        mass = (1 - hazard) * mass + hazard * np.exp(self.log_prior)
        self.log_mass = np.log(np.maximum(mass, 1e-300))

    def update(self, grid: np.ndarray, loglik: np.ndarray) -> None:
        """Multiply in a likelihood given on any sorted grid of native GD (interpolated in log GD).

        Args:
            grid: (k,) sorted GD values where loglik is known (e.g. the Calibrator's grid).
            loglik: (k,) log-likelihood values (any additive constant).
        """
        grid = np.asarray(grid, dtype=float)
        loglik = np.asarray(loglik, dtype=float)
        if grid.ndim != 1 or grid.shape != loglik.shape or grid.size < 2:
            raise ControlError(f"grid/loglik must be 1-D of equal length, got {grid.shape}")
        if not np.all(np.isfinite(loglik)):
            raise ControlError("loglik must be finite")
        ll = np.interp(self.log_grid, np.log(grid), loglik - loglik.max())
        log_mass = self.log_mass + ll
        self.log_mass = log_mass - logsumexp(log_mass)

    def posterior(self) -> GridPosterior:
        """The current posterior of GD."""
        return GridPosterior(self.grid, np.exp(self.log_mass - self.log_mass.max()))
