"""The Bayesian Calibration Routine (BCR): streaming accelerations in, GD posteriors out.

The paper's BCR keeps a moving buffer of the last 1,000 front-axle accelerations (120 Hz), computes
f = var(buffer) (eq. 5, normalised by T) and calibrates the GPM/SA emulator on (v, f) to get a GD
posterior. This class does the same through ``gpmsa.Calibrator.log_likelihood_grid`` (exact, on
a grid) and, by default (``method="filter"``), combines successive windows in a sequential Bayes
filter (`control.tracker`): one window's f has a 15-25% spread across road realisations, so more
than one window is needed to beat one window's accuracy. ``method="window"`` is the paper's
estimator: each estimate uses its own window only.

Windows that overlap share samples and must not be multiplied together as if independent. Two
ways to respect that:

- ``method="filter"`` (default): K = ceil(buffer / update_every) interleaved filters, filter k
  taking the disjoint windows that end at updates k, k + K, ... at full power; each estimate is
  the posterior of the filter whose window just ended, so it reacts to its newest window as fast
  as the one-window estimator, and adds the earlier, disjoint windows that the change-point /
  random-walk prior still deems relevant.
- ``method="tempered"``: one filter, updated at every estimate with the newest window's
  likelihood raised to the power n_new / buffer, where n_new is the number of samples that
  entered the buffer since the filter's last update (125 / 1,000 in steady state; 1 after a
  restart). Over a stretch of constant roughness the tempered likelihoods add up to one full
  window likelihood per ``buffer`` new samples, so no sample is counted twice. After a change,
  though, the windows that straddle it enter with weight too, so the estimate moves later than
  with the interleaved filters (about 10 m against 6 m for a 300 -> 500 step at 1.5 m/s with
  the test double of tests/control); in closed loop it is better where the roughness is steady
  and worse after changes, no better overall (docs/closed-loop.md).
"""

from __future__ import annotations

import time as _time
from dataclasses import dataclass, field, replace

import numpy as np

from control.errors import ControlError
from control.estimate import Estimate
from control.feature import FEATURES, window_feature
from control.tracker import GDTracker, TrackerSettings

METHODS = ("filter", "tempered", "window")


@dataclass(frozen=True)
class BCRSettings:
    """Settings of a BCR (see `BCR`); the closed loop builds its BCR from these."""

    buffer: int = 1000
    rate_hz: float = 120.0
    update_every: int = 125
    feature: str = "log_var"
    method: str = "filter"
    tracker: TrackerSettings = field(default_factory=TrackerSettings)
    max_age_s: float = 5.0
    interval_level: float = 0.9

    def __post_init__(self) -> None:
        if not (isinstance(self.buffer, int | np.integer) and self.buffer >= 10):
            raise ControlError(f"buffer must be an integer >= 10 samples, got {self.buffer}")
        if not (np.isfinite(self.rate_hz) and self.rate_hz > 0):
            raise ControlError(f"rate_hz must be > 0, got {self.rate_hz}")
        if not (isinstance(self.update_every, int | np.integer) and self.update_every >= 1):
            raise ControlError(f"update_every must be an integer >= 1, got {self.update_every}")
        if self.feature not in FEATURES:
            raise ControlError(f"feature must be one of {FEATURES}, got {self.feature!r}")
        if self.method not in METHODS:
            raise ControlError(f"method must be one of {METHODS}, got {self.method!r}")
        if not (np.isfinite(self.max_age_s) and self.max_age_s > 0):
            raise ControlError(f"max_age_s must be > 0, got {self.max_age_s}")
        if not 0 < self.interval_level < 1:
            raise ControlError(f"interval_level must lie in (0, 1), got {self.interval_level}")


def emulator_domain(calibrator) -> tuple[tuple[float, float], tuple[float, float]]:
    """(speed range, GD range) of the calibrator's emulator, native units."""
    emu = calibrator.emulator
    dom = emu.domain
    return tuple(map(float, dom[emu.x_names[0]])), tuple(map(float, dom[emu.t_names[0]]))


class BCR:
    """Streaming GD estimator around a `gpmsa.Calibrator`.

    Args:
        calibrator: a prepared `gpmsa.Calibrator` (anything with ``log_likelihood_grid(x_obs, y_obs)
            -> (theta_native_grid, loglik)`` and ``emulator.domain``) whose emulator maps speed v
            (m/s) and GD to the window observation y.
        buffer: window length, samples (the paper: 1,000).
        rate_hz: accelerometer rate, Hz (the paper: 120).
        update_every: new samples between estimates (125: about one estimate a second at 120 Hz;
            with ``method="filter"``, 1,000 / 125 = 8 interleaved filters of disjoint windows).
        **settings: the other `BCRSettings` fields (feature, method, tracker, max_age_s,
            interval_level).

    Guards: the output is an `Estimate` whose status says why there is no number while the buffer
    fills, when the window's speed is outside the emulator's domain, after NaN or dropped samples
    (the buffer restarts: windows are contiguous), when the calibrator refuses, and when the newest
    estimate is older than ``max_age_s``.
    """

    def __init__(
        self,
        calibrator,
        buffer: int = 1000,
        rate_hz: float = 120.0,
        update_every: int = 125,
        **settings,
    ):
        self.settings = BCRSettings(
            buffer=buffer, rate_hz=rate_hz, update_every=update_every, **settings
        )
        self.calibrator = calibrator
        self.speed_range, self.gd_range = emulator_domain(calibrator)
        self.gd_name = calibrator.emulator.t_names[0]
        tracker = self.settings.tracker
        n_chains = 1
        if self.settings.method == "filter":
            n_chains = -(-self.settings.buffer // self.settings.update_every)
        elif self.settings.method == "window":
            tracker, n_chains = replace(tracker, mean_segment_m=0.0), 1
        self.trackers = [GDTracker(self.gd_range, tracker) for _ in range(n_chains)]
        self.reset()

    @classmethod
    def from_settings(cls, calibrator, settings: BCRSettings) -> BCR:
        """A BCR with the given settings."""
        s = settings
        return cls(
            calibrator,
            s.buffer,
            s.rate_hz,
            s.update_every,
            feature=s.feature,
            method=s.method,
            tracker=s.tracker,
            max_age_s=s.max_age_s,
            interval_level=s.interval_level,
        )

    def reset(self) -> None:
        """Empty the buffer and forget the GD state."""
        self._t = np.empty(0)
        self._pos = np.empty(0)
        self._acc = np.empty(0)
        self._spd = np.empty(0)
        self._since_update = 0
        self._n_updates = 0
        self._fault = ""
        self._fresh = 0  # samples in the buffer the tempered filter has not seen
        self._tracked_at: list[float | None] = [None] * len(self.trackers)
        for tracker in self.trackers:
            tracker.reset()
        self.last = Estimate(time=0.0, position=0.0, status="filling", reason="no samples yet")

    def update(
        self, t: np.ndarray, position: np.ndarray, accel: np.ndarray, speed: np.ndarray
    ) -> Estimate:
        """Take new samples; return the newest estimate (or why there is none).

        Args:
            t: (n,) sample times, s, increasing by 1/rate_hz (a larger step means dropped samples).
            position: (n,) front-axle positions, m.
            accel: (n,) measured vertical front-axle accelerations, m/s^2 (NaN = sensor fault).
            speed: (n,) measured speeds, m/s.
        """
        arrays = [np.atleast_1d(np.asarray(a, dtype=float)) for a in (t, position, accel, speed)]
        n = arrays[0].size
        for name, a in zip(("t", "position", "accel", "speed"), arrays, strict=True):
            if a.ndim != 1 or a.size != n:
                raise ControlError(f"{name} must be 1-D of length {n} (as t), got shape {a.shape}")
        t, position, accel, speed = arrays
        if n == 0:
            return self._check_age(self.last)
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(position))):
            raise ControlError("t and position must be finite (they come from the clock/odometry)")
        start = 0
        while start < n:
            room = self.settings.update_every - self._since_update
            stop = min(n, start + room)
            self._append(t[start:stop], position[start:stop], accel[start:stop], speed[start:stop])
            self._since_update += stop - start
            start = stop
            if self._since_update >= self.settings.update_every:
                self.last = self._estimate(self._n_updates % len(self.trackers))
                self._since_update = 0
                self._n_updates += 1
        return self._check_age(self.last)

    # --- internals -------------------------------------------------------------------------------

    def _append(self, t, pos, acc, spd) -> None:
        """Append samples; a non-finite value or a time gap restarts the buffer after it."""
        dt_nom = 1.0 / self.settings.rate_hz
        prev_t = self._t[-1:] if self._t.size else t[:1] - dt_nom
        steps = np.diff(np.concatenate([prev_t, t]))
        bad_value = ~(np.isfinite(acc) & np.isfinite(spd))
        gap = (steps > 1.5 * dt_nom) | (steps <= 0.5 * dt_nom)
        restart = np.flatnonzero(bad_value | gap)
        if restart.size:
            k = restart[-1]
            n_bad = int(bad_value.sum())
            n_gap = int(gap.sum())
            what = []
            if n_bad:
                what.append(f"{n_bad} non-finite sample(s)")
            if n_gap:
                missing = int(np.round(np.max(steps[gap]) / dt_nom)) - 1
                what.append(f"a time step {np.max(steps[gap]):.4g} s (about {missing} dropped)")
            self._fault = f"{' and '.join(what)} near t = {t[k]:.2f} s; buffer restarted"
            keep = slice(k + 1, None) if bad_value[k] else slice(k, None)
            parts = [a[keep] for a in (t, pos, acc, spd)]
            self._fresh = parts[0].size
        else:
            held = (self._t, self._pos, self._acc, self._spd)
            parts = [np.concatenate(pair) for pair in zip(held, (t, pos, acc, spd), strict=True)]
            self._fresh += t.size
        b = self.settings.buffer
        self._fresh = min(self._fresh, b)
        self._t, self._pos, self._acc, self._spd = (a[-b:] for a in parts)

    def _now(self) -> tuple[float, float]:
        return (
            (float(self._t[-1]), float(self._pos[-1]))
            if self._t.size
            else (
                float(self.last.time),
                float(self.last.position),
            )
        )

    def _estimate(self, chain: int) -> Estimate:
        t_now, pos_now = self._now()
        s = self.settings
        if self._fault:
            reason, self._fault = self._fault, ""
            return Estimate(t_now, pos_now, "sensor_fault", reason)
        if self._acc.size < s.buffer:
            return Estimate(
                t_now, pos_now, "filling", f"buffer holds {self._acc.size} of {s.buffer} samples"
            )
        tic = _time.perf_counter()
        v = float(np.mean(self._spd))
        lo, hi = self.speed_range
        # the emulator's own rule (it snaps float rounding at the ends onto the domain)
        unit = float(self.calibrator.emulator.standardizer.x_to_unit([[v]])[0, 0])
        if not 0.0 <= unit <= 1.0:
            return Estimate(
                t_now,
                pos_now,
                "out_of_domain",
                f"window speed {v:.3g} m/s outside the emulator's range [{lo:g}, {hi:g}] m/s",
                speed=v,
            )
        y = window_feature(self._acc, s.feature)
        if not np.isfinite(y):
            return Estimate(
                t_now, pos_now, "sensor_fault", "window feature undefined (zero variance?)", speed=v
            )
        try:
            grid, loglik = self.calibrator.log_likelihood_grid([[v]], [[y]])
        except ValueError as exc:  # the gpmsa errors are ValueError subclasses
            return Estimate(t_now, pos_now, "calibration_failed", str(exc), speed=v, feature=y)
        tracker, last_pos = self.trackers[chain], self._tracked_at[chain]
        tracker.predict(0.0 if last_pos is None else max(pos_now - last_pos, 0.0))
        power = self._fresh / s.buffer if s.method == "tempered" else 1.0
        tracker.update(np.ravel(grid), np.ravel(loglik), power=power)
        self._fresh = 0
        self._tracked_at[chain] = pos_now
        name = self.gd_name
        post = tracker.posterior(name)
        return Estimate(
            t_now,
            pos_now,
            "ok",
            gd_mean=post.mean(name),
            gd_sd=post.sd(name),
            interval=post.interval(name, s.interval_level),
            posterior=post,
            latency_s=_time.perf_counter() - tic,
            speed=v,
            feature=y,
        )

    def _check_age(self, est: Estimate) -> Estimate:
        """Replace an estimate older than max_age_s (by sample time) with a 'stale' status."""
        t_now, pos_now = self._now()
        age = t_now - est.time
        if est.ok and age > self.settings.max_age_s:
            return Estimate(
                t_now,
                pos_now,
                "stale",
                f"newest estimate is {age:.2f} s old (max_age_s = {self.settings.max_age_s:g})",
            )
        return est
