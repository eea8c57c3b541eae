"""LoopMetrics.rmse finds a GD that went through float32 (to a relative 1e-6)."""

import numpy as np
import pytest

import roadgen
from control.closed_loop import LoopMetrics
from control.errors import ControlError
from control.metrics import gd_errors


def _metrics(gds):
    track = roadgen.track([(50, gds[0]), (50, gds[1])], seed=0)
    errs = gd_errors(track, np.array([10.0, 60.0]), np.array([301.0, 499.0]))
    return LoopMetrics(gd_errors=errs, detection_delay_m=(), fast_on_rough_m=0.0,
                       traversal_time_s=1.0, wall_time_s=1.0, latency_median_s=0.0,
                       latency_max_s=0.0, ok_fraction=1.0)  # fmt: skip


def test_a_track_of_float32_gds_is_scored_at_the_gd_as_written():
    """Before: 'no part of the track has prescribed GD 300.1; its GDs: 300.1, 500'."""
    gds = np.array([300.1, 500.0], dtype=np.float32)
    m = _metrics(gds)
    assert m.rmse(300.1) == m.rmse(gds[0]) == m.gd_errors[0].rmse == pytest.approx(0.9, rel=1e-4)
    assert m.rmse(float(np.float32(500.0))) == m.gd_errors[1].rmse


def test_a_gd_off_by_more_than_the_tolerance_is_refused_with_its_digits():
    m = _metrics(np.array([300.1, 500.0], dtype=np.float32))
    with pytest.raises(ControlError, match=r"GD 300.11; its GDs: 300.1000061035156, 500$"):
        m.rmse(300.11)
    m = _metrics([300.0, 500.0])
    assert m.rmse(np.float32(300.0)) == m.gd_errors[0].rmse


def test_as_dict_keeps_two_gds_that_print_alike_apart():
    """Keyed by %g, a part of GD 300.0000001 overwrote the part of GD 300 (one rmse, one count)."""
    m = _metrics([300.0, 300.0000001])
    summary = m.as_dict()
    assert list(summary["rmse"]) == ["300", "300.0000001"]
    assert summary["n_estimates"] == {"300": 1, "300.0000001": 1}
    assert list(_metrics([300.0, 500.0]).as_dict()["rmse"]) == ["300", "500"]  # as before
