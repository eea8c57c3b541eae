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
  v_max / ((GD_max - GD_min) / 2), which gives v_max at GD_min). It stops the robot mid-band
  and commands less than v_safe over part of the band (GD 275-350 with the defaults). Below
  the emulator's speed domain (0.5 m/s for the shipped emulators, from GD 287.5) the BCR learns
  nothing: the robot creeps or stands on its last estimate until that turns stale
  (``BCRSettings.max_age_s``) and safety mode moves it on at v_safe. And as safety mode is then
  faster than the law, a fault (or the latch after one) can make the robot faster than its
  fault-free twin: the latch's guarantee below holds for "linear" and "switch" only;
- ``"switch"``: v_max in performance mode, v_safe in safety mode.

Speed grid: in performance mode the law's speed is rounded down to v_safe + k ``speed_step_mps``
(default 0.1 m/s; v_max and 0 are on the grid), so a change of the estimate far below its
resolution changes no command. The closed loop is chaotic (wheel lift-off): on the continuous
law a 1e-9 gain error of the accelerometer, which no check can see, moved the command by
~1e-7 m/s and later positions by metres. On the grid the command moves only when the law
crosses a grid point, and it is never above the law. ``speed_step_mps=0``: the continuous law.

Risk posture: ``risk=None`` feeds the posterior mean of GD to the law (the paper). ``risk=alpha``
feeds the (1 - alpha) posterior quantile instead, so safety mode starts as soon as
P(GD > GD_max) > alpha. Any estimate that is not "ok" (buffer filling, fault, out of domain,
stale), an "ok" one whose GD is not finite, or one whose data favour the emulator's upper GD edge
(``Estimate.domain_edge == "upper"``: the road may be rougher than any the emulator knows, and the
posterior, bounded by that edge, cannot say how much) means safety mode.

After a fault (``after_fault``): a sensor that has failed once is not trusted again within the
run. With ``"latch"`` (default), the first estimate whose status is a fault (``FAULT_STATUSES``:
"sensor_fault", or "implausible" with a plausibility p below ``latch_p``) puts the robot in
safety mode for the rest of the run, or until the operator calls `SimplexRun.reset`; the BCR
goes on estimating, so its trace still shows what it sees. With ``"resume"`` the law takes over
again at the first "ok" estimate. Once a run has diverged from its fault-free twin the closed
loop is chaotic, and a resumed run may meet the next rough stretch a block sooner or later than
the twin; a latched one drives at the safe speed from the fault on, so a fault that the checks
flag in its first block never makes the robot faster on rough ground (docs/closed-loop.md), on
the laws whose performance speed is never below v_safe ("linear", "switch"; not "paper").
The latch needs the run's history: `Simplex.command` is memoryless, `Simplex.start` gives the
stateful `SimplexRun` that the closed loop and the replay use.

Release dwell (``release_m``, opt-in; default 0: none): once the run has driven in
performance mode, safety mode for whatever reason (a GD above GD_max, an estimate that is not
"ok", the latch until `SimplexRun.reset`) returns to performance mode only once the law has
read performance mode (the same test as without the dwell, with the ``risk`` posture) at every
update over ``release_m`` metres of travel (the estimates' ``position``); any update that
reads safety mode restarts the count. The start's safety mode (the BCR's buffer filling, and a
GD above GD_max before the first performance mode) has no dwell; a fault (one that latches, with
either ``after_fault``) ends the start. The held speed is v_safe, or the law's where that is
lower ("paper"): the dwell never commands more than the law. A sensor whose gain drops
reads as smoother ground until the BCR's checks find it; the dwell keeps such a reading in
safety mode for ``release_m`` more metres, at the price of ``release_m`` metres at v_safe after
each safety mode of a healthy run (docs/closed-loop.md, "Release dwell", measures both).
Used by `start`'s `SimplexRun` only.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from control.errors import ControlError
from control.estimate import FAULT_STATUSES, Estimate
from control.validation import check_instance, is_choice, is_real, require_reals
from gpmsa.errors import numbers_text

LAWS = ("linear", "paper", "switch")
AFTER_FAULT = ("latch", "resume")
LATCH_P = 1e-12
"""Default ``Simplex.latch_p``."""


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
        law: "linear", "paper" or "switch" ("paper" commands speeds below v_safe, down to 0, and
            below the emulator's speed domain; see the module docstring).
        after_fault: "latch" (safety mode for the rest of the run after a fault) or "resume"
            (back to the law at the next ok estimate); used by `start`'s `SimplexRun`.
        latch_p: an "implausible" estimate latches only when its ``plausibility_p`` is below
            this (NaN: latches). The BCR's own limit (1e-6) is for dropping one block: over
            ~40,000 blocks of 400 fault-free closed-loop runs, 6 fell below it (the block law's
            tails are lighter than the road's), the smallest at 3.4e-10; a fault that no check
            of the signal sees and no GD explains lies far beyond (90% of such blocks of added
            noise below 1e-15). Used with ``after_fault="latch"`` only (another value with
            "resume" is a ControlError: it would have no effect).
        speed_step_mps: the performance-mode speed is rounded down to v_safe + k times this,
            m/s (0: the continuous law; see the module docstring).
        release_m: release dwell, m (finite, >= 0; 0: none): after safety mode, performance
            mode again only once the law has read it over this much travel (see the module
            docstring); used by `start`'s `SimplexRun`.
    """

    gd_min: float = 250.0
    gd_max: float = 350.0
    v_max: float = 2.0
    v_safe: float = 1.0
    kp: float | None = None
    risk: float | None = None
    law: str = "linear"
    after_fault: str = "latch"
    latch_p: float = LATCH_P
    speed_step_mps: float = 0.1
    release_m: float = 0.0

    def __post_init__(self) -> None:
        require_reals(
            self,
            ("gd_min", "gd_max", "v_max", "v_safe", "kp", "risk", "latch_p", "speed_step_mps",
             "release_m"),
            optional=("kp", "risk"),
        )  # fmt: skip
        for name in ("gd_min", "gd_max", "v_max", "v_safe"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise ControlError(f"{name} must be finite and > 0, got {value}")
        if not self.gd_min < self.gd_max:
            raise ControlError(
                f"gd_min must be < gd_max, got {self.gd_min} and {self.gd_max}: the band holds "
                "the law's speeds between v_max and v_safe; for one threshold (v_max up to "
                "gd_max, v_safe above it) use law='switch', which reads gd_max alone, with any "
                "gd_min below it"
            )
        if not self.v_safe <= self.v_max:
            raise ControlError(f"v_safe must be <= v_max, got {self.v_safe} and {self.v_max}")
        if self.kp is not None and not (np.isfinite(self.kp) and self.kp > 0):
            raise ControlError(f"kp must be finite and > 0, got {self.kp}")
        if self.risk is not None and not 0 < self.risk < 1:
            raise ControlError(f"risk must be None or lie in (0, 1), got {self.risk}")
        if not is_choice(self.law, LAWS):
            raise ControlError(f"law must be one of {LAWS}, got {self.law!r}")
        if self.law == "switch" and self.kp is not None:
            raise ControlError("kp has no effect with law='switch' (v_max or v_safe): leave it")
        if not (np.isfinite(self.speed_step_mps) and 0 <= self.speed_step_mps <= self.v_max):
            raise ControlError(
                f"speed_step_mps must lie in [0, v_max] = "
                f"[0, {numbers_text(self.speed_step_mps, self.v_max)[1]}], "
                f"got {self.speed_step_mps}"
            )
        if not (np.isfinite(self.release_m) and self.release_m >= 0):
            raise ControlError(
                f"release_m must be a finite distance >= 0, m, got {self.release_m}: 0 for no "
                "release dwell, or the metres of travel over which the law must read "
                "performance mode before the run leaves safety mode"
            )
        if not 0 < self.latch_p <= 1:
            raise ControlError(f"latch_p must lie in (0, 1], got {self.latch_p}")
        if not is_choice(self.after_fault, AFTER_FAULT):
            raise ControlError(
                f"after_fault must be one of {AFTER_FAULT}, got {self.after_fault!r}"
            )
        if self.after_fault == "resume" and self.latch_p != LATCH_P:
            raise ControlError(
                f"latch_p = {self.latch_p:g} has no effect with after_fault='resume' (nothing "
                "latches: the law takes over again at the next ok estimate); leave it, or use "
                "after_fault='latch'"
            )

    @property
    def gain(self) -> float:
        """K_p in use, (m/s) per GD unit."""
        if self.kp is not None:
            return self.kp
        if self.law == "paper":
            return self.v_max / ((self.gd_max - self.gd_min) / 2)
        return (self.v_max - self.v_safe) / (self.gd_max - self.gd_min)

    def performance_speed(self, gd: float) -> float:
        """The performance-mode law v(GD) for GD <= gd_max, m/s. `ControlError` for a ``gd``
        that is not a real number or is NaN (it has no speed)."""
        if not (is_real(gd) and not np.isnan(gd)):
            raise ControlError(f"gd must be a real number (1e-6 m^3), got {gd!r}")
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

    def start(self) -> SimplexRun:
        """A `SimplexRun`: this controller over one run, with the memory ``after_fault`` needs."""
        return SimplexRun(self)

    def command(self, estimate: Estimate) -> Command:
        """The speed command for one BCR estimate, memoryless (no latch: see `start`)."""
        check_instance(estimate, "estimate", Estimate)
        if not estimate.ok:
            return Command(self.v_safe, "safety", np.nan, f"no estimate ({estimate.status})")
        if self.risk is None:
            gd = estimate.gd_mean
        elif estimate.posterior is not None:
            gd = estimate.quantile(1 - self.risk)
        else:
            return Command(self.v_safe, "safety", np.nan, "risk posture needs the posterior")
        if not (np.isfinite(gd) and gd > 0):  # no roughness reads below 0
            return Command(self.v_safe, "safety", np.nan, f"the estimate's GD is {gd}")
        if estimate.domain_edge == "upper":
            return Command(
                self.v_safe, "safety", gd, "the road reads at or above the emulator's roughest GD"
            )
        if gd > self.gd_max:
            shown = numbers_text(gd, self.gd_max, digits=4)[0]  # (just past: not as GD_max)
            limit = numbers_text(gd, self.gd_max)[1]  # (:g, more where gd reads as it)
            return Command(self.v_safe, "safety", gd, f"GD {shown} > GD_max {limit}")
        return Command(self.on_speed_grid(self.performance_speed(gd)), "performance", gd)

    def on_speed_grid(self, speed: float) -> float:
        """``speed`` rounded down to the grid v_safe + k ``speed_step_mps`` (k any integer; v_max
        and 0 are on it too), m/s; unchanged when the step is 0. Never above ``speed``.
        `ControlError` for a ``speed`` that is not a finite real number >= 0."""
        if not (is_real(speed) and np.isfinite(speed) and speed >= 0):
            raise ControlError(f"speed must be a finite real number >= 0, m/s, got {speed!r}")
        step = self.speed_step_mps
        if step == 0 or speed >= self.v_max:
            return speed
        k = np.floor((speed - self.v_safe) / step + 1e-9)  # 1e-9: grid points stay put
        return float(min(max(self.v_safe + k * step, 0.0), speed))  # min: round-off of k * step


class SimplexRun:
    """A `Simplex` over one run: its commands, latched in safety mode after a fault when
    ``simplex.after_fault == "latch"``, held in safety mode by the release dwell when
    ``simplex.release_m > 0``.

    Attributes:
        simplex: the controller (`ControlError` for anything else).
        latched_by: the estimate that latched safety mode, or None.
        clear_since_m: with the release dwell, the position (m) of the first of the updates
            in a row whose law reads performance mode; None after one that reads safety mode.
        in_safety: with the release dwell, whether the last command was in safety mode.
        performed: with the release dwell, whether the run has commanded performance mode or
            met a fault (an estimate that latches, ``FAULT_STATUSES``, with either
            ``after_fault``); the dwell holds from the first safety mode after either: the
            start's has none.
    """

    clear_since_m: float | None = None  # (class values: a run pickled before the dwell)
    in_safety: bool = True
    performed: bool = False

    def __init__(self, simplex: Simplex) -> None:
        check_instance(simplex, "simplex", Simplex, "make one with control.Simplex(...)")
        self.simplex = simplex
        self.latched_by: Estimate | None = None
        self.clear_since_m: float | None = None
        self.in_safety = True
        self.performed = False

    @property
    def latched(self) -> bool:
        """True while a past fault holds the robot in safety mode."""
        return self.latched_by is not None

    def command(self, estimate: Estimate) -> Command:
        """The speed command for the next estimate of the run."""
        check_instance(estimate, "estimate", Estimate)
        s = self.simplex
        fault = self._latches(estimate)
        if s.after_fault == "latch" and not self.latched and fault:
            self.latched_by = estimate
        if fault and s.release_m > 0:  # a fault is never the start's safety mode
            self.performed = True
        if self.latched_by is None:
            command = s.command(estimate)
            if s.release_m == 0:
                return command
            command = self._dwell(command, estimate)
            self.in_safety = command.mode == "safety"
            return command
        self.clear_since_m, self.in_safety = None, True
        first = self.latched_by
        return Command(
            s.v_safe,
            "safety",
            np.nan,
            f"latched by an estimate of status {first.status!r} at {first.time:.2f} s"
            + (f" ({first.reason})" if first.reason else "")
            + "; reset() to resume",
        )

    def _dwell(self, command: Command, estimate: Estimate) -> Command:
        """``command``, the law's, held in safety mode after the run's first performance mode
        (or fault) until the law has read performance mode over ``release_m`` metres in a row
        (an update without a finite position restarts the count). The held speed is v_safe, or
        the law's where lower ("paper"): the dwell never commands more than the law."""
        if command.mode == "safety":
            self.clear_since_m = None
            return command
        position = estimate.position
        if not np.isfinite(position):
            self.clear_since_m = None
        elif self.clear_since_m is None:
            self.clear_since_m = position
        clear_m = 0.0 if self.clear_since_m is None else position - self.clear_since_m
        if self.performed and self.in_safety and not clear_m >= self.simplex.release_m:
            return Command(  # (min: "paper" reads performance mode below v_safe; never faster)
                min(self.simplex.v_safe, command.speed),
                "safety",
                command.gd_used,
                f"release dwell: the law has read performance mode over {max(clear_m, 0.0):.2f} "
                f"of release_m = {self.simplex.release_m:g} m",
            )
        self.performed = True
        return command

    def _latches(self, estimate: Estimate) -> bool:
        if estimate.status == "implausible":
            return not estimate.plausibility_p >= self.simplex.latch_p  # NaN latches
        return estimate.status in FAULT_STATUSES

    def reset(self) -> None:
        """Clear the latch (the operator has checked the sensor); the law applies again (with
        the release dwell, after ``release_m`` metres of it reading performance mode)."""
        self.latched_by = None
