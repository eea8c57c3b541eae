"""What a bad-argument fuzz of the public control API found still slipping through: a SimplexRun
of something that is no Simplex (an AttributeError at its first command), replay_bag's
``progress`` of any type (run_closed_loop refuses it), and metrics that scored positions
off the track's ends as its first or last segment (a position in mm read as the last GD)."""

from types import SimpleNamespace

import numpy as np
import pytest
from _robot_cases import small_result

import control
from control import ControlError, Estimate, Simplex, SimplexRun

OK = Estimate(time=1.0, position=1.0, status="ok", gd_mean=300.0, gd_sd=10.0, interval=(280, 320))


@pytest.mark.parametrize("simplex", [None, "latch", Simplex, control.BCRSettings()])
def test_a_simplex_run_of_no_simplex_is_refused_naming_it(simplex):
    """Took anything; its first command raised AttributeError ('NoneType' object has no
    attribute 'after_fault') or, for the class itself, a TypeError of a missing argument."""
    with pytest.raises(ControlError, match=r"^simplex must be a control\.Simplex, got "):
        SimplexRun(simplex)


def test_a_simplex_run_of_a_simplex_commands_as_before():
    run = SimplexRun(Simplex())
    assert run.command(OK) == Simplex().start().command(OK) == Simplex().command(OK)


@pytest.mark.parametrize("progress", ["yes", 1, None, np.nan])
def test_replay_bag_refuses_a_progress_that_is_no_bool(tmp_path, progress):
    """run_closed_loop refused these; replay_bag took any value as its truth value."""
    pytest.importorskip("mcap")
    bag = control.record_run(small_result(), tmp_path / "run.mcap")
    with pytest.raises(ControlError, match=rf"^progress must be True or False, got {progress!r}"):
        control.replay_bag(bag, "A", progress=progress)
    assert control.replay_bag(bag, "A", progress=np.bool_(False)).status.size  # numpy's bool too


TRACK = SimpleNamespace(  # what the metrics read of a roadgen Track
    segments=((50.0, 300.0), (50.0, 500.0)), boundaries_m=(0.0, 50.0), length_m=100.0
)
ON = np.array([10.0, 60.0, 90.0, 100.0])
EST = np.array([300.0, 500.0, 500.0, 500.0])


@pytest.mark.parametrize(
    "metric",
    [
        lambda pos: control.gd_errors(TRACK, pos, EST),
        lambda pos: control.detection_delays(TRACK, pos, EST),
        lambda pos: control.fast_on_rough_m(TRACK, pos, np.full(pos.size, 2.0), 350.0, 1.0),
    ],
    ids=["gd_errors", "detection_delays", "fast_on_rough_m"],
)
@pytest.mark.parametrize("bad, index", [(1000.0, 3), (-5.0, 0)])
def test_the_metrics_refuse_positions_off_the_track(metric, bad, index):
    """gd_errors charged a position beyond the end (1000 m on a 100 m track: mm read as m, say)
    to the last segment, one before the start to the first; fast_on_rough_m counted 900 m of a
    100 m track as driven on it."""
    pos = ON.copy()
    pos[index] = bad
    with pytest.raises(
        ControlError, match=rf"^position holds {bad:g} m at index {index}: .*\[0, 100\] m"
    ):
        metric(pos)


def test_positions_on_the_track_and_its_ends_are_scored_as_before():
    pos = np.array([0.0, 10.0, 60.0, 100.0])
    errs = control.gd_errors(TRACK, pos, np.array([310.0, 300.0, 480.0, 500.0]))
    assert [(e.gd, e.sse, e.n) for e in errs] == [(300.0, 100.0, 2), (500.0, 400.0, 2)]
    assert control.detection_delays(TRACK, pos, EST[[0, 0, 1, 1]]) == (10.0,)
    assert control.fast_on_rough_m(TRACK, pos, np.full(4, 2.0), 350.0, 1.0) == 40.0  # 60-100 m
    nan_at = np.array([np.nan, 10.0, 60.0, np.inf])  # not finite: left out, as documented
    assert sum(e.n for e in control.gd_errors(TRACK, nan_at, EST)) == 2
