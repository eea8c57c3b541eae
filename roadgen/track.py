"""Tracks: consecutive segments of prescribed GD, joined without steps."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import overload

import numpy as np

from roadgen import checks
from roadgen.errors import RoadgenError, distinct_texts
from roadgen.profile import (
    ProfileSettings,
    check_settings,
    grid_points,
    lead_in_taper,
    unit_road,
)
from roadgen.road import Road


@dataclass(frozen=True, eq=False)
class Track(Road):
    """A road made of segments: x (N,) m, z (N,) m, dx_m and what it was made from.

    segments: ((length_m, gd), ...) in driving order, their lengths summing to the road's length
    within dx_m / 2; boundaries_m: start position of each segment (0 and the running sums of the
    lengths, to 1e-9 relative); lead_in_m: length of the start taper; blend_m: length of each
    amplitude cross-fade, centred on a boundary; settings: synthesis settings of the underlying
    road.
    """

    segments: tuple[tuple[float, float], ...]
    boundaries_m: tuple[float, ...]
    lead_in_m: float
    blend_m: float
    settings: ProfileSettings

    def __post_init__(self) -> None:
        super().__post_init__()
        segs = _check_segments(self.segments)
        starts = _check_boundaries(self.boundaries_m, segs)
        _check_total_length(segs, self.length_m, self.dx_m)
        object.__setattr__(self, "segments", segs)
        object.__setattr__(self, "boundaries_m", tuple(float(b) for b in starts))
        lead = checks.non_negative("lead_in_m", self.lead_in_m)
        blend = checks.positive("blend_m", self.blend_m)
        _check_blend_and_lead(segs, self.dx_m, blend, lead)
        check_settings(self.settings, self.dx_m, self.length_m)
        object.__setattr__(self, "lead_in_m", lead)
        object.__setattr__(self, "blend_m", blend)

    @overload
    def gd_at(self, s: float | np.floating) -> float: ...
    @overload
    def gd_at(self, s: np.ndarray | Sequence[float]) -> np.ndarray: ...
    def gd_at(self, s: float | np.floating | np.ndarray | Sequence[float]) -> float | np.ndarray:
        """Prescribed GD at positions ``s`` (m): that of the segment holding each position.

        This is the step function the paper scores against; the realised roughness changes over
        ``blend_m`` around each boundary and is tapered over the lead-in. Positions lie in [0,
        end], end the segments' total length or the road's, whichever is longer: the grid
        rounds the length to whole steps (by up to dx_m / 2), and the segments' own end stays
        a position of the last one. RoadgenError for a position outside, or NaN.
        """
        end = max(self.length_m, sum(length for length, _ in self.segments))
        arr = checks.positions("s", s, end)
        idx = np.searchsorted(np.asarray(self.boundaries_m), arr, side="right") - 1
        gds = np.array([g for _, g in self.segments])
        out = gds[np.clip(idx, 0, len(gds) - 1)]
        return float(out) if out.ndim == 0 else out


def track(
    segments: Sequence[tuple[float, float]],
    seed: int | np.integer | np.random.Generator | None = None,
    dx_m: float = 0.006,
    band: tuple[float, float] | None = None,
    amplitudes: str = "deterministic",
    waviness: float = 2.0,
    lead_in_m: float = 1.0,
    blend_m: float = 1.0,
) -> Track:
    """A track of segments [(length_m, gd), ...]; the paper's is [(50, 300), (50, 500), (50, 300)].

    One GD = 1 road is synthesised over the whole length (see ``iso8608_profile``: same band,
    amplitudes, waviness and seed rules) and multiplied by an amplitude a(x) = sqrt(GD(x)) that is
    constant in each segment and cross-fades with a raised cosine over ``blend_m`` (default 1 m)
    centred on each boundary. Heights are therefore continuous at the joins and each segment has
    exactly its prescribed PSD away from them. A raised-cosine lead-in over ``lead_in_m``
    (default 1 m) makes the track start at z = 0 with zero slope. x = 0 is the start of the first
    segment; the length is rounded to whole dx_m steps.

    Raises RoadgenError for an empty or malformed segment list, non-positive lengths or GDs,
    blend_m < 2 dx_m or longer than the shortest segment (two or more segments; one segment has
    no boundary to blend), a lead-in that reaches into the first blend (or past a single
    segment), and the band and length errors of ``iso8608_profile``.
    """
    segs = _check_segments(segments)
    dx = checks.grid_step("dx_m", dx_m)
    lead = checks.non_negative("lead_in_m", lead_in_m)
    blend = checks.positive("blend_m", blend_m)
    _check_blend_and_lead(segs, dx, blend, lead)
    lengths = np.array([length for length, _ in segs])
    n_points = grid_points(float(lengths.sum()), dx)
    if lead > (n_points - 1) * dx:  # one segment, its length rounded down to whole steps
        lead_text, end = distinct_texts(lead, (n_points - 1) * dx)
        raise RoadgenError(
            f"lead_in_m={lead_text} is out of range: allowed [0, {end}] m (the "
            f"track's length, {lengths.sum():g} m rounded to whole dx_m = {dx:g} m steps); "
            "shorten lead_in_m"
        )
    unit, settings = unit_road(n_points, dx, seed, band, amplitudes, waviness, lead)
    x = np.arange(n_points) * dx
    starts = np.concatenate([[0.0], np.cumsum(lengths)[:-1]])
    amp = _amplitude(x, starts, np.sqrt([g for _, g in segs]), blend)
    return Track(
        x=x,
        z=amp * lead_in_taper(x, lead) * unit,
        dx_m=dx,
        segments=segs,
        boundaries_m=tuple(float(b) for b in starts),
        lead_in_m=lead,
        blend_m=blend,
        settings=settings,
    )


def _amplitude(x: np.ndarray, starts: np.ndarray, amps: np.ndarray, blend: float) -> np.ndarray:
    """sqrt(GD) along x (N,): amps[0], then a raised-cosine step amps[i] - amps[i-1] per start.

    Each point sums, in driving order, step_i x c_i(x) with c_i = 0.5 (1 - cos(pi t_i)), t_i the
    clipped position in boundary i's blend: c_i is exactly 1 past the blend and exactly 0 before
    it. Boundaries lie at least ``blend`` apart, so only the last three that have begun can hold
    c_i < 1; the earlier ones add up to ``levels``, the running sum taken in the same order, and
    the result is bit for bit that of adding every boundary's step over the whole grid, at a
    cost of O(N) instead of O(N x segments).
    """
    steps, bounds = np.diff(amps), starts[1:]
    if bounds.size == 0:
        return np.full_like(x, amps[0])
    levels = np.cumsum(np.concatenate([amps[:1], steps]))  # sequential, in driving order
    begun = np.searchsorted(bounds - 0.5 * blend, x, side="right")  # one more adds 0.0
    first = np.maximum(begun - 2, 0)
    out = levels[first]
    for i in (first, first + 1, first + 2):
        k = np.minimum(i, bounds.size - 1)
        t = np.clip((x - bounds[k]) / blend + 0.5, 0.0, 1.0)
        out = np.where(i < bounds.size, out + steps[k] * 0.5 * (1.0 - np.cos(np.pi * t)), out)
    return out


def _check_blend_and_lead(
    segs: tuple[tuple[float, float], ...], dx: float, blend: float, lead: float
) -> None:
    """Raise RoadgenError unless ``blend`` (m) lies between two grid steps ``dx`` and the
    shortest segment, and the lead-in ``lead`` (m) ends before the first blend. A single segment
    has no boundary, hence no blend: only its lead-in is checked (against its length)."""
    lengths = np.array([length for length, _ in segs])
    if len(segs) > 1:
        _check_blend(lengths, dx, blend)
    lead_max = lengths[0] - (0.5 * blend if len(segs) > 1 else 0.0)
    if lead > lead_max:
        reach = f", less half of blend_m={blend:g} m" if len(segs) > 1 else ""
        lead_text, end = distinct_texts(lead, lead_max)
        raise RoadgenError(
            f"lead_in_m={lead_text} is out of range: allowed [0, {end}] m "
            f"(the first segment, {lengths[0]:g} m{reach}); lengthen the first segment or "
            "shorten lead_in_m"
        )


def _check_blend(lengths: np.ndarray, dx: float, blend: float) -> None:
    """Raise RoadgenError unless ``blend`` (m) lies between two grid steps ``dx`` and the
    shortest of the segments' ``lengths`` (m)."""
    if lengths.min() < 2 * dx:  # no blend fits: name the segment, not an empty range
        k = int(np.argmin(lengths))
        length, two_steps = distinct_texts(lengths[k], 2 * dx)
        raise RoadgenError(
            f"segment {k} is {length} m long, too short for any blend: shorter than two "
            f"grid steps (2 dx_m = {two_steps} m); lengthen it or merge it with a neighbour"
        )
    if not 2 * dx <= blend <= lengths.min():
        blend_text, low, high = distinct_texts(blend, 2 * dx, lengths.min())
        raise RoadgenError(
            f"blend_m={blend_text} is out of range: allowed [{low}, {high}] m "
            "(two grid steps to the shortest segment)"
        )


def _check_boundaries(
    boundaries: tuple[float, ...], segs: tuple[tuple[float, float], ...]
) -> np.ndarray:
    """``boundaries`` (m) as an array, or raise unless they are the segments' start positions: 0
    and the running sums of their lengths, within 1e-9 of the total length."""
    starts = checks.real_array("boundaries_m", boundaries)
    if starts.shape != (len(segs),) or not (
        np.all(np.isfinite(starts)) and np.all(np.diff(starts) > 0)
    ):
        raise RoadgenError(
            f"boundaries_m={boundaries!r} must hold one finite start position per segment "
            f"({len(segs)}), increasing"
        )
    lengths = np.array([length for length, _ in segs])
    expected = np.concatenate([[0.0], np.cumsum(lengths)[:-1]])
    if np.max(np.abs(starts - expected)) > 1e-9 * lengths.sum():
        shown = distinct_texts(*expected, *starts)[: expected.size]  # (not as the given ones)
        raise RoadgenError(
            f"boundaries_m={boundaries!r} do not match segments: a segment starts where the "
            f"previous one ends, at ({', '.join(shown)}) m"
        )
    return starts


def _check_total_length(
    segs: tuple[tuple[float, float], ...], length_m: float, dx_m: float
) -> None:
    """Raise unless the segments' lengths sum to ``length_m`` within dx_m / 2 (the rounding of a
    track's length to whole grid steps)."""
    total = sum(length for length, _ in segs)
    if abs(total - length_m) > 0.5 * dx_m + 1e-9 * total:
        span, length = distinct_texts(total, length_m)
        raise RoadgenError(
            f"segments span {span} m but the road (x) is {length} m long: they must "
            f"agree within dx_m / 2 = {0.5 * dx_m:g} m"
        )


def _check_segments(segments: Sequence[tuple[float, float]]) -> tuple[tuple[float, float], ...]:
    """``segments`` as ((length_m, gd), ...) floats, or RoadgenError naming the first bad one by
    its index (not the whole list, which may hold thousands)."""
    try:
        items = list(segments)
    except TypeError:
        raise RoadgenError(
            f"segments={segments!r} must be a sequence of (length_m, gd) pairs"
        ) from None
    if not items:
        raise RoadgenError(
            f"segments={segments!r} must be a non-empty sequence of (length_m, gd) pairs"
        )
    return tuple(_check_segment(i, seg) for i, seg in enumerate(items))


def _check_segment(i: int, seg: tuple[float, float]) -> tuple[float, float]:
    """Segment ``i`` as (length_m, gd) floats, or RoadgenError naming it."""
    try:
        pair = tuple(seg)
    except TypeError:
        pair = ()
    if len(pair) != 2:
        raise RoadgenError(
            f"segments[{i}]={seg!r} is not a (length_m, gd) pair: segments must be such pairs"
        )
    length = checks.positive(f"segments[{i}] length_m", pair[0])
    return length, checks.gd(f"segments[{i}] gd", pair[1])
