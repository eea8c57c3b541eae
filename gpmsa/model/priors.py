"""Prior distributions, bounds and default initial values (GPM/SA defaults, each overridable)."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, replace

import numpy as np

from gpmsa.errors import GPMSAError

PRECISIONS = ("lamVz", "lamUz", "lamWs", "lamWOs", "lamOs")


@dataclass(frozen=True)
class GammaPrior:
    """Gamma(shape a, rate b) prior on a precision, with open bounds (lower, upper)."""

    a: float
    b: float
    lower: float = 0.0
    upper: float = float("inf")

    def __post_init__(self) -> None:
        if not (self.a > 0 and self.b > 0):
            raise GPMSAError(f"Gamma prior needs a > 0 and b > 0, got a={self.a}, b={self.b}")
        if not (0 <= self.lower < self.upper):
            raise GPMSAError(
                f"Gamma bounds need 0 <= lower < upper, got {self.lower}, {self.upper}"
            )

    def log_density(self, x: np.ndarray) -> float:
        """Unnormalised log density summed over elements; -inf outside the open bounds."""
        x = np.asarray(x)
        if np.any(x <= self.lower) or np.any(x >= self.upper):
            return -np.inf
        return float(np.sum((self.a - 1.0) * np.log(x) - self.b * x))


@dataclass(frozen=True)
class Priors:
    """GPM/SA priors (Gamma in shape/rate form); data corrections are added by ``with_data``.

    theta (unit scale): Normal(theta_mean, theta_sd) truncated to (0, 1).
    betaU, betaV: Beta(rho_a, rho_b) on rho = exp(-beta/4), rho capped at ``rho_cap`` in the
    density; beta in (0, inf). Precisions: Gamma priors below. ``lamWOs`` and ``lamOs`` here are
    the base priors before the data corrections of GPM/SA (see ``with_data``).
    """

    theta_mean: float = 0.5
    theta_sd: float = 10.0
    rho_a: float = 1.0
    rho_b: float = 0.1
    rho_cap: float = 0.999
    lamVz: GammaPrior = field(default_factory=lambda: GammaPrior(1.0, 1e-3))
    lamUz: GammaPrior = field(default_factory=lambda: GammaPrior(5.0, 5.0, 0.3))
    lamWs: GammaPrior = field(default_factory=lambda: GammaPrior(3.0, 3e-3, 60.0, 1e5))
    lamWOs: GammaPrior = field(default_factory=lambda: GammaPrior(5.0, 5e-3, 60.0, 1e5))
    lamOs: GammaPrior = field(default_factory=lambda: GammaPrior(1.0, 1e-3))
    corrected: bool = False

    def with_data(self, wos: tuple[float, float], os: tuple[float, float] = (0.0, 0.0)) -> Priors:
        """Add GPM/SA's data corrections (delta a, delta b) to the lamWOs and lamOs priors.

        lamWOs: a += (l_sim - p_u) m / 2, b += ||Y - W K^T||^2 / 2;
        lamOs: a += (obs elements - rank) / 2, b += residual SS / 2. Applied once.
        """
        if self.corrected:
            return self
        lw, lo = self.lamWOs, self.lamOs
        return replace(
            self,
            lamWOs=replace(lw, a=lw.a + wos[0], b=lw.b + wos[1]),
            lamOs=replace(lo, a=lo.a + os[0], b=lo.b + os[1]),
            corrected=True,
        )

    def to_dict(self) -> dict:
        """JSON-able dict (infinite bounds as the string "inf")."""
        d = asdict(self)
        for name in PRECISIONS:
            d[name] = {k: ("inf" if v == float("inf") else v) for k, v in d[name].items()}
        return d

    @classmethod
    def from_dict(cls, d: dict) -> Priors:
        """Inverse of ``to_dict``."""
        kw = dict(d)
        for name in PRECISIONS:
            kw[name] = GammaPrior(**{k: float(v) for k, v in d[name].items()})
        return cls(**kw)

    def log_theta(self, theta: np.ndarray) -> float:
        """Log prior of theta (unit scale); -inf outside (0, 1)."""
        theta = np.asarray(theta)
        if np.any(theta <= 0.0) or np.any(theta >= 1.0):
            return -np.inf
        return float(-0.5 * np.sum(((theta - self.theta_mean) / self.theta_sd) ** 2))

    def log_beta(self, beta: np.ndarray) -> float:
        """Log prior of correlation parameters beta via rho = exp(-beta/4); -inf unless beta > 0."""
        beta = np.asarray(beta)
        if np.any(beta <= 0.0) or np.any(~np.isfinite(beta)):
            return -np.inf
        rho = np.minimum(np.exp(-0.25 * beta), self.rho_cap)
        return float(np.sum((self.rho_a - 1.0) * np.log(rho) + (self.rho_b - 1.0) * np.log1p(-rho)))

    def scalar_log_prior(self, name: str):
        """A fast function float -> float: the log prior of one element of ``name``."""
        if name == "theta":
            mu, sd = self.theta_mean, self.theta_sd

            def f(x: float) -> float:
                return -0.5 * ((x - mu) / sd) ** 2 if 0.0 < x < 1.0 else -math.inf

        elif name in ("betaU", "betaV"):
            a1, b1, cap = self.rho_a - 1.0, self.rho_b - 1.0, self.rho_cap

            def f(x: float) -> float:
                if not 0.0 < x < math.inf:
                    return -math.inf
                rho = min(math.exp(-0.25 * x), cap)
                return a1 * math.log(rho) + b1 * math.log1p(-rho)

        elif name in PRECISIONS:
            g = getattr(self, name)
            a1, b, lo, hi = g.a - 1.0, g.b, g.lower, g.upper

            def f(x: float) -> float:
                return a1 * math.log(x) - b * x if lo < x < hi else -math.inf

        else:
            raise GPMSAError(f"unknown parameter name {name!r}")
        return f

    def log_prior(self, name: str, value: np.ndarray) -> float:
        """Log prior of parameter ``name`` at ``value`` (any shape)."""
        if name == "theta":
            return self.log_theta(value)
        if name in ("betaU", "betaV"):
            return self.log_beta(value)
        if name in PRECISIONS:
            return getattr(self, name).log_density(value)
        raise GPMSAError(f"unknown parameter name {name!r}")
