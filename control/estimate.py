"""The BCR's output: one GD estimate, or the reason there is none."""

from __future__ import annotations

from dataclasses import dataclass
from math import isnan

import numpy as np

from control.errors import ControlError
from control.validation import is_choice, is_real, python_number, python_value
from gpmsa import Posterior

#: Status values. Only "ok" carries numbers; every other status says why there is no estimate.
STATUSES = (
    "ok",
    "filling",  # not enough contiguous samples yet (start, after a gap), or the block after a fault
    "out_of_domain",
    "sensor_fault",
    "implausible",
    "calibration_failed",
    "stale",
)
#: The statuses that say the sensor or its signal failed (the Simplex latches on them).
FAULT_STATUSES = ("sensor_fault", "implausible")


def graver_fault(first: Estimate | None, second: Estimate) -> Estimate | None:
    """The graver of two estimates as faults (None if neither is one): a sensor fault before an
    implausible block (the earlier of two sensor faults), else the less plausible block."""
    if second.status not in FAULT_STATUSES:
        return first
    if first is None:
        return second
    if second.status == "sensor_fault" and first.status != "sensor_fault":
        return second
    both_implausible = first.status == second.status == "implausible"
    if both_implausible and second.plausibility_p < first.plausibility_p:
        return second
    return first


#: The values of a named `Estimate.domain_edge` ("" names none).
DOMAIN_EDGES = ("upper", "lower")


def run_text(status, sample_time, sample_position, samples: str) -> str:
    """A run's estimates for a one-line repr (`ClosedLoopResult`'s, `ReplayResult`'s): "125
    estimates over 44.1 s, 49.7 m: filling 2, ok 122, out_of_domain 1; 5290 sensor samples"
    (the span of the samples fed to the BCR; the statuses counted, by name), "no estimate; 40
    sensor samples" without one; ``samples`` names the samples ("sensor", "IMU"). Never the
    arrays: a repr of a long run's stays short and quick."""
    status, t, s = (np.ravel(np.asarray(a)) for a in (status, sample_time, sample_position))
    counted = _count(t.size, f"{samples} sample")
    if not status.size:
        return f"no estimate; {counted}"
    names, counts = np.unique(status.astype(str), return_counts=True)
    statuses = ", ".join(f"{k} {c}" for k, c in zip(names, counts, strict=True))
    span = f" over {t[-1] - t[0]:.1f} s, {s[-1] - s[0]:.1f} m" if t.size and s.size else ""
    return f"{_count(status.size, 'estimate')}{span}: {statuses}; {counted}"


def _count(n: int, what: str) -> str:
    """``n`` and ``what``, plural unless one ("1 estimate", "2 estimates")."""
    return f"{n} {what}{'' if n == 1 else 's'}"


def edge_counts(domain_edge) -> dict[str, int]:
    """How many estimates name each edge of the GD domain, from their ``domain_edge`` values
    (e.g. `ClosedLoopResult.domain_edge`), keyed by DOMAIN_EDGES; ControlError unless those
    are a sequence of "" and DOMAIN_EDGES."""
    edges = np.asarray(domain_edge, dtype=object)
    known = ("", *DOMAIN_EDGES)
    if (
        isinstance(domain_edge, str)
        or edges.ndim != 1
        or not all(isinstance(e, str) and e in known for e in edges)
    ):
        raise ControlError(
            f"domain_edge must be a sequence of '', 'upper' or 'lower' (one per estimate), got "
            f"{domain_edge!r:.60}"
        )
    return {edge: int(np.sum(edges == edge)) for edge in DOMAIN_EDGES}


#: `favoured_edge`: the evidence (posterior-to-prior ratio, a Bayes factor) that marks an edge
#: of the GD domain as favoured, against every GD at least EDGE_MARGIN (relative) inside it:
#: 20 is "strong" evidence on Kass and Raftery's (1995) scale.
EDGE_BAYES_FACTOR = 20.0
EDGE_MARGIN = 0.05


def favoured_edge(nodes: np.ndarray, posterior_mass: np.ndarray, prior_mass: np.ndarray) -> str:
    """The edge "upper" ("lower") when the data favour the last (first) of the increasing GD
    ``nodes`` by a Bayes factor above EDGE_BAYES_FACTOR over every node at least EDGE_MARGIN
    inside it (the posterior-to-prior mass ratio there is that much higher); "" otherwise, and
    on a grid too narrow to hold a node that far inside."""
    with np.errstate(divide="ignore", invalid="ignore"):  # no prior mass: no evidence there
        log_ratio = np.where(prior_mass > 0, np.log(posterior_mass) - np.log(prior_mass), -np.inf)
    threshold = np.log(EDGE_BAYES_FACTOR)
    inside_top = nodes <= nodes[-1] * (1.0 - EDGE_MARGIN)
    inside_bottom = nodes >= nodes[0] * (1.0 + EDGE_MARGIN)
    if not (inside_top.any() and inside_bottom.any()):
        return ""
    if log_ratio[-1] - log_ratio[inside_top].max() > threshold:
        return "upper"
    if log_ratio[0] - log_ratio[inside_bottom].max() > threshold:
        return "lower"
    return ""


NUMBERS = ("time", "position", "gd_mean", "gd_sd", "latency_s", "speed", "prob_change",
           "data_time", "plausibility_p")  # fmt: skip
"""The `Estimate` fields that hold one real number (NaN: none)."""


@dataclass(frozen=True, eq=False)
class Estimate:
    """A posterior of GD at one instant, or why there is none.

    Attributes:
        time: s, time of the newest sample the BCR has seen.
        position: m, front-axle position at that time.
        status: one of STATUSES; "ok" means gd_mean etc. are valid.
        reason: a sentence for a person ("" when an ok estimate used new data; an ok estimate
            made without new data, e.g. while standing, says so).
        gd_mean: posterior mean of GD (1e-6 m^3); NaN unless ok.
        gd_sd: posterior standard deviation; NaN unless ok.
        interval: credible interval (lo, hi) of the BCR's kind and level (the highest-density
            interval by default); NaNs unless ok.
        posterior: the GD posterior on a grid (quantiles, P(GD > x)); None unless ok.
        latency_s: wall-clock time of the computation that produced this estimate, s.
        speed: m/s, mean measured speed over the samples used (NaN if none).
        feature: the newest observation (the block's feature vector, or the window's log f);
            None if none.
        prob_change: P(the roughness changed within the BCR's ``recent_change_m``) (change-point
            method; NaN otherwise). It is 1 over the first metres of a stream (or after
            ``BCR.reset``): the only segment the filter knows began there.
        data_time: s, time of the newest sample whose information the estimate holds.
        plausibility_p: for an "implausible" estimate, the upper-tail probability of the
            newest observation under the emulator's law at the GD that explains it best (the
            smaller, the less any GD explains it); NaN otherwise.
        domain_edge: "upper" ("lower") when the data strongly favour the emulator's highest
            (lowest) GD over every GD inside its domain (`favoured_edge`): the road may be
            rougher (smoother) than any the emulator knows, and the posterior, which assumes GD
            within the domain, then understates (overstates) it; "" otherwise and unless ok.
    """

    time: float
    position: float
    status: str
    reason: str = ""
    gd_mean: float = np.nan
    gd_sd: float = np.nan
    interval: tuple[float, float] = (np.nan, np.nan)
    posterior: Posterior | None = None
    latency_s: float = 0.0
    speed: float = np.nan
    feature: np.ndarray | None = None
    prob_change: float = np.nan
    data_time: float = np.nan
    plausibility_p: float = np.nan
    domain_edge: str = ""

    def __post_init__(self) -> None:
        if not is_choice(self.status, STATUSES):
            raise ControlError(f"status must be one of {STATUSES}, got {self.status!r}")
        for name in NUMBERS:  # NaN where there is none; never a string, a bool or an array
            value = getattr(self, name)
            if not is_real(value):
                raise ControlError(f"{name} must be a real number (NaN: none), got {value!r}")
            python_number(self, name)  # np.float32 would make the Simplex's law float32
        self._check_interval()
        if self.domain_edge not in ("", *DOMAIN_EDGES):
            raise ControlError(
                f"domain_edge must be '' or one of {DOMAIN_EDGES}, got {self.domain_edge!r}"
            )
        if self.posterior is not None and not isinstance(self.posterior, Posterior):
            raise ControlError(
                f"posterior must be a gpmsa.Posterior or None, got {type(self.posterior).__name__}"
            )
        if not self.ok:
            self._check_empty()

    def _check_empty(self) -> None:
        """ControlError naming the first of the posterior's numbers (gd_mean, gd_sd, interval,
        posterior, domain_edge) that an estimate other than "ok" holds."""
        held = {
            "gd_mean": not np.isnan(self.gd_mean),
            "gd_sd": not np.isnan(self.gd_sd),
            "interval": not np.isnan(float(self.interval[0])),
            "posterior": self.posterior is not None,
            "domain_edge": self.domain_edge != "",
        }
        for name, holds in held.items():
            if holds:
                raise ControlError(
                    f"a {self.status!r} estimate has no {name} (only an 'ok' one carries the "
                    f"posterior's numbers), got {getattr(self, name)!r:.60}"
                )

    def _check_interval(self) -> None:
        """ControlError unless ``interval`` is a pair (lo, hi) of real numbers with lo <= hi, or
        a pair of NaNs."""
        pair = self.interval
        if not (isinstance(pair, tuple | list) and len(pair) == 2 and all(map(is_real, pair))):
            raise ControlError(f"interval must be a pair (lo, hi) of real numbers, got {pair!r}")
        lo, hi = float(pair[0]), float(pair[1])
        if isnan(lo) != isnan(hi) or lo > hi:  # (math's isnan: two floats)
            raise ControlError(f"interval must have lo <= hi (or be two NaNs), got {pair!r}")
        if any(isinstance(v, np.generic) for v in pair):  # as the numbers: Python's
            object.__setattr__(self, "interval", tuple(map(python_value, pair)))

    @property
    def ok(self) -> bool:
        """True when the estimate carries a usable posterior."""
        return self.status == "ok"

    def prob_above(self, value: float) -> float:
        """P(GD > value) for a finite GD ``value``; NaN unless ok."""
        if not (is_real(value) and np.isfinite(value)):
            raise ControlError(f"value must be a finite GD, got {value!r}")
        if self.posterior is None:
            return np.nan
        return float(self.posterior.prob_above(self.posterior.names[0], float(value)))

    def quantile(self, q: float) -> float:
        """The GD quantile at probability q in [0, 1]; NaN unless ok."""
        if not (is_real(q) and 0 <= q <= 1):
            raise ControlError(f"q must be a probability in [0, 1], got {q!r}")
        if self.posterior is None:
            return np.nan
        return float(self.posterior.quantile(self.posterior.names[0], float(q)))
