"""Figures: closed loop (paper Figs 7-10), training design (Fig. 5), posteriors (Appendix A)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.figure import Figure

from control.errors import ControlError
from control.validation import is_real
from gpmsa.mcmc.diagnostics import bins_apart
from gpmsa.plots._figure import series_colours


def _ink() -> str:
    """The style's foreground colour (``rcParams["text.color"]``) for the prescribed GD: black
    in matplotlib's default style, as "k" was; white in "dark_background", where black would
    not show."""
    from matplotlib import rcParams

    return rcParams["text.color"]


def _track_steps(track) -> tuple[np.ndarray, np.ndarray]:
    x = np.append(np.asarray(track.boundaries_m, dtype=float), float(track.length_m))
    gd = np.array([gd for _, gd in track.segments] + [track.segments[-1][1]], dtype=float)
    return x, gd


def _runs(results) -> list:
    """``results`` as a list of runs; ControlError for one run passed alone or a non-sequence."""
    if hasattr(results, "position") or isinstance(results, str):
        raise ControlError(
            f"results must be a sequence of ClosedLoopResults, got one {type(results).__name__}: "
            "for one run pass [result]"
        )
    try:
        return list(results)
    except TypeError:
        raise ControlError(
            f"results must be a sequence of ClosedLoopResults, got {results!r:.60}"
        ) from None


def _optional_real(value, name: str, what: str) -> float | None:
    """``value`` (None or a finite real number) as a float; ControlError naming it otherwise."""
    if value is None:
        return None
    if not (is_real(value) and np.isfinite(value)):
        raise ControlError(f"{name} must be a finite {what} or None, got {value!r:.60}")
    return float(value)


def _interval_level(results: list, level: float | None) -> float:
    """The level of the runs' credible interval: ``level`` where given (it must agree with the
    level each run's BCR recorded, ``settings["bcr"].interval_level``), else the recorded one
    (0.9, BCRSettings' default, where none is recorded); ControlError otherwise."""
    recorded = sorted({float(bcr.interval_level) for r in results
                       if (bcr := (getattr(r, "settings", None) or {}).get("bcr")) is not None
                       and hasattr(bcr, "interval_level")})  # fmt: skip
    if level is None:
        if len(recorded) > 1:
            raise ControlError(
                f"the runs' BCRs used different interval levels {recorded}: plot them apart"
            )
        return recorded[0] if recorded else 0.9
    if not (is_real(level) and 0 < level < 1):
        raise ControlError(f"level must lie in (0, 1) (e.g. 0.9 for 90%), got {level!r}")
    if recorded and recorded != [float(level)]:
        raise ControlError(
            f"level={level!r} is not the level the runs' BCR reported its interval at "
            f"(settings['bcr'].interval_level={', '.join(f'{v:g}' for v in recorded)}): leave "
            "level=None"
        )
    return float(level)


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
    results: Sequence,
    track,
    title: str = "",
    gd_max: float | None = 350.0,
    level: float | None = None,
) -> Figure:
    """GD estimate (posterior mean, and the credible interval as thin lines) against position;
    estimates that name an edge of the emulator's GD domain (``domain_edge``) are marked with a
    triangle pointing beyond it.

    Args:
        results: `ClosedLoopResult`s driven over `track` (or tracks with the same segments).
        track: the track whose prescribed GD is drawn as a black step line.
        title: the axes' title ("": "BCR estimate of GD").
        gd_max: the Simplex's GD_max: the parts rougher than it are shaded (None: no shading).
        level: the level of the BCR's interval (for the legend), in (0, 1); None: the
            ``interval_level`` the runs' BCR recorded (``settings["bcr"]``; 0.9 where none is
            recorded). A level other than the recorded one is a ControlError.
    """
    results = _runs(results)
    level = _interval_level(results, level)
    gd_max = _optional_real(gd_max, "gd_max", "GD (1e-6 m^3)")
    fig = Figure(figsize=(7.5, 4.6), layout="constrained")
    ax = fig.add_subplot()
    _mark_track(ax, track, gd_max)
    x, gd = _track_steps(track)
    ax.step(x, gd, where="post", color=_ink(), lw=1.5, label="prescribed GD")
    colours = series_colours(len(results))
    for i, r in enumerate(results):
        line = ax.plot(r.position, r.gd_mean, lw=1.3, color=colours[i],
                       label=f"run {i + 1}: posterior mean")[0]  # fmt: skip
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

    Args:
        results: `ClosedLoopResult`s driven over `track` (or tracks with the same segments).
        track: the track whose segment changes are marked (dotted verticals).
        title: the axes' title ("": "Speed set by the Simplex controller").
        gd_max: the Simplex's GD_max: the parts rougher than it are shaded (None: no shading).
        v_safe: the Simplex's safe speed, m/s, drawn as a dashed line (None: no line).
    """
    results = _runs(results)
    gd_max = _optional_real(gd_max, "gd_max", "GD (1e-6 m^3)")
    v_safe = _optional_real(v_safe, "v_safe", "speed (m/s)")
    fig = Figure(figsize=(7.5, 3.0), constrained_layout=True)
    ax = fig.add_subplot()
    _mark_track(ax, track, gd_max)
    colours = series_colours(len(results))
    for i, r in enumerate(results):
        start = r.sample_position[0] if len(r.sample_position) else 0.0  # a run without samples
        moving = r.sample_position > start + 0.1
        ax.plot(r.sample_position[moving], r.sample_speed[moving], lw=1.0, color=colours[i],
                label=f"run {i + 1}")  # fmt: skip
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
    """The training design points (v, GD) (paper Fig. 5): speeds ``v`` (m/s) and GDs ``gd``
    (1e-6 m^3) of the runs; ``title`` "" reads "Latin hypercube design, N runs"."""
    fig = Figure(figsize=(4.5, 4), constrained_layout=True)
    ax = fig.add_subplot()
    ax.scatter(v, gd, s=10)
    ax.set_xlabel("v (m/s)")
    ax.set_ylabel("GD (1e-6 m$^3$)")
    ax.set_title(title or f"Latin hypercube design, {len(v)} runs")
    return fig


POSTERIOR_BINS = 40
"""Bins of each histogram of `plot_posterior_grid`."""


def plot_posterior_grid(
    cells: Sequence[tuple[float, float, np.ndarray]],
    title: str = "",
    gd_range: tuple[float, float] | None = None,
) -> Figure:
    """Histograms of posterior GD draws per (v, GD) cell (paper Appendix A): a row per true GD,
    a column per speed; a (v, GD) pair without a cell is a blank panel reading "no data".

    Args:
        cells: (v, true GD, draws) triples; the true GD is drawn as a vertical line.
        title: the figure's title ("": none).
        gd_range: (lo, hi) of the histograms' common GD axis (1e-6 m^3), e.g. the emulator's GD
            domain; None: the span of every draw and true GD, rounded out to whole steps of the
            power of ten at or below it ((200, 600) for the paper's cells on its domain).

    Raises ControlError for draws that are empty or not finite, or a gd_range that is not two
    finite values lo < hi.
    """
    try:
        cells = list(cells)  # (read twice: a generator too)
    except TypeError:
        raise ControlError(
            f"cells must be a sequence of (v, true GD, draws), got {cells!r:.60}"
        ) from None
    values = _cell_values(cells)
    hist_range = _gd_range(values) if gd_range is None else _checked_gd_range(gd_range)
    speeds = sorted({c[0] for c in cells})
    gds = sorted({c[1] for c in cells})
    fig = Figure(figsize=(2.6 * len(speeds), 1.5 * len(gds)), constrained_layout=True)
    axes = fig.subplots(len(gds), len(speeds), sharex=True, squeeze=False)
    drawn = np.zeros(axes.shape, dtype=bool)
    for v, gd, draws in cells:
        row, col = gds.index(gd), speeds.index(v)
        ax = axes[row, col]
        drawn[row, col] = True
        # float64, as the range was checked (numpy spaces the bins in the draws' own type)
        ax.hist(np.asarray(draws, dtype=np.float64), bins=POSTERIOR_BINS, range=hist_range,
                density=True, alpha=0.7)  # fmt: skip
        ax.axvline(gd, color=_ink(), lw=1)
        ax.set_yticks([])
    for row, gd in enumerate(gds):
        axes[row, 0].set_ylabel(f"GD {gd:g}", fontsize=9)
    for col, v in enumerate(speeds):
        axes[0, col].set_title(f"v = {v:g} m/s", fontsize=9)  # (shown on an empty panel too)
        lowest = axes[np.flatnonzero(drawn[:, col])[-1], col]  # each column has a cell
        lowest.xaxis.set_tick_params(which="both", labelbottom=True)  # (sharex hid them)
        lowest.xaxis.offsetText.set_visible(True)
        lowest.set_xlabel("GD (1e-6 m$^3$)")
    for row, col in zip(*np.nonzero(~drawn), strict=True):  # a (v, GD) with no cell
        ax = axes[row, col]
        ax.set_axis_off()
        ax.text(0.5, 0.5, f"no data\nv = {speeds[col]:g} m/s, GD {gds[row]:g}", ha="center",
                va="center", fontsize=8, color="0.5", transform=ax.transAxes)  # fmt: skip
    if title:
        fig.suptitle(title)
    return fig


def _cell_values(cells: Sequence[tuple[float, float, np.ndarray]]) -> np.ndarray:
    """Every cell's draws and true GD (1e-6 m^3) in one array, or ControlError naming the first
    cell whose draws are empty or not finite, or whose true GD is not a finite number."""
    values = []
    for i, cell in enumerate(cells):
        try:
            v, gd, draws = cell
        except (TypeError, ValueError):
            v = None
        if not (is_real(v) and np.isfinite(v)):
            raise ControlError(
                f"cells[{i}] must be a (v, true GD, draws) triple with v a finite speed, m/s, "
                f"got {cell!r:.80}"
            )
        try:
            arr = np.asarray(draws, dtype=float).ravel()
        except (TypeError, ValueError):
            raise ControlError(
                f"cells[{i}]: the draws must be an array of GD values (numbers), got {draws!r:.60}"
            ) from None
        true_gd = float(gd) if is_real(gd) else float("nan")
        if arr.size == 0 or not np.all(np.isfinite(arr)) or not np.isfinite(true_gd):
            raise ControlError(
                f"cells[{i}]: the draws must be a non-empty array of finite GD values and the "
                f"true GD a finite number, got {arr.size} draws "
                f"({np.count_nonzero(~np.isfinite(arr))} not finite) and GD {gd!r}"
            )
        values.append(np.append(arr, true_gd))
    if not values:
        raise ControlError("cells is empty: need at least one (v, true GD, draws) triple")
    return np.concatenate(values)


def _gd_range(values: np.ndarray) -> tuple[float, float]:
    """The span (1e-6 m^3) of ``values``, rounded out to whole steps of the power of ten at or
    below it (one step more either side where the span rounds to nothing). A span too narrow
    for `POSTERIOR_BINS` bins of distinct float64 edges (draws a few ulps apart) counts as
    none: the range about one value."""
    lo, hi = float(values.min()), float(values.max())
    rounded = _rounded_range(lo, hi)
    return rounded if _holds_bins(*rounded) else _rounded_range(lo, lo)


def _rounded_range(lo: float, hi: float) -> tuple[float, float]:
    """[lo, hi] rounded out to whole steps of the power of ten at or below its span (at or
    below max(|lo|, 1) where lo = hi; one step more either side where it rounds to nothing)."""
    step = 10.0 ** np.floor(np.log10(hi - lo if hi > lo else max(abs(lo), 1.0)))
    lo_r, hi_r = float(np.floor(lo / step) * step), float(np.ceil(hi / step) * step)
    return (lo_r, hi_r) if hi_r > lo_r else (lo_r - step, hi_r + step)


def _checked_gd_range(gd_range: tuple[float, float]) -> tuple[float, float]:
    """``gd_range`` (1e-6 m^3) as two floats lo < hi, or ControlError."""
    try:
        lo, hi = (float(g) for g in gd_range)
    except (TypeError, ValueError):
        lo = hi = float("nan")
    if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
        raise ControlError(f"gd_range={gd_range!r} must be two finite GD values lo < hi")
    if not _holds_bins(lo, hi):
        raise ControlError(
            f"gd_range={gd_range!r} is too narrow for {POSTERIOR_BINS} bins at float64's "
            f"resolution about {lo:g}: give a wider range, or None for the draws' own"
        )
    return lo, hi


def _holds_bins(lo: float, hi: float) -> bool:
    """Whether [lo, hi] holds `POSTERIOR_BINS` equal bins of distinct float64 edges (numpy
    refuses a histogram range that does not: "Too many bins for data range")."""
    return bins_apart(lo, hi, POSTERIOR_BINS)
