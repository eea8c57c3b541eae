"""Scores of a closed-loop run: RMSE of the GD estimate, detection delays, speed on rough ground;
means over many runs with their clustered standard errors; reports as strict JSON."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from control.errors import ControlError
from control.validation import float_array, is_real
from gpmsa.io.container import jsonable


@dataclass(frozen=True)
class GDError:
    """Squared-error sums of the GD estimate over the parts of a track with one prescribed GD.

    Attributes:
        gd: the prescribed GD of those parts.
        sse: sum of squared errors of the estimates (posterior means) there.
        n: number of estimates there.
    """

    gd: float
    sse: float
    n: int

    @property
    def rmse(self) -> float:
        """Root mean squared error (NaN without estimates)."""
        return float(np.sqrt(self.sse / self.n)) if self.n else np.nan


def _track_parts(track) -> tuple[np.ndarray, np.ndarray]:
    """(start of each segment, m; its prescribed GD) of ``track``: `ControlError` naming what is
    wrong where it lacks a roadgen Track's ``segments`` ((length_m, gd) pairs) and
    ``boundaries_m`` (one finite start per segment, increasing)."""
    for name in ("segments", "boundaries_m"):
        if not hasattr(track, name):
            raise ControlError(
                f"track must be a roadgen Track (segments, boundaries_m), got {track!r:.60} "
                f"({type(track).__name__}), which has no {name}"
            )
    try:
        seg_gd = np.array([gd for _, gd in track.segments], dtype=float)
        starts = np.asarray(track.boundaries_m, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ControlError(
            f"track.segments must hold (length_m, gd) pairs and track.boundaries_m numbers: {exc}"
        ) from exc
    if not seg_gd.size:
        raise ControlError("track has no segment")
    if starts.shape != seg_gd.shape:
        raise ControlError(
            f"track.boundaries_m must hold one start per segment, got {starts.size} for "
            f"{seg_gd.size} segments"
        )
    if not (np.all(np.isfinite(starts)) and np.all(np.diff(starts) > 0)):
        raise ControlError(f"track.boundaries_m must be finite and increasing, got {starts}")
    return starts, seg_gd


def _check_on_track(track, starts: np.ndarray, position: np.ndarray) -> None:
    """ControlError for a finite position off ``track``: before its first segment's start or
    past its end (the segments' total length or ``track.length_m``, whichever is longer, as
    `roadgen.Track.gd_at` reads it), within 1e-9 of its span; the metrics would charge it to
    the first or last segment (a position in mm, say, all to the last one)."""
    end = float(starts[-1]) + _last_length(track)
    length = getattr(track, "length_m", None)
    if is_real(length) and np.isfinite(length):
        end = max(end, float(length))
    lo = float(starts[0])
    tol = 1e-9 * max(end - lo, 1.0)
    off = np.isfinite(position) & ((position < lo - tol) | (position > end + tol))
    if off.any():
        k = int(np.flatnonzero(off)[0])
        raise ControlError(
            f"position holds {position[k]:g} m at index {k}: off the track, which spans "
            f"[{lo:g}, {end:g}] m: give positions on it, in metres (as the run's)"
        )


def _last_length(track) -> float:
    """Length of ``track``'s last segment, m (0 where it is not a finite number >= 0)."""
    try:
        length = float(track.segments[-1][0])
    except (TypeError, ValueError, IndexError):
        return 0.0
    return length if np.isfinite(length) and length >= 0 else 0.0


def segment_index(track, position: np.ndarray) -> np.ndarray:
    """Index of the track segment holding each position (clipped to the first/last segment).
    `ControlError` for a position that is NaN (it lies in no segment: leave it out first) and
    for a ``track`` without a roadgen Track's segments and boundaries_m."""
    starts, _ = _track_parts(track)
    position = float_array(position, "position")
    if np.isnan(position).any():
        raise ControlError(
            f"position holds NaN at index {int(np.flatnonzero(np.isnan(position))[0])}: a "
            "position that is NaN lies in no segment (leave it out first)"
        )
    return _segment_of(starts, position)


def _segment_of(starts: np.ndarray, position: np.ndarray) -> np.ndarray:
    """`segment_index` of checked segment starts and positions (no NaN)."""
    idx = np.searchsorted(starts, position, side="right") - 1
    return np.clip(idx, 0, starts.size - 1)


def _traces(position, values, name: str) -> tuple[np.ndarray, np.ndarray]:
    """(position, values) as 1-D float arrays of one length; ControlError naming the problem."""
    position = float_array(position, "position")
    values = float_array(values, name)
    if position.ndim != 1 or position.shape != values.shape:
        raise ControlError(
            f"position and {name} must be 1-D of one length, got shapes {position.shape} and "
            f"{values.shape}"
        )
    return position, values


def gd_errors(track, position: np.ndarray, gd_estimate: np.ndarray) -> tuple[GDError, ...]:
    """Errors of the estimates against the prescribed GD at each estimate's position, as the paper.

    Args:
        track: a roadgen Track (segments, boundaries_m).
        position: (n,) positions of the estimates (front axle when the estimate was made), m,
            on the track (`ControlError` for a finite one off it).
        gd_estimate: (n,) posterior means; NaN entries (no estimate), and estimates without a
            finite position, are left out.

    Returns:
        One `GDError` per distinct prescribed GD, in increasing GD.
    """
    position, gd_estimate = _traces(position, gd_estimate, "gd_estimate")
    starts, seg_gd = _track_parts(track)
    _check_on_track(track, starts, position)
    ok = np.isfinite(gd_estimate) & np.isfinite(position)
    gds, part = np.unique(seg_gd, return_inverse=True)
    part = part[_segment_of(starts, position[ok])]  # the distinct GD of each kept estimate
    part[np.isnan(gds[part])] = gds.size  # a GD that is NaN matches no estimate
    # each GD's estimates in one slice, in their order (stable): the sums of a mask per GD,
    # bit for bit, in one pass rather than one per distinct GD
    order = np.argsort(part, kind="stable")
    values = gd_estimate[ok][order]
    edges = np.searchsorted(part[order], np.arange(gds.size + 1))
    out = []
    for k, gd in enumerate(gds):
        sel = values[edges[k] : edges[k + 1]]
        out.append(GDError(float(gd), float(np.sum((sel - gd) ** 2)), int(sel.size)))
    return tuple(out)


def pooled_rmse(errors: Sequence[Sequence[GDError]], gd: float) -> float:
    """RMSE at prescribed GD `gd` pooled over several runs (all their estimates together).

    NaN when no run made an estimate there (a part shorter than the first block), as
    `GDError.rmse` for one run; ControlError when no run has a part at ``gd`` at all (a GD
    mistyped would otherwise read as "no estimate").

    Args:
        errors: per run, its `GDError`s (``[r.metrics.gd_errors for r in results]``; any
            iterable, read once).
    """
    if not is_real(gd):
        raise ControlError(f"gd must be a real number (1e-6 m^3), got {gd!r}")
    try:
        errors = [run if isinstance(run, GDError) else tuple(run) for run in errors]
    except TypeError as exc:
        raise ControlError(f"errors must hold one sequence of GDError per run: {exc}") from exc
    if any(isinstance(run, GDError) for run in errors):
        raise ControlError(
            "errors must hold one sequence of GDError per run; for one run's errors pass "
            "[metrics.gd_errors]"
        )
    for k, run in enumerate(errors):
        for e in run:
            if not isinstance(e, GDError):
                raise ControlError(f"errors[{k}] holds {e!r:.60}, not a GDError")
    parts = sorted({e.gd for run in errors for e in run})
    if gd not in parts:
        raise ControlError(
            f"no run has a part at GD {gd!r}; the runs' parts are at GD "
            f"{', '.join(f'{g:g}' for g in parts) or 'none'}"
        )
    sse = sum(e.sse for run in errors for e in run if e.gd == gd)
    n = sum(e.n for run in errors for e in run if e.gd == gd)
    return float(np.sqrt(sse / n)) if n else float("nan")


def clustered_mean(per_run: Sequence) -> tuple[float, float]:
    """Mean of values pooled over runs, and its standard error clustered by run.

    The estimates of one run share its road and its filter's excursions, so they are not
    independent; the standard error treats each run as one draw (the cluster-robust sandwich
    with the small-sample factor G / (G - 1), G runs with values).

    Args:
        per_run: per run, a 1-D sequence of finite values (e.g. one run's relative errors);
            runs with no values are left out.

    Returns:
        (mean, standard error); NaN for the mean without values and for the standard error
        with fewer than two runs that have values.
    """
    try:
        runs = [float_array(x, f"per_run[{k}]") for k, x in enumerate(per_run)]
    except TypeError as exc:  # (float_array raises ControlError for what it refuses)
        raise ControlError(f"per_run must hold one sequence of values per run: {exc}") from exc
    for k, x in enumerate(runs):
        if x.ndim != 1 or not np.all(np.isfinite(x)):
            raise ControlError(
                f"per_run[{k}] must be a 1-D sequence of finite values (one run's); for one "
                "run's values pass [values]"
            )
    runs = [x for x in runs if x.size]
    if not runs:
        return float("nan"), float("nan")
    n = np.array([x.size for x in runs], dtype=float)
    sums = np.array([x.sum() for x in runs])
    mean = float(sums.sum() / n.sum())
    if len(runs) < 2:
        return mean, float("nan")
    scatter = np.sqrt(np.sum((sums - mean * n) ** 2)) / n.sum()
    return mean, float(scatter * np.sqrt(len(runs) / (len(runs) - 1)))


def detection_delays(track, position: np.ndarray, gd_estimate: np.ndarray) -> tuple[float, ...]:
    """Distance past each GD change until the estimate first crosses the midpoint of the two GDs, m.

    One value per boundary between segments of different GD; NaN if the estimate never crosses
    before the next change of GD (adjacent segments of one GD are one part; or the end of the
    data). ``position`` and ``gd_estimate`` are (n,) in time order ("first" is first in time),
    positions on the track (`ControlError` for a finite one off it); estimates that are not
    finite (NaN: none) detect nothing, as in `gd_errors`.
    """
    position, gd_estimate = _traces(position, gd_estimate, "gd_estimate")
    starts, seg_gd = _track_parts(track)
    _check_on_track(track, starts, position)
    # each change of GD k watches from its start to the next change: [starts[k], starts[next])
    change = np.flatnonzero(seg_gd[1:] != seg_gd[:-1]) + 1  # (a NaN GD differs from all)
    before, after = seg_gd[change - 1], seg_gd[change]
    mid = (before + after) / 2
    delays = np.full(change.size, np.nan)
    seen = np.flatnonzero(np.isfinite(position) & np.isfinite(gd_estimate))
    w = np.searchsorted(starts[change], position[seen], side="right") - 1  # the change watching
    seen, w = seen[w >= 0], w[w >= 0]
    est, m = gd_estimate[seen], mid[w]
    crossed = np.where(after[w] > before[w], est > m, est < m)
    first, at = np.unique(w[crossed], return_index=True)  # the first in time of each change
    hit = seen[crossed][at]
    delays[first] = position[hit] - starts[change[first]]
    return tuple(float(d) for d in delays)


def interval_coverage(
    gd_mean: np.ndarray, gd_lo: np.ndarray, gd_hi: np.ndarray, gd_true: np.ndarray
) -> float:
    """Fraction of the estimates (those with a finite posterior mean ``gd_mean``) whose credible
    interval [gd_lo, gd_hi] holds the prescribed GD ``gd_true``, both ends included: an interval
    may end exactly at a domain bound that is the truth (a part at GD 200 or 600); one with a
    NaN end holds nothing. NaN where no estimate has a finite mean.

    Args:
        gd_mean, gd_lo, gd_hi, gd_true: (n,) each, 1e-6 m^3.
    """
    arrays = [float_array(a, n) for a, n in ((gd_mean, "gd_mean"), (gd_lo, "gd_lo"),
                                            (gd_hi, "gd_hi"), (gd_true, "gd_true"))]  # fmt: skip
    gd_mean, gd_lo, gd_hi, gd_true = arrays
    if gd_mean.ndim != 1 or any(a.shape != gd_mean.shape for a in arrays):
        shapes = ", ".join(str(a.shape) for a in arrays)
        raise ControlError(
            f"gd_mean, gd_lo, gd_hi and gd_true must be 1-D of one length, got shapes {shapes}"
        )
    ok = np.isfinite(gd_mean)
    if not ok.any():
        return float("nan")
    return float(np.mean((gd_lo[ok] <= gd_true[ok]) & (gd_true[ok] <= gd_hi[ok])))


def fast_on_rough_m(
    track, position: np.ndarray, speed: np.ndarray, gd_max: float, v_safe: float, tol: float = 0.02
) -> float:
    """Distance driven faster than v_safe + tol (m/s) where the prescribed GD exceeds gd_max, m.

    Args:
        position, speed: (n,) the vehicle's samples (front axle), m (finite, non-decreasing,
            on the track) and m/s.
        gd_max, v_safe: the Simplex's (> 0, as `Simplex` requires). tol: >= 0, m/s.
    """
    for name, value, zero_ok in (
        ("gd_max", gd_max, False),
        ("v_safe", v_safe, False),
        ("tol", tol, True),
    ):
        if not (is_real(value) and np.isfinite(value) and (value > 0 or (zero_ok and value == 0))):
            bound = ">= 0" if zero_ok else "> 0"
            raise ControlError(f"{name} must be a finite real number {bound}, got {value!r}")
    starts, seg_gd = _track_parts(track)
    position, speed = _traces(position, speed, "speed")
    if not (np.all(np.isfinite(position)) and np.all(np.diff(position) >= 0)):
        raise ControlError("position must hold finite, non-decreasing samples, m")
    if not np.all(np.isfinite(speed)):
        raise ControlError("speed must hold finite samples, m/s")
    _check_on_track(track, starts, position)
    if position.size < 2:
        return 0.0
    mid = 0.5 * (position[1:] + position[:-1])
    rough = seg_gd[_segment_of(starts, mid)] > gd_max
    fast = 0.5 * (speed[1:] + speed[:-1]) > v_safe + tol
    return float(np.sum(np.diff(position)[rough & fast]))


def strict_json(value):
    """``value`` (dicts, lists, tuples, numbers, strings) ready for ``json.dumps(...,
    allow_nan=False)``: numpy scalars as Python's, floats that are not finite (NaN, inf) as None
    (JSON's null), tuples as lists, keys as strings (``gpmsa.io.container.jsonable``, which the
    emulator files use)."""
    return jsonable(value)
