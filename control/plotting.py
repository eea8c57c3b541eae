"""Figures: closed loop (paper Figs 7-10), training design (Fig. 5), posteriors (Appendix A)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.figure import Figure


def _track_steps(track) -> tuple[np.ndarray, np.ndarray]:
    x = np.append(np.asarray(track.boundaries_m, dtype=float), float(track.length_m))
    gd = np.array([gd for _, gd in track.segments] + [track.segments[-1][1]], dtype=float)
    return x, gd


def _boundaries(ax, track) -> None:
    for b in track.boundaries_m[1:]:
        ax.axvline(b, color="tab:blue", lw=0.8, ls=":")


def plot_gd_trace(results: Sequence, track, title: str = "") -> Figure:
    """GD estimate (posterior mean and credible band) against position, one line per run.

    Args:
        results: `ClosedLoopResult`s driven over `track` (or tracks with the same segments).
        track: the track whose prescribed GD is drawn as a black step line.
    """
    fig = Figure(figsize=(7, 3.6), constrained_layout=True)
    ax = fig.add_subplot()
    x, gd = _track_steps(track)
    ax.step(x, gd, where="post", color="k", lw=1.5, label="prescribed GD")
    for i, r in enumerate(results):
        line = ax.plot(r.position, r.gd_mean, lw=1.2, label=f"run {i + 1}")[0]
        ax.fill_between(r.position, r.gd_lo, r.gd_hi, color=line.get_color(), alpha=0.15, lw=0)
    _boundaries(ax, track)
    ax.set_xlabel("position (m)")
    ax.set_ylabel("GD (1e-6 m$^3$)")
    ax.set_xlim(0, float(track.length_m))
    ax.set_title(title or "BCR estimate of GD (mean and 90% interval)")
    ax.legend(loc="upper right", fontsize=8)
    return fig


def plot_speed(results: Sequence, track, title: str = "") -> Figure:
    """Vehicle speed against position, one line per run, with the track's GD changes marked."""
    fig = Figure(figsize=(7, 3.0), constrained_layout=True)
    ax = fig.add_subplot()
    for i, r in enumerate(results):
        ax.plot(r.sample_position, r.sample_speed, lw=1.0, label=f"run {i + 1}")
    _boundaries(ax, track)
    ax.set_xlabel("position (m)")
    ax.set_ylabel("speed v (m/s)")
    ax.set_xlim(0, float(track.length_m))
    ax.set_ylim(0, None)
    ax.set_title(title or "Speed set by the Simplex controller")
    ax.legend(loc="lower right", fontsize=8)
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
        ax.set_xlabel("GD")
    if title:
        fig.suptitle(title)
    return fig
