"""A closed-loop run's and a replay's results print as one short line (the estimates, their
span, their statuses), as gpmsa's results do, not as a dataclass's default repr: a 50 m run
printed 21,000 characters, its replay 90,000 (every Estimate with its posterior), growing
with the run (an hour's replay: megabytes, seconds to print)."""

from __future__ import annotations

import dataclasses

import numpy as np

from control.closed_loop import ClosedLoopResult, LoopMetrics
from control.metrics import GDError
from control.robot.replay import ReplayResult

K, N = 20_000, 2_400_000  # estimates, sensor samples: a long run


def _statuses(k: int) -> np.ndarray:
    status = np.full(k, "ok", dtype=object)
    status[:2], status[-1] = "filling", "out_of_domain"
    return status


def _loop() -> ClosedLoopResult:
    per_estimate = {name: np.zeros(K) for name in ("time", "position", "gd_mean", "gd_lo",
                    "gd_hi", "gd_true", "prob_change", "command", "latency_s")}  # fmt: skip
    strings = {name: np.full(K, "", dtype=object) for name in ("reason", "domain_edge", "mode")}
    metrics = LoopMetrics(gd_errors=(GDError(300.0, 1.0, 3),), detection_delay_m=(),
                          fast_on_rough_m=0.0, traversal_time_s=20_000.5, wall_time_s=1.0,
                          latency_median_s=1e-3, latency_max_s=2e-3, ok_fraction=0.99)  # fmt: skip
    return ClosedLoopResult(
        **per_estimate, **strings, status=_statuses(K),
        sample_time=np.linspace(0.0, 20_000.5, N), sample_position=np.linspace(0.0, 15_000.5, N),
        sample_speed=np.ones(N), sample_accel=np.zeros(N), metrics=metrics,
    )  # fmt: skip


def test_a_closed_loop_result_prints_one_short_line():
    text = repr(_loop())
    assert len(text) < 200 and "\n" not in text, text
    assert text.startswith("ClosedLoopResult(20000 estimates over 20000.5 s, 15000.5 m:"), text
    assert "filling 2, ok 19997, out_of_domain 1" in text, text
    assert "2400000 sensor samples" in text and str(_loop()) == text


def test_a_closed_loop_result_without_estimates_says_so():
    empty = {f.name: np.empty(0) for f in dataclasses.fields(ClosedLoopResult)}
    empty["metrics"] = _loop().metrics
    text = repr(ClosedLoopResult(**empty))
    assert text == "ClosedLoopResult(no estimate; 0 sensor samples)", text


def test_a_replay_result_prints_one_short_line_without_its_estimates():
    fields = {f.name: None for f in dataclasses.fields(ReplayResult)}
    fields.update(status=_statuses(K), sample_time=np.linspace(5.0, 3605.5, N),
                  sample_position=np.linspace(0.0, 3000.0, N), estimates=(object(),) * K,
                  source="/data/bags/" + "x" * 200 + "/run 1.mcap")  # fmt: skip
    text = repr(ReplayResult(**fields))
    assert len(text) < 200 and "\n" not in text, text
    assert text.startswith("ReplayResult(20000 estimates over 3600.5 s, 3000.0 m:"), text
    assert "filling 2, ok 19997, out_of_domain 1" in text, text
    assert "2400000 IMU samples" in text and text.endswith("from 'run 1.mcap')"), text
