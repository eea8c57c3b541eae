"""Injected sensor faults: what a failing accelerometer, clock or odometer does to the samples."""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np

from control.errors import ControlError
from control.validation import check_instance, float_array, is_choice, require_reals

FAULT_KINDS = (
    "nan",  # the accelerometer reads NaN
    "drop",  # the samples never arrive
    "spike",  # every `magnitude`-th sample (rounded) is replaced by +-1e6 m/s^2 (spacing >= 1)
    "noise",  # N(0, magnitude^2) m/s^2 added
    "scale",  # the acceleration multiplied by magnitude
    "quantize",  # rounded to steps of magnitude m/s^2
    "stuck",  # the last good value repeated (held across batches by `FaultInjector`)
    "clip",  # clipped to +-magnitude m/s^2
    "time_nan",  # the time stamps read NaN
    "position_nan",  # the odometry reads NaN
)

MAX_SPIKE_SPACING = 2**62
"""Largest spike spacing counted, samples: a larger one (beyond numpy's integers) spikes the
fault's first sample alone, as any spacing longer than the fault does."""


@dataclass(frozen=True)
class SensorFault:
    """An injected fault over [start_s, start_s + duration_s) of sample time.

    Attributes:
        start_s: time the fault begins, s.
        duration_s: how long it lasts, s.
        kind: one of FAULT_KINDS (see there for what ``magnitude`` means).
        magnitude: the fault's size (kind-dependent; ignored by nan, drop, stuck, time_nan,
            position_nan).
    """

    start_s: float
    duration_s: float
    kind: str = "nan"
    magnitude: float = 1.0

    def __post_init__(self) -> None:
        require_reals(self, ("start_s", "duration_s", "magnitude"))
        if not (np.isfinite(self.start_s) and self.start_s >= 0):
            raise ControlError(f"start_s must be >= 0 and finite, got {self.start_s}")
        if not (np.isfinite(self.duration_s) and self.duration_s > 0):
            raise ControlError(f"duration_s must be > 0 and finite, got {self.duration_s}")
        if not is_choice(self.kind, FAULT_KINDS):
            raise ControlError(f"kind must be one of {FAULT_KINDS}, got {self.kind!r}")
        if not (np.isfinite(self.magnitude) and self.magnitude > 0):
            raise ControlError(f"magnitude must be finite and > 0, got {self.magnitude}")
        if self.kind == "spike" and self.magnitude < 1:
            raise ControlError(f"a spike fault's magnitude is a spacing >= 1, got {self.magnitude}")


class FaultInjector:
    """The faults applied to a stream of sample batches, one batch after another (a stuck sensor
    holds the value it read before the fault through every batch the fault spans). The samples
    do not depend on how the stream is split into batches (but where two noise faults overlap:
    each batch draws their noise in turn).

    Args:
        faults: the `SensorFault`s.
        rng: the generator of the random faults ("noise").

    A batch that raises part way (a KeyboardInterrupt) leaves the injector, its generator
    included, as it was before it. ``copy.copy`` (as ``copy.deepcopy``) gives an injector with
    its own copy of the generator and of what the stuck and spike faults hold: it continues as
    this one would, and applying either leaves the other as it was.
    """

    def __init__(self, faults, rng: np.random.Generator) -> None:
        if isinstance(faults, SensorFault):
            raise ControlError("faults must be a sequence of SensorFault: pass [fault]")
        try:
            if isinstance(faults, str | bytes):
                raise TypeError
            self.faults = tuple(faults)
        except TypeError:
            raise ControlError(
                f"faults must be a sequence of SensorFault, got {faults!r:.60}"
            ) from None
        for k, fault in enumerate(self.faults):
            check_instance(fault, f"faults[{k}]", SensorFault)
        check_instance(rng, "rng", np.random.Generator)
        self.rng = rng
        # per stuck fault, the newest finite reading of the batches before, with the faults
        # listed before it applied (as it reads the samples before it in its own batch)
        self._read: dict[int, float] = {}
        self._held: dict[int, float] = {}  # per stuck fault, the value it holds
        self._spiked: dict[int, int] = {}  # per spike fault, the samples it has covered so far
        self._spans = _spans(self.faults)

    def __copy__(self) -> FaultInjector:
        """``copy.copy``: a deep copy (a shallow one shared the generator and the held values,
        so that the copy's batches changed the original's next ones)."""
        return copy.deepcopy(self)

    def __setstate__(self, state: dict) -> None:
        """Unpickling: one pickled before session 83 kept one newest reading, with every fault
        applied, for all its stuck faults."""
        last = state.pop("_last", np.nan)
        stuck = [i for i, f in enumerate(state["faults"]) if f.kind == "stuck"]
        state.setdefault("_read", {i: last for i in stuck if np.isfinite(last)})
        state.setdefault("_spans", _spans(state["faults"]))  # (one pickled before session 85)
        self.__dict__.update(state)

    def __call__(self, t, position, accel, speed):
        """(t, position, accel, speed) of the next batch with the faults applied (copies)."""
        t, pos = _batch("t", t), _batch("position", position)
        acc, spd = _batch("accel", accel), _batch("speed", speed)
        if not t.size == pos.size == acc.size == spd.size:
            raise ControlError(
                f"t, position, accel and speed must have one length, got {t.size}, {pos.size}, "
                f"{acc.size} and {spd.size}"
            )
        keep = np.ones(t.size, dtype=bool)
        clock = t.copy()
        # kept once the batch is done
        spiked, held, read = dict(self._spiked), dict(self._held), dict(self._read)
        drawn = self.rng.bit_generator.state if self.faults else None  # (~2 us)
        try:
            self._apply(t, pos, acc, clock, keep, spiked, held, read)
            # (inside the try: an interrupt here, after the generator drew, undoes that too)
            batch = t[keep], pos[keep], acc[keep], spd[keep]
        except BaseException:  # (a KeyboardInterrupt): the injector as before the batch
            if drawn is not None:
                self.rng.bit_generator.state = drawn
            raise
        self._spiked, self._held, self._read = spiked, held, read  # (no call between them)
        return batch

    def _apply(self, t, pos, acc, clock, keep, spiked: dict, held: dict, read: dict) -> None:
        """Apply the faults to a batch's arrays in place; ``spiked``, ``held`` and ``read``:
        copies of the spike counts, stuck values and stuck faults' newest readings, updated
        (`__call__` keeps them once all went well). Only the faults whose span may reach the
        batch's times (and the stuck ones, which read every batch before theirs) are visited:
        a long stream with a fault every few seconds costs per batch what its own faults do."""
        for i in self._visited(clock).tolist():
            fault = self.faults[i]
            hit = (clock >= fault.start_s) & (clock < fault.start_s + fault.duration_s)
            if fault.kind == "stuck" and i not in held:
                self._before(acc, hit, i, read)
            if not hit.any():
                continue
            k, m = fault.kind, fault.magnitude
            if k == "nan":
                acc[hit] = np.nan
            elif k == "drop":
                keep &= ~hit
            elif k == "spike":
                # counted over the fault's whole span, not per batch: the nearest whole spacing
                every, seen = max(1, round(min(m, MAX_SPIKE_SPACING))), spiked.get(i, 0)
                covered = seen + np.arange(int(hit.sum()))
                on = covered % every == 0
                acc[np.flatnonzero(hit)[on]] = 1e6 * np.where((covered[on] // every) % 2, 1.0, -1.0)
                spiked[i] = seen + int(hit.sum())
            elif k == "noise":
                acc[hit] += self.rng.normal(0.0, m, int(hit.sum()))
            elif k == "scale":
                acc[hit] *= m
            elif k == "quantize":
                with np.errstate(over="ignore"):  # a step far below a reading's resolution
                    steps = np.round(acc[hit] / m) * m
                acc[hit] = np.where(np.isfinite(steps), steps, acc[hit])  # ... leaves it
            elif k == "stuck":  # the reading before it (the first one if none came)
                acc[hit] = held.setdefault(i, read.get(i, float(acc[np.argmax(hit)])))
            elif k == "clip":
                acc[hit] = np.clip(acc[hit], -m, m)
            elif k == "time_nan":
                t[hit] = np.nan
            elif k == "position_nan":
                pos[hit] = np.nan

    def _visited(self, clock: np.ndarray) -> np.ndarray:
        """Indices, in list order, of the faults `_apply` visits for a batch at times
        ``clock``: every fault but those whose [start_s, start_s + duration_s) lies wholly
        before or after the batch's finite times (such a fault hits none of its samples)."""
        start, end, stuck = self._spans
        times = clock[~np.isnan(clock)]
        if not times.size:
            return np.flatnonzero(stuck)
        return np.flatnonzero(((start <= times.max()) & (end > times.min())) | stuck)

    @staticmethod
    def _before(acc: np.ndarray, hit: np.ndarray, i: int, read: dict) -> None:
        """Keep in ``read[i]`` the newest finite reading of ``acc`` before the first sample of
        ``hit`` (all of them where none is hit), the value stuck fault ``i`` holds once it
        begins: ``acc`` as the faults listed before it left it, in this batch or the ones
        before (a stuck fault after a NaN fault holds the value before the NaNs)."""
        finite = np.flatnonzero(np.isfinite(acc[: np.argmax(hit) if hit.any() else None]))
        if finite.size:
            read[i] = float(acc[finite[-1]])


def _spans(faults: tuple[SensorFault, ...]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(start, end, stuck) per fault: its start_s and start_s + duration_s as floats, each
    widened by one ulp (a start or duration given as an int or a numpy scalar rounds to the
    nearest float: the span stays one that holds every time its fault hits), and whether it is
    a stuck fault."""
    start = np.array([float(f.start_s) for f in faults], dtype=float)
    end = np.array([float(f.start_s + f.duration_s) for f in faults], dtype=float)
    stuck = np.array([f.kind == "stuck" for f in faults], dtype=bool)
    with np.errstate(under="ignore"):  # one ulp from 0 is a subnormal
        return np.nextafter(start, -np.inf), np.nextafter(end, np.inf), stuck


def _batch(name: str, value) -> np.ndarray:
    """A batch's ``value`` as a 1-D float array (a copy); `ControlError` naming ``name`` for
    what is not a 1-D sequence of real numbers."""
    arr = float_array(value, name)
    if arr.ndim != 1:
        raise ControlError(f"{name} must be 1-D, got shape {arr.shape}")
    return arr
