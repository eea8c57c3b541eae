"""The closed-loop figures as a user calls them: the interval's level in the legend is the one
the runs' BCR used, and bad arguments are named (session 69 walkthrough)."""

from types import SimpleNamespace

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from control_doubles import plotted_run_and_track  # noqa: E402

from control import BCRSettings, ControlError  # noqa: E402
from control.plotting import plot_gd_trace, plot_speed  # noqa: E402


def _recorded(run, level: float):
    """``run`` with the settings a ClosedLoopResult records: its BCR's interval level."""
    return SimpleNamespace(**vars(run), settings={"bcr": BCRSettings(interval_level=level)})


def _legend(fig) -> list[str]:
    return [t.get_text() for t in fig.legends[0].get_texts()]


def test_the_legend_names_the_interval_level_the_runs_recorded():
    """A BCR run with interval_level=0.95 was drawn as a "90% interval" (the default level)."""
    run, track = plotted_run_and_track()
    assert "run 1: 95% interval" in _legend(plot_gd_trace([_recorded(run, 0.95)], track))
    assert "run 1: 90% interval" in _legend(plot_gd_trace([run], track))  # none recorded
    assert "run 1: 80% interval" in _legend(plot_gd_trace([run], track, level=0.8))
    with pytest.raises(ControlError, match=r"level=0.9 is not .*interval_level=0.95"):
        plot_gd_trace([_recorded(run, 0.95)], track, level=0.9)
    with pytest.raises(ControlError, match=r"different interval levels \[0.8, 0.95\]"):
        plot_gd_trace([_recorded(run, 0.95), _recorded(run, 0.8)], track)


def test_bad_gd_max_and_v_safe_are_named():
    run, track = plotted_run_and_track()
    for bad in ("350", np.nan, [350.0]):  # TypeError deep in a comparison, or no shading
        with pytest.raises(ControlError, match="gd_max must be a finite GD"):
            plot_gd_trace([run], track, gd_max=bad)
        with pytest.raises(ControlError, match="gd_max must be a finite GD"):
            plot_speed([run], track, gd_max=bad)
    for bad in ("1", np.inf):  # "Unknown format code 'g' for object of type 'str'"
        with pytest.raises(ControlError, match="v_safe must be a finite speed"):
            plot_speed([run], track, v_safe=bad)


def test_a_run_without_samples_draws_no_speed_line():
    """plot_speed indexed the first sample of a run that has none (IndexError)."""
    run, track = plotted_run_and_track()
    empty = SimpleNamespace(**{**vars(run), "sample_position": np.array([]),
                               "sample_speed": np.array([])})  # fmt: skip
    fig = plot_speed([empty, run], track)
    assert [line.get_label() for line in fig.axes[0].lines][-3:-1] == ["run 1", "run 2"]
    assert fig.axes[0].lines[-3].get_xdata().size == 0
