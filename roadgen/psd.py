"""PSD of a road and the GD it implies (ISO 8608 fixed-slope fit)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol

import numpy as np

from roadgen import checks
from roadgen.errors import RoadgenError, bound_text, distinct_texts
from roadgen.iso8608 import GD_SCALE, N0, check_waviness
from roadgen.profile import band_edges

FIT_BAND = (0.05, 1.0)
"""Default band of the GD fit, cycles/m: an octave below n0 to a decade above (20 m to 1 m
wavelengths). It keeps clear of the wheel-enveloping loss at high n and of the few, leaky
lowest bins, and holds 20 harmonics even on a 21 m road."""

WELCH_MIN_BIN = 6
"""Welch bins below this index are not fitted: there the Hann window's smoothing of a steep
spectrum is too large to correct."""

WELCH_MAX_WAVINESS = 3.5
"""method="welch" fits roads of waviness up to this (measured roads lie within 1.5-3.5): beyond
it the Hann window's leakage from the steep low frequencies outgrows the correction (150 m, 6
seeds: +2% at w = 4, +15% at 4.5, x2 at 5)."""

FIT_MIN_WAVINESS = 1.0
"""method="fit" fits roads of waviness from this (measured roads lie within 1.5-3.5): below it
the end match's line through two single heights, which then carry mostly short-wave content,
leaks more than the road's flat PSD holds in the band (150 m, 30 seeds: sd 1.3% and worst 6% at
w = 1, sd 18% and worst 86% at w = 0.5, against 0.06% at w = 2)."""

PSD_METHODS = ("periodogram", "welch")
GD_METHODS = ("fit", "welch", "periodogram")


class HasHeights(Protocol):
    """Anything with heights z (N,) m on a uniform grid of step dx_m (Profile, Track)."""

    @property
    def z(self) -> np.ndarray: ...
    @property
    def dx_m(self) -> float: ...


def profile_psd(
    road: HasHeights,
    method: str = "periodogram",
    nperseg: int | None = None,
    end_match: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """One-sided displacement PSD of a road: spatial frequencies n (M,) cycles/m > 0, Gd (M,) m^3.

    method: "periodogram" (scipy.signal.periodogram, boxcar window, mean removed: on roadgen's
        periodic profiles with deterministic amplitudes it returns Gd(n_k) exactly), or "welch"
        (scipy.signal.welch, Hann window, ``nperseg`` points per segment, default N // 4, 50%
        overlap, mean removed).
    end_match: periodogram only; subtract the line through the first and last heights instead of
        the mean. It removes the step that a non-periodic road (a track, a window cut from a
        road, a measured profile) has at the wrap-around, whose leakage falls like n^-2, as
        steeply as the road's own PSD; on periodic profiles it costs ~0.1% (150 m) to ~1% (21 m).

    Raises RoadgenError for an unknown method, a road without finite heights z (N,) and a grid
    step dx_m > 0, an nperseg that is not an integer in [8, N] (for "welch": a road of fewer than
    8 heights, or of fewer than 32 with the default nperseg), an end_match that is not a bool,
    and nperseg with "periodogram" or end_match=True with "welch" (they do not apply).
    """
    checks.choice("method", method, PSD_METHODS)
    z, dx = checks.heights("road", road)
    end_match = checks.flag("end_match", end_match)
    if method == "welch" and end_match:
        raise RoadgenError("end_match applies to method='periodogram' only, not 'welch'")
    if method == "periodogram" and nperseg is not None:
        raise RoadgenError("nperseg applies to method='welch' only, not 'periodogram'")
    if method == "welch" and z.size < 8:
        raise RoadgenError(f"method='welch' needs a road of >= 8 heights, got {z.size}")
    if nperseg is None and method == "welch" and z.size < 32:  # the default N // 4 needs 8
        raise RoadgenError(
            f"method='welch' with the default nperseg (N // 4) needs a road of >= 32 heights, "
            f"got {z.size}; give nperseg in [8, {z.size}] or use method='periodogram'"
        )
    seg = z.size // 4 if nperseg is None else checks.integer("nperseg", nperseg, 8)
    if method == "welch" and not 8 <= seg <= z.size:
        raise RoadgenError(f"nperseg={nperseg!r} is out of range: allowed [8, {z.size}]")
    return _psd(z, dx, method, seg, end_match)


def _psd(
    z: np.ndarray, dx: float, method: str, nperseg: int, end_match: bool
) -> tuple[np.ndarray, np.ndarray]:
    """``profile_psd`` of checked heights z (N,) m on a step dx m (n = 0 dropped)."""
    import scipy.signal  # here, not at import (tests/test_import_cost.py)

    # an overflow (inf, NaN) and an underflow (0): _finite_psd and _nonzero_gd name them
    with np.errstate(over="ignore", invalid="ignore", under="ignore"):
        if method == "periodogram":
            detrend = _end_match if end_match else "constant"
            n, gd = scipy.signal.periodogram(z, fs=1.0 / dx, window="boxcar", detrend=detrend)
        else:
            n, gd = scipy.signal.welch(
                z, fs=1.0 / dx, window="hann", nperseg=nperseg, detrend="constant"
            )
    return n[1:], _finite_psd(gd[1:], z)


def _fit_psd(
    z: np.ndarray, dx: float, method: str, nperseg: int, end_match: bool
) -> tuple[np.ndarray, np.ndarray]:
    """``_psd`` less the Nyquist bin of an even ``nperseg``, for the GD and slope fits: a
    one-sided PSD (scipy's) does not double that bin, which has no mirror image, so it reads
    half the density of a random road, and roadgen synthesises nothing there (an exact 0).
    RoadgenError for a road of 2 heights, whose only bin above 0 is the Nyquist bin."""
    if z.size < 3:
        raise RoadgenError(
            f"the road holds {z.size} heights: its only PSD bin above n = 0 is the Nyquist "
            f"frequency {0.5 / dx:.6g} cycles/m, which the GD and slope fits leave out; need >= 3 "
            "heights"
        )
    n, gd = _psd(z, dx, method, nperseg, end_match)
    return (n[:-1], gd[:-1]) if nperseg % 2 == 0 else (n, gd)


def _finite_psd(values: np.ndarray, z: np.ndarray) -> np.ndarray:
    """``values`` (a PSD, or a GD from it) if all finite; RoadgenError where heights z m so
    large that their squares overflow float64 made them inf or NaN."""
    if not np.all(np.isfinite(values)):
        raise RoadgenError(
            f"road.z holds heights up to {np.max(np.abs(z)):.3g} m: their PSD overflows "
            "float64; give heights in m"
        )
    return values


def estimate_gd(
    road: HasHeights,
    method: str = "fit",
    band: tuple[float, float] | None = None,
    waviness: float | None = None,
) -> float:
    """GD (units 1e-6 m^3) of a road from its displacement PSD.

    method:
      "fit" (default): fixed-slope fit Gd(n) = C (n/n0)^-w to the end-matched periodogram
          (``profile_psd(end_match=True)``, robust to non-periodic roads) over ``band`` (default
          FIT_BAND = (0.05, 1.0) cycles/m); C = mean of Gd(n_k) (n_k/n0)^w, the maximum-likelihood
          estimate for chi-squared periodogram ordinates. On roadgen's profiles with
          deterministic amplitudes its error over seeds has sd ~0.06% (150 m) and ~0.5% (21 m):
          95% of seeds within 0.15% and 1%, the worst of 300 within 0.3% and 2.5%.
      "welch": the same fit to the Welch PSD (``profile_psd(method="welch")``), skipping bins below
          index WELCH_MIN_BIN and dividing out the Hann window's first-order smoothing bias
          1 + w (w + 1) / (6 k^2) at bin k.
      "periodogram": the paper's check, the periodogram at the harmonic nearest n0 = 0.1 cycles/m,
          scaled to n0 along the slope (one ordinate, mean removed: exact for deterministic
          amplitudes, noisy for random ones).
    A road that records the band of its content (``settings.band`` of a Profile or Track) is
    fitted only inside it (edges as ``profile.band_edges``; Welch bins also keep 2 bins, the Hann
    window's main lobe, clear of its edges), and "periodogram" needs content at its harmonic.
    No method reads the Nyquist bin of an even record: scipy's one-sided PSD does not double it,
    so it holds half the density (and nothing, on roadgen's profiles).
    waviness: w of the fit; default the road's ``settings.waviness`` if it has one, else 2.
        "welch" takes w up to WELCH_MAX_WAVINESS (3.5), "fit" from FIT_MIN_WAVINESS (1).
    A road without roughness in the band (flat; for "fit" also a straight ramp, which the end
    match removes) gives 0.0.

    Raises RoadgenError for an unknown method, a bad band or waviness (or settings.band or
    settings.waviness), a waviness above 3.5 for "welch" or below 1 for "fit", a band outside
    the road's content band, a road of 2 heights or too short to hold a PSD bin in the band,
    heights whose PSD
    under- or overflows, and for "periodogram" a band (it reads one harmonic), a road without
    content at the harmonic nearest n0 or whose nearest harmonic lies more than
    PERIODOGRAM_REACH from n0 (a road under 5 m).
    """
    checks.choice("method", method, GD_METHODS)
    z, dx = checks.heights("road", road)
    w = _waviness(road, waviness)
    content = _content_band(road, dx)
    if method == "periodogram":
        if band is not None:
            raise RoadgenError(
                "band applies to method='fit' and 'welch'; method='periodogram' reads the one "
                f"harmonic nearest n0 = {N0} cycles/m"
            )
        return _nonzero_gd(lambda h: _periodogram_gd(h, dx, w, content), z)
    lo, hi = _fit_band(band, dx)
    if method == "welch" and w > WELCH_MAX_WAVINESS:
        most, w_text = distinct_texts(WELCH_MAX_WAVINESS, w)
        raise RoadgenError(
            f"method='welch' fits waviness up to WELCH_MAX_WAVINESS={most}, got "
            f"w={w_text}: beyond it the Hann window's leakage biases the estimate (x2 at w = 5); "
            "use method='fit'"
        )
    if method == "fit" and w < FIT_MIN_WAVINESS:
        least, w_text = distinct_texts(FIT_MIN_WAVINESS, w)
        raise RoadgenError(
            f"method='fit' fits waviness from FIT_MIN_WAVINESS={least}, got w={w_text}: below it "
            "the end match's leakage biases the estimate (sd 18%, worst 86% at w = 0.5 on 150 m); "
            "use method='welch' or, on a road made by roadgen without a lead-in, 'periodogram'"
        )
    if method == "welch" and z.size < 32:  # profile_psd's default segment, N // 4, holds 8
        raise RoadgenError(f"method='welch' needs a road of >= 32 heights, got {z.size}")
    return _nonzero_gd(lambda h: _fitted_gd(h, dx, method, (lo, hi), content, w), z)


def _fitted_gd(
    z: np.ndarray,
    dx: float,
    method: str,
    band: tuple[float, float],
    content: tuple[float, float] | None,
    w: float,
) -> float:
    """GD of checked heights z (N,) m on a step dx m: the fixed-slope (-w) fit over ``band``
    (cycles/m) of their end-matched periodogram ("fit") or Welch PSD ("welch")."""
    if method == "fit":
        n, gd = _fit_psd(z, dx, "periodogram", z.size, end_match=True)
        keep = _fit_bins(n, band, content, z.size, dx, method)
    else:
        n, gd = _fit_psd(z, dx, "welch", z.size // 4, end_match=False)
        keep = _fit_bins(n, band, content, z.size, dx, method)
        k = n / n[0]
        if not np.any(keep & (k >= WELCH_MIN_BIN)):
            raise _welch_too_short(band, float(n[keep][-1]), z.size, dx)
        keep &= k >= WELCH_MIN_BIN
        gd = gd / (1.0 + w * (w + 1.0) / (6.0 * k**2))
    return float(_finite_psd(np.mean(gd[keep] * (n[keep] / N0) ** w) / GD_SCALE, z))


def _nonzero_gd(estimate: Callable[[np.ndarray], float], z: np.ndarray) -> float:
    """``estimate(z)``, a GD from heights z (N,) m. Where it is 0 although z is not flat, it is
    computed again on z scaled by a power of 2 (exactly) to a largest |z| in [0.5, 1) m: a GD
    above 0 there means the heights are so small that their squares underflow float64
    (RoadgenError); 0 again means the road has no roughness in the band (a straight ramp with
    the end-matched fit), and 0.0 is returned."""
    value = estimate(z)
    if value == 0.0 and np.ptp(z) > 0.0:
        exponent = np.frexp(np.max(np.abs(z)))[1]
        if estimate(np.ldexp(z, -exponent)) > 0.0:
            raise RoadgenError(
                f"road.z holds heights of at most {np.max(np.abs(z)):.3g} m: their PSD "
                "underflows float64; give heights in m"
            )
    return value


PERIODOGRAM_REACH = 2.0
"""method="periodogram": how far (a factor) the harmonic it reads may lie from n0."""


def _periodogram_gd(
    z: np.ndarray, dx: float, w: float, content: tuple[float, float] | None
) -> float:
    """GD from the periodogram ordinate of z (N,) m nearest n0, scaled to n0 along slope -w."""
    n, gd = _fit_psd(z, dx, "periodogram", z.size, end_match=False)
    k = int(np.argmin(np.abs(np.log(n / N0))))
    if abs(np.log(n[k] / N0)) > np.log(PERIODOGRAM_REACH) + 1e-9:
        length, shortest = distinct_texts(z.size * dx, 1.0 / (PERIODOGRAM_REACH * N0))
        reach = (N0 / PERIODOGRAM_REACH, N0 * PERIODOGRAM_REACH)
        nearest, spacing = distinct_texts(n[k], 1.0 / (z.size * dx), *reach)[:2]
        raise RoadgenError(
            f"method='periodogram' reads the harmonic nearest n0 = {N0} cycles/m, but the "
            f"nearest of this road ({length} m: harmonics every "
            f"{spacing} cycles/m) is {nearest} cycles/m, more than a factor "
            f"{PERIODOGRAM_REACH:g} from n0; scaling it to n0 along the slope would extrapolate. "
            f"Use a road of at least {shortest} m"
        )
    if content is not None:
        edge_lo, edge_hi = band_edges(content, z.size)
        if not edge_lo <= n[k] <= edge_hi:
            nearest, low, high = distinct_texts(n[k], *content)
            raise RoadgenError(
                f"method='periodogram' reads the harmonic nearest n0 = {N0} cycles/m, "
                f"{nearest} cycles/m, but the road has no content there: its settings.band="
                f"({low}, {high}) cycles/m; use method='fit' with a band "
                "inside settings.band, or make the road with a band that holds n0"
            )
    return float(_finite_psd(gd[k] * (n[k] / N0) ** w / GD_SCALE, z))


def _fit_bins(
    n: np.ndarray,
    band: tuple[float, float],
    content: tuple[float, float] | None,
    n_points: int,
    dx: float,
    method: str | None,
) -> np.ndarray:
    """Mask of the PSD bins n (M,) cycles/m of a road of ``n_points`` heights on a step ``dx`` m
    that lie in ``band`` and, if known, in its ``content`` band (for "welch" 2 bins inside its
    edges); raises RoadgenError if none does, naming the cause (and ``method``, estimate_gd's;
    None for a caller without one, psd_slope)."""
    lo, hi = band
    how = "" if method is None else f" with method={method!r}"
    in_band = (n >= lo) & (n <= hi)
    if not np.any(in_band):
        raise RoadgenError(
            f"the road (length {n_points * dx:.6g} m) is too short for band=({lo:.6g}, {hi:.6g}) "
            f"cycles/m{how}: its PSD has no bin there (spacing {n[0]:.6g} "
            "cycles/m)"
        )
    if content is None:
        return in_band
    margin = 2.0 * n[0] if method == "welch" else 0.0
    edge_lo, edge_hi = band_edges(content, n_points)
    keep = in_band & (n >= edge_lo + margin) & (n <= edge_hi - margin)
    if not np.any(keep):
        clear = f" less 2 Welch bins ({margin:.6g} cycles/m) at each edge" if margin else ""
        lo_text, hi_text, low, high = distinct_texts(lo, hi, *content)
        raise RoadgenError(
            f"band=({lo_text}, {hi_text}) cycles/m holds no PSD bin of the road inside its "
            f"content band settings.band=({low}, {high}) cycles/m{clear}"
            f"{',' if how else ''}{how}: the road has no content there; "
            + (_welch_bins_text(n, edge_lo + margin, edge_hi - margin) if margin else
               "pass a band inside settings.band")
        )  # fmt: skip
    return keep


def _welch_bins_text(n: np.ndarray, lo: float, hi: float) -> str:
    """The remedy for a Welch fit whose band holds no bin of n (M,) cycles/m in [lo, hi] (the
    content band less its 2-bin margins): the bins it would fit (from WELCH_MIN_BIN up), a
    longer road, or method='fit' (no margins). The first and last are rounded inwards (a band
    that reaches either holds it), where a bin lies between them (a band from the first to the
    last then holds that one), else outwards (that band holds them: one bin reads as a range
    around it, not 1.33334 to 1.33333)."""
    usable = n[(n >= lo) & (n <= hi) & (n / n[0] >= WELCH_MIN_BIN)]  # as _fitted_gd
    if usable.size == 0:
        return "use a longer road, or method='fit'"
    inwards = usable.size > 2
    first, last = bound_text(usable[0], up=inwards), bound_text(usable[-1], up=not inwards)
    return (
        f"pass a band that holds one of the Welch bins it fits, {first} to {last} cycles/m "
        f"(every {n[0]:.6g} cycles/m), use a longer road, or method='fit'"
    )


def _welch_too_short(
    band: tuple[float, float], top: float, n_points: int, dx: float
) -> RoadgenError:
    """The error for a road whose Welch bins in ``band``, up to ``top`` cycles/m, all lie below
    WELCH_MIN_BIN."""
    seg = n_points // 4
    n_first = WELCH_MIN_BIN / (seg * dx)
    lo, hi, top_text, first = distinct_texts(*band, top, n_first)
    return RoadgenError(
        f"the road (length {n_points * dx:.6g} m) is too short for band=({lo}, {hi}) "
        f"cycles/m with method='welch': it fits only Welch bins from index "
        f"WELCH_MIN_BIN={WELCH_MIN_BIN} of its segments of N // 4 = {seg} heights "
        f"({seg * dx:.6g} m), n >= {first} cycles/m, and its bins in the band reach only "
        f"{top_text} cycles/m; use a road longer than {4 * WELCH_MIN_BIN / top:.3g} m, a band "
        f"reaching above {first} cycles/m, or method='fit'"
    )


def psd_slope(road: HasHeights, band: tuple[float, float] | None = None) -> float:
    """Least-squares slope of log Gd on log n over ``band`` (default FIT_BAND); ISO 8608: -2.

    As ``estimate_gd``, a road that records the band of its content (``settings.band``) is
    fitted only inside it; RoadgenError where ``band`` holds fewer than 2 bins with power there.
    """
    z, dx = checks.heights("road", road)
    lo, hi = _fit_band(band, dx)
    n, gd = _fit_psd(z, dx, "periodogram", z.size, end_match=True)
    in_band = (n >= lo) & (n <= hi)
    if np.count_nonzero(in_band) >= 2:
        in_band &= _fit_bins(n, (lo, hi), _content_band(road, dx), z.size, dx, None)
    keep = in_band & (gd > 0)
    if np.count_nonzero(keep) < 2:
        if np.count_nonzero((n >= lo) & (n <= hi)) < 2:
            length = z.size * dx
            why = (f"holds fewer than 2 PSD bins of this road ({length:.6g} m: bins every "
                   f"{1.0 / length:.6g} cycles/m)")  # fmt: skip
        elif np.count_nonzero(in_band) < 2:
            why = "holds fewer than 2 PSD bins inside the road's content band (settings.band)"
        else:
            why = "holds no power: the road is flat there (a constant or a straight ramp)"
        raise RoadgenError(f"band=({lo:.6g}, {hi:.6g}) {why}; no slope to fit")
    return float(np.polyfit(np.log(n[keep]), np.log(gd[keep]), 1)[0])


def _end_match(z: np.ndarray) -> np.ndarray:
    """z minus the straight line through its first and last values, along its last axis
    (scipy < 1.16 passes ``periodogram``'s detrend the segments as rows of a 2-D array)."""
    return z - np.linspace(z[..., 0], z[..., -1], z.shape[-1], axis=-1)


def _fit_band(band: tuple[float, float] | None, dx: float) -> tuple[float, float]:
    """The fit band (cycles/m): ``band`` checked against the Nyquist frequency 0.5 / dx, or
    FIT_BAND if None (RoadgenError naming the grid if it reaches above that frequency)."""
    nyquist = 0.5 / dx
    if band is not None:
        return checks.band("band", band, nyquist)
    if FIT_BAND[1] > nyquist:
        dx_text, most = distinct_texts(dx, 0.5 / FIT_BAND[1])
        nyq, top = distinct_texts(nyquist, *FIT_BAND)[0], bound_text(nyquist, up=False)
        raise RoadgenError(
            f"the grid dx_m={dx_text} m (Nyquist frequency {nyq} cycles/m) is too coarse "
            f"for the default fit band FIT_BAND={FIT_BAND} cycles/m: pass a band inside "
            f"(0, {top}] cycles/m, or use dx_m <= {most} m"
        )
    return FIT_BAND


def _waviness(road: HasHeights, waviness: float | None) -> float:
    """w of the fit: ``waviness``, else the road's ``settings.waviness`` (checked), else 2."""
    if waviness is not None:
        return check_waviness("waviness", waviness)
    value = getattr(getattr(road, "settings", None), "waviness", None)
    return 2.0 if value is None else check_waviness("road.settings.waviness", value)


def _content_band(road: HasHeights, dx: float) -> tuple[float, float] | None:
    """The road's ``settings.band`` (cycles/m, checked against the Nyquist frequency 0.5 / dx),
    or None if it records none."""
    value = getattr(getattr(road, "settings", None), "band", None)
    return None if value is None else checks.band("road.settings.band", value, 0.5 / dx)
