"""Figures of a road: its profile, and its PSD against the prescribed line (paper Figs 3-4)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from roadgen.errors import RoadgenError, bound_text, distinct_texts
from roadgen.iso8608 import N0, gd_spectrum
from roadgen.psd import FIT_BAND, FIT_MIN_WAVINESS, estimate_gd, profile_psd
from roadgen.road import Road, check_road

if TYPE_CHECKING:
    from matplotlib.figure import Figure


def plot_profile_psd(
    road: Road,
    method: str = "periodogram",
    title: str | None = None,
    band: tuple[float, float] | None = None,
) -> Figure:
    """Figure with the profile z(x) in mm (top) and its PSD (bottom, log-log, m^3 against cycles/m).

    The PSD panel shows the prescribed line(s) Gd(n) = GD 1e-6 (n/n0)^-w for each distinct GD of the
    road (``gd`` of a Profile, the segments' GDs of a Track), n0 = 0.1 cycles/m, and the GD that
    ``estimate_gd`` recovers (its "fit"; "welch" for a waviness below FIT_MIN_WAVINESS, where
    the fit's end match leaks). ``method`` is that of ``profile_psd``; ``title`` the figure's
    title (None: none). The prescribed lines are drawn wide and translucent underneath, the
    road's PSD as a thin line with a dot per ordinate on top: with deterministic amplitudes the
    periodogram lies exactly on its line and stays visible there. A plain Road (no GD of its
    own) shows no prescribed line and is fitted with waviness 2. ``band`` (cycles/m) is that of
    the GD fit (``estimate_gd``); default FIT_BAND, its n_max lowered to the grid's Nyquist
    frequency 0.5 / dx_m on grids coarser than 0.5 m.

    Raises RoadgenError unless ``road`` is a roadgen Road, for a flat road (no PSD to draw), a grid
    too coarse for the default band (dx_m >= 10 m), and for the errors of ``profile_psd`` and
    ``estimate_gd``.
    """
    check_road("road", road)
    n, gd = profile_psd(road, method)
    if not np.any(gd > 0.0):
        raise RoadgenError(
            f"road is flat: its {method} is zero at every frequency, so there is no PSD to draw "
            "on log axes"
        )
    waviness = getattr(getattr(road, "settings", None), "waviness", 2.0)
    fit = "fit" if waviness >= FIT_MIN_WAVINESS else "welch"  # the fit's end match leaks below
    recovered = estimate_gd(road, band=_fit_band(road.dx_m) if band is None else band, method=fit)
    from matplotlib.figure import Figure  # here, not at import (tests/test_import_cost.py)

    fig = Figure(figsize=(7.0, 6.5), layout="constrained")
    ax_z, ax_p = fig.subplots(2, 1)
    ax_z.plot(road.x, 1e3 * road.z, lw=0.6)
    ax_z.set_xlabel("distance x (m)")
    ax_z.set_ylabel("height z (mm)")
    for k, g in enumerate(_prescribed_gds(road)):
        ax_p.loglog(n, gd_spectrum(n, g, waviness), lw=5.0, alpha=0.35, color=f"C{k + 1}",
                    solid_capstyle="butt", zorder=1, label=f"prescribed GD {g:g}")  # fmt: skip
    ax_p.loglog(n, gd, lw=0.6, color="C0", marker=".", ms=2.0, zorder=3, label=f"{method} of z")
    ax_p.loglog([N0], [recovered * 1e-6], "o", color="k", label=f"recovered GD {recovered:.1f}")
    ax_p.set_xlabel("spatial frequency n (cycles/m)")
    ax_p.set_ylabel("Gd(n) (m$^3$)")
    ax_p.set_ylim(np.min(gd[gd > 0]), 10 * np.max(gd))
    ax_p.legend(loc="lower left")
    if title is not None:
        fig.suptitle(title)
    return fig


def _fit_band(dx_m: float) -> tuple[float, float]:
    """FIT_BAND (cycles/m) with n_max lowered to the Nyquist frequency 0.5 / dx_m of the grid."""
    nyquist = 0.5 / dx_m
    if FIT_BAND[0] >= nyquist:
        dx_text, most = distinct_texts(dx_m, 0.5 / FIT_BAND[0])
        nyq, top = distinct_texts(nyquist, *FIT_BAND)[0], bound_text(nyquist, up=False)
        raise RoadgenError(
            f"the grid dx_m={dx_text} m (Nyquist frequency {nyq} cycles/m) is too coarse "
            f"for the GD fit band FIT_BAND={FIT_BAND} cycles/m: pass a band inside "
            f"(0, {top}] cycles/m, or use dx_m < {most} m"
        )
    return FIT_BAND[0], min(FIT_BAND[1], nyquist)


def _prescribed_gds(road: Road) -> list[float]:
    segments = getattr(road, "segments", None)
    if segments is not None:
        return sorted({g for _, g in segments})
    gd = getattr(road, "gd", None)
    return [] if gd is None else [gd]
