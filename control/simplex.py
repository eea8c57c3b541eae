"""Simplex speed controller: a performance law on GD; a fixed safe speed above GD_max or on a fault.

The paper's eq. 8 reads, for GD in [GD_min, GD_max],

    v = K_p ((GD_min + GD_max) / 2 - GD),

and v = 1.0 m/s above GD_max. As written this commands 0 m/s at the middle of the band (GD 300 for
the paper's [250, 350]), negative speeds above it, and nothing below GD_min; it is not what the
paper's robot did (it drove at up to 2.0 m/s on GD 300). Laws offered here:

- ``"linear"`` (default): v = v_max - K_p (GD - GD_min) clipped to [v_safe, v_max], with
  K_p = (v_max - v_safe) / (GD_max - GD_min): v_max at and below GD_min, v_safe at GD_max, so the
  command is continuous where the safety mode takes over;
- ``"paper"``: eq. 8 literally, clipped to [0, v_max] (v_max below GD_min; K_p defaults to
  v_max / ((GD_max - GD_min) / 2), which gives v_max at GD_min). It stops the robot mid-band;
- ``"switch"``: v_max in performance mode, v_safe in safety mode.

Risk posture: ``risk=None`` feeds the posterior mean of GD to the law (the paper). ``risk=alpha``
feeds the (1 - alpha) posterior quantile instead, so safety mode starts as soon as
P(GD > GD_max) > alpha. Any estimate that is not "ok" (buffer filling, fault, out of domain,
stale) means safety mode.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from control.errors import ControlError
from control.estimate import Estimate

LAWS = ("linear", "paper", "switch")


@dataclass(frozen=True)
class Command:
    """One speed command.

    Attributes:
        speed: commanded speed, m/s.
        mode: "performance" or "safety".
        gd_used: the GD value the law used (posterior mean or quantile); NaN on a fault.
        reason: why safety mode, "" in performance mode.
    """

    speed: float
    mode: str
    gd_used: float
    reason: str = ""


@dataclass(frozen=True)
class Simplex:
    """The paper's Simplex controller (see the module docstring for the laws and risk posture).

    Attributes:
        gd_min, gd_max: performance band of GD (1e-6 m^3); above gd_max: safety mode.
        v_max: top speed, m/s (the Jackal's 2.0).
        v_safe: safety-mode speed, m/s (the paper's 1.0).
        kp: proportional gain, (m/s) per GD unit; None for the law's default.
        risk: None (use the posterior mean) or alpha in (0, 1) (use the (1 - alpha) quantile).
        law: "linear", "paper" or "switch".
    """

    gd_min: float = 250.0
    gd_max: float = 350.0
    v_max: float = 2.0
    v_safe: float = 1.0
    kp: float | None = None
    risk: float | None = None
    law: str = "linear"

    def __post_init__(self) -> None:
        for name in ("gd_min", "gd_max", "v_max", "v_safe"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise ControlError(f"{name} must be finite and > 0, got {value}")
        if not self.gd_min < self.gd_max:
            raise ControlError(f"gd_min must be < gd_max, got {self.gd_min} and {self.gd_max}")
        if not self.v_safe <= self.v_max:
            raise ControlError(f"v_safe must be <= v_max, got {self.v_safe} and {self.v_max}")
        if self.kp is not None and not (np.isfinite(self.kp) and self.kp > 0):
            raise ControlError(f"kp must be finite and > 0, got {self.kp}")
        if self.risk is not None and not 0 < self.risk < 1:
            raise ControlError(f"risk must be None or lie in (0, 1), got {self.risk}")
        if self.law not in LAWS:
            raise ControlError(f"law must be one of {LAWS}, got {self.law!r}")

    @property
    def gain(self) -> float:
        """K_p in use, (m/s) per GD unit."""
        if self.kp is not None:
            return self.kp
        if self.law == "paper":
            return self.v_max / ((self.gd_max - self.gd_min) / 2)
        return (self.v_max - self.v_safe) / (self.gd_max - self.gd_min)

    def performance_speed(self, gd: float) -> float:
        """The performance-mode law v(GD) for GD <= gd_max, m/s."""
        if self.law == "linear":
            return float(
                np.clip(self.v_max - self.gain * (gd - self.gd_min), self.v_safe, self.v_max)
            )
        if self.law == "paper":
            if gd < self.gd_min:
                return self.v_max
            mid = (self.gd_min + self.gd_max) / 2
            return float(np.clip(self.gain * (mid - gd), 0.0, self.v_max))
        return self.v_max

    def command(self, estimate: Estimate) -> Command:
        """The speed command for one BCR estimate."""
        if not estimate.ok:
            return Command(self.v_safe, "safety", np.nan, f"no estimate ({estimate.status})")
        if self.risk is None:
            gd = estimate.gd_mean
        elif estimate.posterior is not None:
            gd = estimate.quantile(1 - self.risk)
        else:
            return Command(self.v_safe, "safety", np.nan, "risk posture needs the posterior")
        if gd > self.gd_max:
            return Command(self.v_safe, "safety", gd, f"GD {gd:.0f} > GD_max {self.gd_max:g}")
        return Command(self.performance_speed(gd), "performance", gd)
