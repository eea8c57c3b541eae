"""control's closed-loop figures tell their runs apart by colour under any style: a style
whose colour cycle is shorter than the runs (a one-colour ``axes.prop_cycle``; matplotlib's
"grayscale" has 4) drew every run, and its legend entry, alike."""

import matplotlib

matplotlib.use("Agg")

import matplotlib as mpl  # noqa: E402
from control_doubles import plotted_run_and_track  # noqa: E402
from cycler import cycler  # noqa: E402
from matplotlib.colors import to_rgba  # noqa: E402

from control.plotting import plot_gd_trace, plot_speed  # noqa: E402


def _run_colours(fig) -> list[tuple]:
    lines = fig.axes[0].get_lines()
    return [to_rgba(ln.get_color()) for ln in lines if ln.get_label().startswith("run ")
            and ln.get_label().endswith(("posterior mean", "run 1", "run 2", "run 3"))]  # fmt: skip


def test_three_runs_differ_in_colour_under_a_one_colour_cycle():
    run, track = plotted_run_and_track()
    for plot in (plot_gd_trace, plot_speed):
        with mpl.rc_context({"axes.prop_cycle": cycler(color=["#1f77b4"])}):
            one = _run_colours(plot([run, run, run], track))
        default = _run_colours(plot([run, run, run], track))
        assert len(one) == 3 and len(set(one)) == 3, plot.__name__
        assert one == default == [to_rgba(f"C{k}") for k in range(3)]  # the default's, as before
