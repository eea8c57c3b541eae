"""The closed loop's progress bar is closed when the run stops on an error (its time limit, a
Ctrl-C), as when it ends: a bar left open (held by the traceback, as IPython and Jupyter keep
the last one) stayed in tqdm's list of bars, and every later bar was drawn a line lower."""

import pytest

import roadgen
from control import ControlError, run_closed_loop
from gpmsa import _progress


@pytest.fixture
def bars(monkeypatch):
    """The bars made while the test runs."""
    made = []
    real = _progress._bar_class()

    class Recorded(real):
        def __init__(self, *args, **kwargs):
            super().__init__(*args, **kwargs)
            made.append(self)

    monkeypatch.setattr(_progress, "_bar_class", lambda: Recorded)
    return made


def test_a_loop_stopped_by_its_time_limit_closes_its_bar(bars, emulator_a, likelihood_a):
    track = roadgen.track([(6, 300), (6, 500)], seed=3)
    with pytest.raises(ControlError, match="max_time_s"):
        run_closed_loop(
            track, emulator_a, seed=3, likelihood=likelihood_a, progress=True, max_time_s=1.0
        )
    assert len(bars) == 1 and bars[0].disable  # tqdm's close sets it
