"""Prior distributions, bounds and default initial values (GPM/SA defaults, each overridable)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field, fields, replace
from typing import TYPE_CHECKING

import numpy as np

from gpmsa.errors import GPMSAError

PRECISIONS = ("lamVz", "lamUz", "lamWs", "lamWOs", "lamOs")
RHOV = ("rhoV_a", "rhoV_b")
"""betaV's own Beta prior on rho (GPM/SA's priors.rhoV); unset: betaU's."""
MAX_PRIOR_SHAPE = 1e12
"""Largest Gamma shape a of a prior (the data corrections give (l_sim - p_u) m / 2; a shape of
1e30 would make the lamOs quadrature ask for petabytes); emulator files are held to it too."""


def theta_prior_overflow(theta_mean: float, theta_sd: float) -> tuple[str, str] | None:
    """(field, why) where theta's Normal(theta_mean, theta_sd) on (0, 1) (both finite,
    theta_sd > 0) has no float64 density: its precision 1/theta_sd**2, or its exponent
    ((theta - theta_mean) / theta_sd)**2 at the end of (0, 1) farther from theta_mean, not a
    finite number (the prior would be zero everywhere but at theta_mean, or everywhere); None
    where it has one."""
    var = theta_sd * theta_sd
    if var == 0.0 or not math.isfinite(1.0 / var):
        return "theta_sd", (
            f"{theta_sd!r} is too small: its precision 1/theta_sd**2 is beyond float64 "
            "(theta_sd must exceed about 7.5e-155; hold theta at a value with fixed= instead)"
        )
    z = (abs(theta_mean - 0.5) + 0.5) / theta_sd
    if not math.isfinite(z * z):
        return "theta_mean", (
            f"{theta_mean!r} is too far from (0, 1) for theta_sd {theta_sd!r}: "
            "((theta - theta_mean) / theta_sd)**2 is beyond float64 there, so the prior is zero "
            "everywhere"
        )
    return None


def _real(obj, name: str) -> float:
    """Field ``name`` of ``obj`` as a float, stored back; GPMSAError unless a real number."""
    value = getattr(obj, name)
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        raise GPMSAError(
            f"{type(obj).__name__}.{name} must be a real number, got {value!r} "
            f"({type(value).__name__})"
        )
    object.__setattr__(obj, name, float(value))
    return float(value)


def _float(value, name: str) -> float:
    """A number of ``Priors.from_dict`` (the string "inf" is infinity, as ``to_dict`` writes
    it); GPMSAError naming the field otherwise."""
    if isinstance(value, str) and value == "inf":
        return math.inf
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        raise GPMSAError(f"Priors.from_dict: {name} must be a number, got {value!r}")
    return float(value)


@dataclass(frozen=True)
class GammaPrior:
    """Gamma(shape a, rate b) prior on a precision, with open bounds (lower, upper).

    Allowed: 0 < a <= ``MAX_PRIOR_SHAPE``, 0 < b finite, 0 <= lower < upper, lower finite.
    """

    a: float
    b: float
    lower: float = 0.0
    upper: float = float("inf")

    def __post_init__(self) -> None:
        a, b, lower, upper = (_real(self, k) for k in ("a", "b", "lower", "upper"))
        if not (0 < a <= MAX_PRIOR_SHAPE and 0 < b < math.inf):
            raise GPMSAError(
                f"Gamma prior needs 0 < a <= {MAX_PRIOR_SHAPE:g} and b > 0 finite, got a={a}, b={b}"
            )
        if not (0 <= lower < upper and lower < math.inf):
            raise GPMSAError(f"Gamma bounds need 0 <= lower < upper, got {lower}, {upper}")

    def log_density(self, x: np.ndarray) -> float:
        """Unnormalised log density summed over elements; -inf outside the open bounds (a NaN
        is outside them)."""
        x = np.asarray(x)
        if not np.all((x > self.lower) & (x < self.upper)):
            return -np.inf
        return float(np.sum((self.a - 1.0) * np.log(x) - self.b * x))


@dataclass(frozen=True)
class Priors:
    """GPM/SA priors (Gamma in shape/rate form); data corrections are added by ``with_data``.

    theta (unit scale): Normal(theta_mean, theta_sd) truncated to (0, 1). ``theta_mean``,
    ``theta_sd``: numbers (one prior shared by every calibration parameter), or sequences of
    one number per calibration parameter (stored as tuples; element k gets the k-th; SEPIA's
    ``model.params.theta.prior.params``), which a model checks against its q; one of them a
    number and the other a sequence: the number is shared. theta_mean finite, theta_sd finite
    and > 0. A categorical theta element's prior is uniform over its levels whatever its entry
    here; a hierarchical study element's is its group's.
    betaU: Beta(rho_a, rho_b) on rho = exp(-beta/4), rho capped at ``rho_cap`` in the density;
    beta in (0, inf). betaV: Beta(rhoV_a, rhoV_b) likewise (GPM/SA's priors.rhoV), under the same
    cap; None for both (the default): betaU's Beta(rho_a, rho_b). ``rhoV_a``, ``rhoV_b``: both
    numbers (shared by every discrepancy precision group) or both sequences of one number per
    group (stored as tuples; group g's column betaV[:, g] gets the g-th pair), each finite and
    > 0. Precisions: a ``GammaPrior(a, b, lower, upper)`` each, by default GPM/SA's:
    ``lamUz`` (the weights' GP precision) Gamma(5, 5) above 0.3, ``lamWs`` (their nugget's
    precision) Gamma(3, 0.003) and ``lamWOs`` (the runs' residual precision) Gamma(5, 0.005),
    both within (60, 1e5), ``lamOs`` (the observation precision's scale) and ``lamVz`` (the
    discrepancy's precision) Gamma(1, 0.001). ``lamWOs`` and ``lamOs`` here are the base
    priors before the data corrections of GPM/SA (see ``with_data``); ``gpmsa.fit`` refuses
    corrected priors (``corrected=True``, e.g. an Emulator's ``priors``).
    ``lamVz``: one GammaPrior shared by every discrepancy precision group, or a sequence of them
    (stored as a tuple), one per group, as GPM/SA's per-group rows of priors.lamVz.params:
    group g's lamVz[g] gets the g-th; a model with a discrepancy of G groups needs G of them.
    """

    theta_mean: float | tuple[float, ...] = 0.5
    theta_sd: float | tuple[float, ...] = 10.0
    rho_a: float = 1.0
    rho_b: float = 0.1
    rho_cap: float = 0.999
    lamVz: GammaPrior | tuple[GammaPrior, ...] = field(
        default_factory=lambda: GammaPrior(1.0, 1e-3)
    )
    lamUz: GammaPrior = field(default_factory=lambda: GammaPrior(5.0, 5.0, 0.3))
    lamWs: GammaPrior = field(default_factory=lambda: GammaPrior(3.0, 3e-3, 60.0, 1e5))
    lamWOs: GammaPrior = field(default_factory=lambda: GammaPrior(5.0, 5e-3, 60.0, 1e5))
    lamOs: GammaPrior = field(default_factory=lambda: GammaPrior(1.0, 1e-3))
    corrected: bool = False
    rhoV_a: float | tuple[float, ...] | None = None
    rhoV_b: float | tuple[float, ...] | None = None

    if TYPE_CHECKING:  # what the constructor takes (sequences, stored as tuples)

        def __init__(
            self,
            theta_mean: float | Sequence[float] = 0.5,
            theta_sd: float | Sequence[float] = 10.0,
            rho_a: float = 1.0,
            rho_b: float = 0.1,
            rho_cap: float = 0.999,
            lamVz: GammaPrior | Sequence[GammaPrior] = ...,
            lamUz: GammaPrior = ...,
            lamWs: GammaPrior = ...,
            lamWOs: GammaPrior = ...,
            lamOs: GammaPrior = ...,
            corrected: bool = False,
            rhoV_a: float | Sequence[float] | None = None,
            rhoV_b: float | Sequence[float] | None = None,
        ) -> None: ...

    def __post_init__(self) -> None:
        self._check_theta()
        allowed = {"rho_a": "finite and > 0", "rho_b": "finite and > 0", "rho_cap": "in (0, 1)"}
        for name, rule in allowed.items():
            v = _real(self, name)
            ok = 0 < v < 1 if name == "rho_cap" else math.isfinite(v) and v > 0
            if not ok:
                raise GPMSAError(f"Priors.{name} must be {rule}, got {v}")
        object.__setattr__(self, "lamVz", as_group_priors(self.lamVz, "Priors.lamVz"))
        for name in PRECISIONS:
            if name != "lamVz" and not isinstance(getattr(self, name), GammaPrior):
                raise GPMSAError(f"Priors.{name} must be a gpmsa.GammaPrior, got "
                                 f"{getattr(self, name)!r}")  # fmt: skip
        if not isinstance(self.corrected, bool):
            raise GPMSAError(f"Priors.corrected must be True or False, got {self.corrected!r}")
        self._check_rhov()

    def _check_theta(self) -> None:
        """theta_mean (finite), theta_sd (finite, > 0): each a float, or a tuple of floats (one
        per calibration parameter), both tuples of equal length; every (mean, sd) pair with a
        float64 density (``theta_prior_overflow``); GPMSAError naming the field otherwise."""
        m = _theta_values(self.theta_mean, "Priors.theta_mean", "finite", math.isfinite)
        s = _theta_values(self.theta_sd, "Priors.theta_sd", "finite and > 0",
                          lambda v: math.isfinite(v) and v > 0)  # fmt: skip
        if isinstance(m, tuple) and isinstance(s, tuple) and len(m) != len(s):
            raise GPMSAError(
                f"Priors.theta_mean gives {len(m)} per-element value(s) but Priors.theta_sd "
                f"{len(s)}: give one of each per calibration parameter (or a number, shared)"
            )
        object.__setattr__(self, "theta_mean", m)
        object.__setattr__(self, "theta_sd", s)
        for k in range(self.theta_count or 1):
            bad = theta_prior_overflow(*self.theta_prior(k))
            if bad is not None:
                where = f"[{k}]" if self.theta_count else ""
                raise GPMSAError(f"Priors.{bad[0]}{where} = {bad[1]}")

    @property
    def theta_count(self) -> int | None:
        """The number of calibration parameters per-element theta priors are for (the length of
        theta_mean or theta_sd given as a sequence); None where one prior is shared by all."""
        for v in (self.theta_mean, self.theta_sd):
            if isinstance(v, tuple):
                return len(v)
        return None

    def theta_prior(self, element: int) -> tuple[float, float]:
        """(mean, sd) of the truncated normal prior of unit-scale theta element ``element``."""
        m, s = self.theta_mean, self.theta_sd
        return (m[element] if isinstance(m, tuple) else m,
                s[element] if isinstance(s, tuple) else s)  # fmt: skip

    def theta_moments(self, q: int | None = None, elements=None):
        """(mean, sd) of theta's truncated normal priors: the two floats where one prior is
        shared by every element (so that such priors compute as they always have), else two
        float arrays (q,) (each element's), or their ``elements`` (an index or index list).
        ``q``: the model's number of calibration parameters, checked against per-element priors
        (GPMSAError naming the field and both counts); None: not checked."""
        n = self.theta_count
        if n is None:
            return self.theta_mean, self.theta_sd
        if q is not None and n != q:
            field = "theta_mean" if isinstance(self.theta_mean, tuple) else "theta_sd"
            raise GPMSAError(
                f"Priors.{field} gives {n} per-element theta prior(s) but the model has q = {q} "
                "calibration parameter(s): give one value per calibration parameter (in "
                "t_names' order), or one number shared by all"
            )
        m, s = (np.broadcast_to(np.asarray(v, dtype=np.float64), (n,))
                for v in (self.theta_mean, self.theta_sd))  # fmt: skip
        if elements is None:
            return m.copy(), s.copy()
        return m[elements], s[elements]

    def _check_rhov(self) -> None:
        """rhoV_a, rhoV_b: both None, both numbers or both sequences of equal length (stored as
        floats or tuples of floats), each finite and > 0; GPMSAError naming the field."""
        a, b = self.rhoV_a, self.rhoV_b
        if (a is None) != (b is None):
            raise GPMSAError(
                "Priors.rhoV_a and Priors.rhoV_b set betaV's Beta prior together: give both, or "
                f"neither (betaV then has betaU's Beta(rho_a, rho_b)), got rhoV_a={a!r:.60}, "
                f"rhoV_b={b!r:.60}"
            )
        if a is None:
            return
        va, vb = _rho_values(a, "Priors.rhoV_a"), _rho_values(b, "Priors.rhoV_b")
        if isinstance(va, tuple) != isinstance(vb, tuple) or (
            isinstance(va, tuple) and len(va) != len(vb)
        ):
            raise GPMSAError(
                "Priors.rhoV_a and Priors.rhoV_b must both be numbers (shared by every "
                "discrepancy precision group) or both sequences of one number per group, of "
                f"equal length, got rhoV_a={a!r:.60}, rhoV_b={b!r:.60}"
            )
        object.__setattr__(self, "rhoV_a", va)
        object.__setattr__(self, "rhoV_b", vb)

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

    @property
    def per_group(self) -> bool:
        """Whether ``lamVz`` holds one prior per discrepancy precision group (a tuple)."""
        return isinstance(self.lamVz, tuple)

    def lamvz_priors(self, n_groups: int) -> tuple[GammaPrior, ...]:
        """The lamVz prior of each of ``n_groups`` discrepancy precision groups: the shared one
        repeated, or the per-group ones; GPMSAError naming both counts when they differ."""
        if not self.per_group:
            return (self.lamVz,) * n_groups
        if len(self.lamVz) != n_groups:
            raise GPMSAError(
                f"Priors.lamVz gives {len(self.lamVz)} per-group prior(s) but the discrepancy has "
                f"{n_groups} precision group(s) (discrepancy_groups): give one GammaPrior per "
                "group, or one GammaPrior shared by all"
            )
        return self.lamVz

    @property
    def rhov_per_group(self) -> bool:
        """Whether ``rhoV_a``, ``rhoV_b`` hold one Beta prior per discrepancy precision group."""
        return isinstance(self.rhoV_a, tuple)

    def rhov_priors(self, n_groups: int) -> tuple[tuple[float, float], ...]:
        """(a, b) of betaV's Beta prior on rho for each of ``n_groups`` discrepancy precision
        groups: betaU's (rho_a, rho_b) where rhoV is unset, the shared pair repeated, or the
        per-group pairs; GPMSAError naming both counts when they differ."""
        if not self.rhov_per_group:
            return (self.rho_prior("betaV"),) * n_groups
        if len(self.rhoV_a) != n_groups:
            raise GPMSAError(
                f"Priors.rhoV_a, rhoV_b give {len(self.rhoV_a)} per-group prior(s) but the "
                f"discrepancy has {n_groups} precision group(s) (discrepancy_groups): give one "
                "number per group in each, or one number shared by all"
            )
        return tuple(zip(self.rhoV_a, self.rhoV_b, strict=True))

    def rho_prior(self, name: str, element: int = 0) -> tuple[float, float]:
        """(a, b) of the Beta prior on rho = exp(-beta/4) of column ``element`` of ``name``
        (betaU or betaV; betaV's column g is precision group g's, whose prior may be its own)."""
        if name == "betaU" or self.rhoV_a is None:
            return self.rho_a, self.rho_b
        if not self.rhov_per_group:
            return self.rhoV_a, self.rhoV_b
        if not 0 <= element < len(self.rhoV_a):
            raise GPMSAError(
                f"Priors.rhoV_a, rhoV_b give {len(self.rhoV_a)} per-group prior(s); there is none "
                f"for group {element}: give one number per discrepancy precision group"
            )
        return self.rhoV_a[element], self.rhoV_b[element]

    def rho_arrays(self, name: str, n_groups: int):
        """(a, b) of the Beta priors on rho of ``name`` (betaU or betaV): floats where one prior
        covers every element, else arrays (n_groups,) along betaV's last axis (its groups)."""
        if name == "betaV" and self.rhov_per_group:
            a, b = zip(*self.rhov_priors(n_groups), strict=True)
            return np.array(a), np.array(b)
        return self.rho_prior(name)

    def precision_prior(self, name: str, element: int = 0) -> GammaPrior:
        """The Gamma prior of element ``element`` of precision ``name``: lamVz[g]'s is the g-th
        of per-group priors; every other element shares its parameter's one prior."""
        g = getattr(self, name)
        if not isinstance(g, tuple):
            return g
        if not 0 <= element < len(g):
            raise GPMSAError(
                f"Priors.lamVz gives {len(g)} per-group prior(s); there is none for group "
                f"{element}: give one GammaPrior per discrepancy precision group"
            )
        return g[element]

    def gamma_arrays(self, name: str, size: int) -> tuple[np.ndarray, ...]:
        """(a, b, lower, upper), each (size,): the Gamma prior of each of ``size`` elements of
        precision ``name`` (lamVz's per-group priors one per element, ``lamvz_priors``)."""
        gs = self.lamvz_priors(size) if name == "lamVz" else (getattr(self, name),) * size
        return tuple(np.array([getattr(g, k) for g in gs]) for k in ("a", "b", "lower", "upper"))

    def to_dict(self) -> dict:
        """JSON-able dict (infinite bounds as the string "inf"); per-group lamVz priors as a
        list of such dicts, one per group; rhoV_a, rhoV_b only where set (a number, or a list
        of one per group), so that priors without them have the dict they had before; per-element
        theta_mean, theta_sd as lists (a shared one as the number it always was)."""
        d = asdict(self)
        for name in ("theta_mean", "theta_sd"):
            if isinstance(d[name], tuple):
                d[name] = list(d[name])
        for name in RHOV:
            if d[name] is None:
                del d[name]
            elif isinstance(d[name], tuple):
                d[name] = list(d[name])
        for name in PRECISIONS:
            if isinstance(d[name], tuple):
                d[name] = [_gamma_dict(g) for g in d[name]]
            else:
                d[name] = _gamma_dict(d[name])
        return d

    @classmethod
    def from_dict(cls, d: dict) -> Priors:
        """Inverse of ``to_dict``; GPMSAError naming a missing or unknown field."""
        if not isinstance(d, dict):
            raise GPMSAError(f"Priors.from_dict needs a dict, got {type(d).__name__}")
        known = {f.name for f in fields(cls)}
        if unknown := sorted(str(k) for k in set(d) - known):
            raise GPMSAError(f"Priors.from_dict: unknown fields {unknown}; known {sorted(known)}")
        kw = dict(d)
        for name in PRECISIONS:
            g = d.get(name)
            if name == "lamVz" and isinstance(g, list):
                if not g:
                    raise GPMSAError(
                        f"Priors.from_dict: {name} as a list needs one prior per discrepancy "
                        "precision group, got an empty list"
                    )
                kw[name] = tuple(_gamma_from(e, f"{name}[{i}]") for i, e in enumerate(g))
            else:
                kw[name] = _gamma_from(g, name)
        return cls(**kw)

    def log_theta(self, theta: np.ndarray, elements=None) -> float:
        """Log prior of theta (unit scale): the whole vector (q,), or with ``elements`` (index
        list) those elements of it; -inf outside (0, 1) (a NaN is outside it)."""
        theta = np.asarray(theta)
        if not np.all((theta > 0.0) & (theta < 1.0)):
            return -np.inf
        each = elements is None and self.theta_count is not None
        q = (theta.shape[-1] if theta.ndim else 1) if each else None
        mean, sd = self.theta_moments(q, elements)
        return float(-0.5 * np.sum(((theta - mean) / sd) ** 2))

    def log_beta(self, beta: np.ndarray, name: str = "betaU") -> float:
        """Log prior of correlation parameters beta of ``name`` (betaU or betaV; betaV's
        per-group priors along its last axis) via rho = exp(-beta/4); -inf unless beta > 0."""
        beta = np.asarray(beta)
        if np.any(beta <= 0.0) or np.any(~np.isfinite(beta)):
            return -np.inf
        a, b = self.rho_arrays(name, beta.shape[-1] if beta.ndim else 1)
        with np.errstate(under="ignore"):  # a large beta's rho underflows (subnormal, or 0)
            rho = np.minimum(np.exp(-0.25 * beta), self.rho_cap)
            # log(rho) is -beta/4 where rho underflowed to 0 (log(0) = -inf gave 0 * -inf = NaN)
            log_rho = np.where(rho > 0.0, np.log(np.where(rho > 0.0, rho, 1.0)), -0.25 * beta)
            return float(np.sum((a - 1.0) * log_rho + (b - 1.0) * np.log1p(-rho)))

    def scalar_log_prior(self, name: str, element: int = 0):
        """A fast function float -> float: the log prior of element ``element`` (its index in a
        1-D parameter, its column in a 2-D one: theta's element, lamVz's or betaV's group, whose
        prior may be its own) of ``name``."""
        if name == "theta":
            mu, sd = self.theta_prior(element)

            def f(x: float) -> float:
                return -0.5 * ((x - mu) / sd) ** 2 if 0.0 < x < 1.0 else -math.inf

        elif name in ("betaU", "betaV"):
            a, b = self.rho_prior(name, element)
            a1, b1, cap = a - 1.0, b - 1.0, self.rho_cap

            def f(x: float) -> float:
                if not 0.0 < x < math.inf:
                    return -math.inf
                rho = min(math.exp(-0.25 * x), cap)  # 0 for a large x: log(rho) is -x/4
                return a1 * (math.log(rho) if rho > 0.0 else -0.25 * x) + b1 * math.log1p(-rho)

        elif name in PRECISIONS:
            g = self.precision_prior(name, element)
            a1, b, lo, hi = g.a - 1.0, g.b, g.lower, g.upper

            def f(x: float) -> float:
                return a1 * math.log(x) - b * x if lo < x < hi else -math.inf

        else:
            raise GPMSAError(f"unknown parameter name {name!r}")
        return f

    def log_prior(self, name: str, value: np.ndarray) -> float:
        """Log prior of parameter ``name`` at ``value`` (any shape; lamVz with per-group priors:
        (G,), element g under the g-th; betaV with per-group priors: (p, G), column g under the
        g-th)."""
        if name == "theta":
            return self.log_theta(value)
        if name in ("betaU", "betaV"):
            return self.log_beta(value, name)
        if name == "lamVz" and self.per_group:
            x = np.asarray(value, dtype=np.float64).reshape(-1)
            a, b, lo, hi = self.gamma_arrays("lamVz", x.size)
            if not np.all((x > lo) & (x < hi)):
                return -np.inf
            return float(np.sum((a - 1.0) * np.log(x) - b * x))
        if name in PRECISIONS:
            return getattr(self, name).log_density(value)
        raise GPMSAError(f"unknown parameter name {name!r}")


def _theta_values(value, name: str, rule: str, ok) -> float | tuple[float, ...]:
    """``value`` as theta_mean or theta_sd (`_per_element`, one per calibration parameter)."""
    return _per_element(value, name, "calibration parameter", rule, ok)


def _rho_values(value, name: str) -> float | tuple[float, ...]:
    """``value`` as a Beta parameter of betaV's prior (`_per_element`, one per discrepancy
    precision group), each finite and > 0."""
    return _per_element(value, name, "discrepancy precision group", "finite and > 0",
                        lambda v: math.isfinite(v) and v > 0)  # fmt: skip


def _per_element(value, name: str, per: str, rule: str, ok) -> float | tuple[float, ...]:
    """``value`` as a float, or a tuple of floats (one per ``per``), each passing ``ok``
    (``rule`` says what it needs); GPMSAError naming ``name`` (and the element) otherwise."""
    many = isinstance(value, list | tuple) or (isinstance(value, np.ndarray) and value.ndim == 1)
    items = list(value) if many else [value]
    if many and not items:
        raise GPMSAError(
            f"{name} must be a number or a non-empty sequence of numbers (one per {per}), got "
            f"{value!r:.80}"
        )
    out = []
    for i, v in enumerate(items):
        where = f"{name}[{i}]" if many else name
        if isinstance(v, bool) or not isinstance(v, int | float | np.integer | np.floating):
            raise GPMSAError(f"{where} must be a real number, got {v!r:.60} ({type(v).__name__})")
        if not ok(float(v)):
            raise GPMSAError(f"{where} must be {rule}, got {float(v)}")
        out.append(float(v))
    return tuple(out) if many else out[0]


def as_group_priors(value, what: str) -> GammaPrior | tuple[GammaPrior, ...]:
    """``value`` as a lamVz prior: one GammaPrior, or a non-empty sequence of them as a tuple
    (one per discrepancy precision group); GPMSAError naming ``what`` otherwise."""
    if isinstance(value, GammaPrior):
        return value
    if isinstance(value, list | tuple) and value and all(isinstance(g, GammaPrior) for g in value):
        return tuple(value)
    raise GPMSAError(
        f"{what} must be a gpmsa.GammaPrior (shared by every discrepancy precision group) or a "
        f"non-empty list or tuple of them (one per group), got {value!r:.120}"
    )


def _gamma_dict(g: dict) -> dict:
    """A GammaPrior's ``asdict`` with an infinite bound as the string "inf"."""
    return {k: ("inf" if v == float("inf") else v) for k, v in g.items()}


def _gamma_from(g, name: str) -> GammaPrior:
    """The GammaPrior of a ``to_dict`` entry; GPMSAError naming ``name`` otherwise."""
    if not isinstance(g, dict) or not {"a", "b"} <= set(g) <= {"a", "b", "lower", "upper"}:
        raise GPMSAError(
            f"Priors.from_dict: {name} must be a dict with a, b (and lower, upper), got {g!r}"
        )
    values = {k: _float(v, f"{name}.{k}") for k, v in g.items()}
    try:
        return GammaPrior(**values)
    except GPMSAError as exc:
        raise GPMSAError(f"Priors.from_dict: {name}: {exc}") from None
