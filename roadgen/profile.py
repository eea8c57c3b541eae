"""ISO 8608 road profiles synthesised from random-phase harmonics (one inverse FFT)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import overload

import numpy as np

from roadgen import checks
from roadgen.errors import RoadgenError, bound_text, distinct_texts
from roadgen.iso8608 import check_waviness, gd_spectrum
from roadgen.road import Road

AMPLITUDE_MODES = ("deterministic", "rayleigh")


@dataclass(frozen=True)
class ProfileSettings:
    """How a profile was made.

    band: (n_min, n_max) cycles/m, the spatial frequencies that carry content (as resolved);
        a pair given as a list or an array is stored as a tuple of two floats.
    amplitudes: "deterministic" (each harmonic carries exactly Gd(n_k) dn) or "rayleigh"
        (Rayleigh-distributed amplitudes, i.e. a Gaussian process with that mean PSD).
    waviness: w in Gd(n) = Gd(n0) (n/n0)^-w, in (0, MAX_WAVINESS = 5] (ISO 8608: 2).
    seed: the integer seed, or None when a Generator or fresh entropy was used.
    lead_in_m: length of the raised-cosine taper from z = 0 at the start, m (0: none).

    RoadgenError, naming the field, for a value outside these (a road bounds the band by its
    Nyquist frequency and the lead-in by its length when it is made with the settings).
    """

    band: tuple[float, float]
    amplitudes: str
    waviness: float
    seed: int | None
    lead_in_m: float

    def __post_init__(self) -> None:
        lo, hi = checks.pair("band", self.band, "(n_min, n_max) in cycles/m")
        if not (math.isfinite(hi) and 0.0 < lo < hi):
            raise RoadgenError(
                f"band={self.band!r} is out of range: need 0 < n_min < n_max, finite, cycles/m"
            )
        # stored as a tuple of floats (a list or an array given made the settings unhashable,
        # and == between two of them raise "truth value of an array is ambiguous")
        object.__setattr__(self, "band", (lo, hi))
        checks.choice("amplitudes", self.amplitudes, AMPLITUDE_MODES)
        check_waviness("waviness", self.waviness)
        checks.seed("seed", self.seed, generator=False)
        checks.non_negative("lead_in_m", self.lead_in_m, unit="m")

    def __setstate__(self, state: dict) -> None:
        """Unpickling: a band pickled as given (a list or an array, before it was stored as a
        tuple) is read as the tuple of two floats that ``__post_init__`` stores."""
        self.__dict__.update(state)
        band = state.get("band")
        if isinstance(band, (list, np.ndarray)):
            object.__setattr__(self, "band", checks.pair("band", band, "(n_min, n_max)"))


@dataclass(frozen=True, eq=False)
class Profile(Road):
    """A road of one prescribed GD: x (N,) m, z (N,) m, dx_m, gd (1e-6 m^3), settings."""

    gd: float
    settings: ProfileSettings

    def __post_init__(self) -> None:
        super().__post_init__()
        object.__setattr__(self, "gd", checks.gd("gd", self.gd))
        check_settings(self.settings, self.dx_m, self.length_m)

    @overload
    def gd_at(self, s: float | np.floating) -> float: ...
    @overload
    def gd_at(self, s: np.ndarray | Sequence[float]) -> np.ndarray: ...
    def gd_at(self, s: float | np.floating | np.ndarray | Sequence[float]) -> float | np.ndarray:
        """Prescribed GD at positions ``s`` (m): the constant ``gd``, shaped like ``s``."""
        arr = checks.positions("s", s, self.length_m)
        out = np.full(arr.shape, self.gd)
        return float(out) if out.ndim == 0 else out


def iso8608_profile(
    length_m: float,
    gd: float,
    dx_m: float = 0.006,
    seed: int | np.integer | np.random.Generator | None = None,
    band: tuple[float, float] | None = None,
    amplitudes: str = "deterministic",
    waviness: float = 2.0,
    lead_in_m: float = 0.0,
) -> Profile:
    """A random road profile whose one-sided displacement PSD is Gd(n) = GD 1e-6 (n/0.1)^-w m^3.

    Grid: ``N = round(length_m / dx_m) + 1`` points x = 0, dx_m, ..., length_m (the length is
    rounded to whole steps). The profile is one period, of length ``P = N dx_m``, of a sum of
    cosines at the periodogram's frequencies n_k = k / P with random phases and amplitudes
    ``A_k = sqrt(2 Gd(n_k) / P)`` (times a unit-power Rayleigh factor for
    ``amplitudes="rayleigh"``), so the boxcar periodogram of ``z`` returns Gd(n_k) exactly at
    every harmonic in the band (deterministic amplitudes). It is computed by one inverse real FFT.

    band: (n_min, n_max) cycles/m with ``1/P <= n_min < n_max <= 1/(2 dx_m)``. Default: every
        harmonic the grid holds, from the fundamental 1/P to the Nyquist limit 1/(2 dx_m)
        (83.3 cycles/m at 6 mm). The upper limit matters: a vehicle at 0.5 m/s sees 10 cycles/m
        as 5 Hz, so a band that stops there would hide the road from its ~10 Hz tyre modes.
        The Nyquist harmonic itself is never used (it has no phase). The edges are inclusive,
        n_min within a relative 1/N (see ``band_edges``): band=(0.1, ...) on a 150 m road keeps
        the harmonic k = 15 at 15 / 150.006 m = 0.099996 cycles/m, the paper's n0.
    waviness: w, in (0, MAX_WAVINESS = 5] (ISO 8608: 2).
    lead_in_m: if > 0, z is multiplied by 0.5 (1 - cos(pi x / lead_in_m)) on [0, lead_in_m], so the
        road starts at z = 0 with zero slope (the vehicle's rest height). The taper is road
        content: it brings z from 0 to the road's long-wave height within lead_in_m, so a GD
        estimate over a stretch that starts with it reads high (a 1 m lead-in, the first 50 m of
        a 150 m road at GD 300, 200 seeds: 347 against 297.5 without it); skip it, as the
        campaign's f_full does.
    seed: int or numpy Generator; the same seed gives the same profile. The phases (and Rayleigh
        factors) do not depend on GD, so one seed gives the same shape scaled by sqrt(GD) for
        every GD: use different seeds for independent roads.

    Raises RoadgenError for a non-positive or non-finite length, a GD below ``checks.MIN_GD`` or
    not finite, a dx outside [``checks.MIN_DX_M``, ``checks.MAX_DX_M``] or above length_m / 1.5
    (fewer than 2 steps), a waviness outside (0, 5], a band outside (0, Nyquist], a length
    shorter than 1/n_min, or a band without harmonics.
    """
    length = checks.positive("length_m", length_m)
    gd_val = checks.gd("gd", gd)
    dx = checks.grid_step("dx_m", dx_m)
    lead = checks.non_negative("lead_in_m", lead_in_m)
    n_points = grid_points(length, dx)
    if lead > (n_points - 1) * dx:
        end = distinct_texts(lead, (n_points - 1) * dx)[1]
        raise RoadgenError(f"lead_in_m={lead_in_m!r} is out of range: allowed [0, {end}] m")
    unit, settings = unit_road(n_points, dx, seed, band, amplitudes, waviness, lead)
    z = np.sqrt(gd_val) * unit * lead_in_taper(np.arange(n_points) * dx, lead)
    return Profile(x=np.arange(n_points) * dx, z=z, dx_m=dx, gd=gd_val, settings=settings)


def unit_road(
    n_points: int,
    dx_m: float,
    seed: int | np.integer | np.random.Generator | None,
    band: tuple[float, float] | None,
    amplitudes: str,
    waviness: float,
    lead_in_m: float,
    *,
    length_name: str = "length_m",
) -> tuple[np.ndarray, ProfileSettings]:
    """Heights (n_points,) m of a GD = 1 profile on the grid, and the resolved settings;
    ``length_name``: the caller's name for the road's length in a band-too-long error."""
    checks.choice("amplitudes", amplitudes, AMPLITUDE_MODES)
    w = check_waviness("waviness", waviness)
    period = n_points * dx_m
    nyquist = 0.5 / dx_m
    dn = 1.0 / period
    if band is None:
        lo, hi = dn, nyquist
    else:
        lo, hi = checks.band("band", band, nyquist)
        if lo < dn * (1.0 - 1e-9):
            raise _short_for_band(band, lo, n_points, dx_m, length_name)
    k = np.arange(n_points // 2 + 1)
    n = k * dn
    edge_lo, edge_hi = band_edges((lo, hi), n_points)
    keep = (k >= 1) & (2 * k < n_points) & (n >= edge_lo) & (n <= edge_hi)
    if not np.any(keep):
        raise RoadgenError(
            f"band={band!r} holds no harmonic of the profile (spacing {dn:.6g} cycles/m): widen it "
            f"or lengthen the profile"
        )
    rng = np.random.default_rng(checks.seed("seed", seed))
    n_keep = int(np.count_nonzero(keep))
    phase = rng.uniform(0.0, 2.0 * np.pi, n_keep)
    amp = np.sqrt(2.0 * gd_spectrum(n[keep], 1.0, w) * dn)
    if amplitudes == "rayleigh":
        amp = amp * rng.rayleigh(scale=np.sqrt(0.5), size=n_keep)
    spectrum = np.zeros(k.size, dtype=complex)
    spectrum[keep] = 0.5 * n_points * amp * np.exp(1j * phase)
    unit = np.fft.irfft(spectrum, n=n_points)
    seed_int = None if seed is None or isinstance(seed, np.random.Generator) else int(seed)
    settings = ProfileSettings(
        band=(float(n[keep][0]) if band is None else lo, hi),
        amplitudes=amplitudes,
        waviness=w,
        seed=seed_int,
        lead_in_m=lead_in_m,
    )
    return unit, settings


def check_settings(settings: object, dx_m: float, length_m: float) -> None:
    """Raise RoadgenError unless ``settings`` is a ProfileSettings that a road of grid step
    ``dx_m`` and length ``length_m`` (m) can have been made with (the PSD estimates read its band
    and waviness)."""
    if not isinstance(settings, ProfileSettings):
        raise RoadgenError(
            f"settings={type(settings).__name__} is not allowed: need a roadgen ProfileSettings"
        )
    checks.band("settings.band", settings.band, 0.5 / dx_m)  # its fields: __post_init__
    if float(settings.lead_in_m) > length_m:
        end = distinct_texts(settings.lead_in_m, length_m)[1]
        raise RoadgenError(
            f"settings.lead_in_m={settings.lead_in_m!r} is out of range: allowed [0, {end}] m "
            "(the road's length)"
        )


def band_edges(band: tuple[float, float], n_points: int) -> tuple[float, float]:
    """Lowest and highest frequency (cycles/m) that a harmonic of an ``n_points`` grid may have to
    count as inside ``band``: n_min less a relative 1/n_points, n_max plus rounding.

    Harmonic k lies at k / (n_points dx), the road's period, just below k / ((n_points - 1) dx)
    over its length: on a 150 m road at 6 mm the harmonic with 15 cycles over the road is at
    0.099996 cycles/m, and a band from 0.1 keeps it.
    """
    lo, hi = band
    return lo * (1.0 - 1.0 / n_points) * (1.0 - 1e-9), hi * (1.0 + 1e-9)


def lead_in_taper(x: np.ndarray, lead_in_m: float) -> np.ndarray:
    """Raised-cosine ramp (N,): 0 at x = 0 up to 1 at x >= lead_in_m (all ones if lead_in_m = 0)."""
    if lead_in_m == 0.0:
        return np.ones_like(x)
    t = np.clip(x / lead_in_m, 0.0, 1.0)
    return 0.5 * (1.0 - np.cos(np.pi * t))


def _short_for_band(
    band: tuple[float, float], lo: float, n_points: int, dx_m: float, length_name: str
) -> RoadgenError:
    """The error for a grid of ``n_points`` whose fundamental lies above the band's n_min
    ``lo``: the least length (``length_name``; whole steps, as `grid_points` rounds it) and
    n_min that pass, their text rounded towards passing (`bound_text`), each read apart from the
    value given."""
    need = max(n_points + 1, math.ceil((1.0 - 1e-9) / (lo * dx_m)))
    while lo < 1.0 / (need * dx_m) * (1.0 - 1e-9):  # iso8608_profile's test, in float64
        need += 1
    length, least = f"{(n_points - 1) * dx_m:.6g}", f"{(need - 1) * dx_m:.6g}"
    if round(float(least) / dx_m) + 1 < need:  # (66.666 passes as well as 66.6660001)
        least = bound_text((need - 1) * dx_m, up=True)
    if length == least:
        length, least = repr((n_points - 1) * dx_m), repr((need - 1) * dx_m)
    n_min, n_low = f"{lo:.6g}", bound_text(1.0 / (n_points * dx_m), up=True)
    if n_min == n_low:
        n_min, n_low = repr(lo), repr(1.0 / (n_points * dx_m))
    return RoadgenError(
        f"{length_name}={length} is too short for band={band!r}: the band's n_min={n_min} "
        f"cycles/m needs {length_name} >= {least} m (or use n_min >= {n_low} cycles/m)"
    )


def grid_points(length_m: float, dx_m: float) -> int:
    """Number of grid points for a length rounded to whole steps; at least 2 steps.

    Raises RoadgenError when the road's synthesis would need more than
    ``checks.MAX_MEMORY_BYTES`` (before anything is allocated).
    """
    steps_f = length_m / dx_m
    checks.memory(
        checks.BYTES_PER_POINT * (steps_f + 1),
        f"a road of length_m={length_m:.6g} at dx_m={dx_m:.6g} ({steps_f + 1:.4g} points)",
    )
    steps = round(steps_f)
    if steps < 2:
        raise RoadgenError(
            f"dx_m={dx_m!r} is out of range for length_m={length_m!r}: allowed (0, length_m / "
            "1.5] (the length, rounded to whole steps, must hold at least 2)"
        )
    return steps + 1
