"""Figures: closed loop (paper Figs 7-10), training design (Fig. 5), posteriors (Appendix A)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.figure import Figure


def _track_steps(track) -> tuple[np.ndarray, np.ndarray]:
    x = np.append(np.asarray(track.boundaries_m, dtype=float), float(track.length_m))
    gd = np.array([gd for _, gd in track.segments] + [track.segments[-1][1]], dtype=float)
    return x, gd


def _mark_track(ax, track, gd_max: float | None) -> None:
    """Segment changes (dotted verticals) and the parts rougher than gd_max (shaded)."""
    for i, b in enumerate(track.boundaries_m[1:]):
        ax.axvline(b, color="0.4", lw=0.8, ls=":", label="segment change" if i == 0 else None)
    if gd_max is None:
        return
    ends = list(track.boundaries_m[1:]) + [float(track.length_m)]
    first = True
    for start, end, (_, gd) in zip(track.boundaries_m, ends, track.segments, strict=True):
        if gd > gd_max:
            ax.axvspan(start, end, color="tab:red", alpha=0.08, lw=0,
                       label=f"prescribed GD > GD_max = {gd_max:g}" if first else None)  # fmt: skip
            first = False


def plot_gd_trace(
    results: Sequence, track, title: str = "", gd_max: float | None = 350.0, level: float = 0.9
) -> Figure:
    """GD estimate (posterior mean, and the credible interval as thin lines) against position;
    estimates that name an edge of the emulator's GD domain (``domain_edge``) are marked with a
    triangle pointing beyond it.

    Args:
        results: `ClosedLoopResult`s driven over `track` (or tracks with the same segments).
        track: the track whose prescribed GD is drawn as a black step line.
        gd_max: the Simplex's GD_max: the parts rougher than it are shaded (None: no shading).
        level: the level of the BCR's interval (for the legend).
    """
    fig = Figure(figsize=(7.5, 4.6), layout="constrained")
    ax = fig.add_subplot()
    _mark_track(ax, track, gd_max)
    x, gd = _track_steps(track)
    ax.step(x, gd, where="post", color="k", lw=1.5, label="prescribed GD")
    for i, r in enumerate(results):
        line = ax.plot(r.position, r.gd_mean, lw=1.3, label=f"run {i + 1}: posterior mean")[0]
        label = f"run {i + 1}: {level:.0%} interval"
        for edge in (r.gd_lo, r.gd_hi):
            ax.plot(r.position, edge, lw=0.6, alpha=0.7, color=line.get_color(), ls="--",
                    label=label)  # fmt: skip
            label = None
        edges = np.asarray(getattr(r, "domain_edge", np.full(r.position.shape, "")), dtype=object)
        for edge, marker in (("upper", "^"), ("lower", "v")):
            named = edges == edge
            if named.any():
                ax.plot(r.position[named], r.gd_mean[named], ls="none", marker=marker, ms=4,
                        color=line.get_color(),
                        label=f"run {i + 1}: {edge} edge of the GD domain")  # fmt: skip
    ax.set_xlabel("position of the front axle (m)")
    ax.set_ylabel("GD (1e-6 m$^3$)")
    ax.set_xlim(0, float(track.length_m))
    ax.set_title(title or "BCR estimate of GD")
    fig.legend(loc="outside lower center", fontsize=7, ncol=4, frameon=False)
    return fig


def plot_speed(
    results: Sequence, track, title: str = "", gd_max: float | None = 350.0,
    v_safe: float | None = 1.0,
) -> Figure:  # fmt: skip
    """Vehicle speed against position, one line per run, with the track's GD changes marked.

    The start (the vehicle ramps up from rest within a few centimetres) is left out.
    """
    fig = Figure(figsize=(7.5, 3.0), constrained_layout=True)
    ax = fig.add_subplot()
    _mark_track(ax, track, gd_max)
    for i, r in enumerate(results):
        moving = r.sample_position > r.sample_position[0] + 0.1
        ax.plot(r.sample_position[moving], r.sample_speed[moving], lw=1.0, label=f"run {i + 1}")
    if v_safe is not None:
        ax.axhline(v_safe, color="0.3", lw=0.8, ls="--", label=f"safe speed {v_safe:g} m/s")
    ax.set_xlabel("position of the front axle (m)")
    ax.set_ylabel("speed v (m/s)")
    ax.set_xlim(0, float(track.length_m))
    ax.set_ylim(0, None)
    ax.set_title(title or "Speed set by the Simplex controller")
    ax.legend(loc="lower right", fontsize=7, framealpha=0.8)
    return fig


def plot_design(v: np.ndarray, gd: np.ndarray, title: str = "") -> Figure:
    """The training design points (v, GD) (paper Fig. 5)."""
    fig = Figure(figsize=(4.5, 4), constrained_layout=True)
    ax = fig.add_subplot()
    ax.scatter(v, gd, s=10)
    ax.set_xlabel("v (m/s)")
    ax.set_ylabel("GD (1e-6 m$^3$)")
    ax.set_title(title or f"Latin hypercube design, {len(v)} runs")
    return fig


def plot_posterior_grid(
    cells: Sequence[tuple[float, float, np.ndarray]], title: str = ""
) -> Figure:
    """Histograms of posterior GD draws per (v, GD) cell (paper Appendix A).

    Args:
        cells: (v, true GD, draws) triples; the true GD is drawn as a vertical line.
    """
    speeds = sorted({c[0] for c in cells})
    gds = sorted({c[1] for c in cells})
    fig = Figure(figsize=(2.6 * len(speeds), 1.5 * len(gds)), constrained_layout=True)
    axes = fig.subplots(len(gds), len(speeds), sharex=True, squeeze=False)
    for v, gd, draws in cells:
        ax = axes[gds.index(gd), speeds.index(v)]
        ax.hist(draws, bins=40, range=(200, 600), density=True, alpha=0.7)
        ax.axvline(gd, color="k", lw=1)
        ax.set_yticks([])
        if gd == gds[0]:
            ax.set_title(f"v = {v:g} m/s", fontsize=9)
        if v == speeds[0]:
            ax.set_ylabel(f"GD {gd:g}", fontsize=9)
    for ax in axes[-1]:
        ax.set_xlabel("GD (1e-6 m$^3$)")
    if title:
        fig.suptitle(title)
    return fig
