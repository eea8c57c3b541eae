"""Review of session 62's ``BCR.resume`` and ``ChangePointFilter.relocate``."""

import numpy as np
from test_robot_io_s60 import _drive, _loop

from control.changepoint import ChangePointFilter


def test_relocating_a_filter_without_data_is_a_reset():
    """A filter that has seen no block holds the prior: a move while down leaves it as after
    ``reset`` (a run starting here), not a run ``ds_m`` metres old whose hazard is the gamma
    law's tail at the first blocks."""
    f = ChangePointFilter(np.linspace(100.0, 600.0, 30))
    f.predict(3.0)  # distance driven before any block
    f.relocate(1e4)
    fresh = ChangePointFilter(np.linspace(100.0, 600.0, 30))
    for got, want in zip(f.state(), fresh.state(), strict=True):
        np.testing.assert_array_equal(got, want)


def test_resume_of_a_bcr_without_gd_state_is_a_fresh_bcr(new_bcr):
    """``resume(moved_m)`` keeps the GD state; with none to keep (no block yet) the stream that
    follows computes as a fresh BCR's (as ``reset()``), whatever the distance."""
    t, p, a, v = _drive([(80.0, 300.0)], 1.0)
    want, _ = _loop(new_bcr("B"), t, p, a, v)
    for moved in (5.0, 1e4):
        bcr = new_bcr("B")
        bcr.resume(moved_m=moved)
        got, _ = _loop(bcr, t, p, a, v)
        assert [e.gd_mean for e in got if e.ok] == [e.gd_mean for e in want if e.ok]
