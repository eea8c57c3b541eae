"""Figures of a road: its profile, and its PSD against the prescribed line (paper Figs 3-4)."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from roadgen.iso8608 import N0, gd_spectrum
from roadgen.psd import estimate_gd, profile_psd
from roadgen.road import Road, check_road


def plot_profile_psd(road: Road, method: str = "periodogram", title: str | None = None) -> Figure:
    """Figure with the profile z(x) in mm (top) and its PSD (bottom, log-log, m^3 against cycles/m).

    The PSD panel shows the prescribed line(s) Gd(n) = GD 1e-6 (n/n0)^-w for each distinct GD of the
    road (``gd`` of a Profile, the segments' GDs of a Track), n0 = 0.1 cycles/m, and the GD that
    ``estimate_gd`` recovers. ``method`` is that of ``profile_psd``. The prescribed lines are
    drawn wide and translucent underneath, the road's PSD as a thin line with a dot per ordinate
    on top: with deterministic amplitudes the periodogram lies exactly on its line and stays
    visible there. A plain Road (no GD of its own) shows no prescribed line and is fitted with
    waviness 2.

    Raises RoadgenError unless ``road`` is a roadgen Road, and for the errors of ``profile_psd``.
    """
    check_road("road", road)
    n, gd = profile_psd(road, method)
    fig = Figure(figsize=(7.0, 6.5), layout="constrained")
    ax_z, ax_p = fig.subplots(2, 1)
    ax_z.plot(road.x, 1e3 * road.z, lw=0.6)
    ax_z.set_xlabel("distance x (m)")
    ax_z.set_ylabel("height z (mm)")
    waviness = getattr(getattr(road, "settings", None), "waviness", 2.0)
    for k, g in enumerate(_prescribed_gds(road)):
        ax_p.loglog(n, gd_spectrum(n, g, waviness), lw=5.0, alpha=0.35, color=f"C{k + 1}",
                    solid_capstyle="butt", zorder=1, label=f"prescribed GD {g:g}")  # fmt: skip
    ax_p.loglog(n, gd, lw=0.6, color="C0", marker=".", ms=2.0, zorder=3, label=f"{method} of z")
    recovered = estimate_gd(road)
    ax_p.loglog([N0], [recovered * 1e-6], "o", color="k", label=f"recovered GD {recovered:.1f}")
    ax_p.set_xlabel("spatial frequency n (cycles/m)")
    ax_p.set_ylabel("Gd(n) (m$^3$)")
    ax_p.set_ylim(np.min(gd[gd > 0]), 10 * np.max(gd))
    ax_p.legend(loc="lower left")
    if title is not None:
        fig.suptitle(title)
    return fig


def _prescribed_gds(road: Road) -> list[float]:
    segments = getattr(road, "segments", None)
    if segments is not None:
        return sorted({g for _, g in segments})
    gd = getattr(road, "gd", None)
    return [] if gd is None else [gd]
