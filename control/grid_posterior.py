"""A posterior of one scalar parameter held as probability masses on a grid."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from control.errors import ControlError


@dataclass(frozen=True, eq=False)
class GridPosterior:
    """Posterior of GD as masses on a sorted grid (exact for the grid; no sampling error).

    Attributes:
        grid: (n,) sorted parameter values, native units (GD, 1e-6 m^3).
        mass: (n,) non-negative probability masses summing to 1.
    """

    grid: np.ndarray
    mass: np.ndarray

    def __post_init__(self) -> None:
        grid = np.asarray(self.grid, dtype=float)
        mass = np.asarray(self.mass, dtype=float)
        if grid.ndim != 1 or grid.shape != mass.shape or grid.size < 2:
            raise ControlError(
                f"grid and mass must be 1-D of equal length >= 2, got {grid.shape} and {mass.shape}"
            )
        if not (np.all(np.isfinite(mass)) and np.all(mass >= 0) and mass.sum() > 0):
            raise ControlError("mass must be finite, non-negative and not all zero")
        if np.any(np.diff(grid) <= 0):
            raise ControlError("grid must be strictly increasing")
        object.__setattr__(self, "grid", grid)
        object.__setattr__(self, "mass", mass / mass.sum())

    def mean(self) -> float:
        """Posterior mean."""
        return float(self.mass @ self.grid)

    def sd(self) -> float:
        """Posterior standard deviation."""
        mu = self.mean()
        return float(np.sqrt(max(self.mass @ (self.grid - mu) ** 2, 0.0)))

    def _cdf_nodes(self) -> np.ndarray:
        """CDF at the grid nodes, each node's mass spread evenly over its two half-cells."""
        return np.cumsum(self.mass) - 0.5 * self.mass

    def cdf(self, value: float | np.ndarray) -> float | np.ndarray:
        """P(GD <= value), linear between nodes (0 below the grid, 1 above)."""
        out = np.interp(np.asarray(value, dtype=float), self.grid, self._cdf_nodes(), 0.0, 1.0)
        return float(out) if out.ndim == 0 else out

    def quantile(self, q: float | np.ndarray) -> float | np.ndarray:
        """Quantile(s) at probability q in [0, 1]: the inverse of `cdf`."""
        q_arr = np.asarray(q, dtype=float)
        if np.any(~np.isfinite(q_arr)) or np.any((q_arr < 0) | (q_arr > 1)):
            raise ControlError(f"q must lie in [0, 1], got {q}")
        out = np.interp(q_arr, self._cdf_nodes(), self.grid)
        return float(out) if out.ndim == 0 else out

    def interval(self, level: float = 0.9) -> tuple[float, float]:
        """Central credible interval with probability `level` in (0, 1)."""
        if not 0 < level < 1:
            raise ControlError(f"level must lie in (0, 1), got {level}")
        lo, hi = self.quantile(np.array([(1 - level) / 2, (1 + level) / 2]))
        return float(lo), float(hi)

    def prob_above(self, value: float) -> float:
        """P(GD > value) = 1 - cdf(value), consistent with `quantile`."""
        return 1.0 - float(self.cdf(value))

    def sample(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """n draws (by inverse CDF on the grid), e.g. for histograms."""
        return np.asarray(self.quantile(rng.uniform(size=n)))
