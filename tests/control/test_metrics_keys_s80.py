"""metrics.json of examples/closed_loop.py (session 80): the pooled RMSE of each prescribed GD
is keyed as each run's (`control.closed_loop.gd_key`), so a reader matches the two.

Before: the pooled RMSE was keyed ``f"{gd:g}"`` (six digits, "450.123") and each run's by all
the GD's digits ("450.123456"): a GD that %g does not write exactly had two keys, and the
script ended in a KeyError (printing its table) after writing metrics.json."""

import json

import numpy as np

from control.closed_loop import ClosedLoopResult, LoopMetrics
from control.metrics import GDError, strict_json
from tests._examples import load_example

GDS = [300.0, 450.123456, 300.1000061]


def _result() -> ClosedLoopResult:
    """A run of three estimates, one on each part (no drive needed)."""
    k, n = 3, 4
    errors = tuple(GDError(gd, 4.0 * (i + 1), 1) for i, gd in enumerate(GDS))
    metrics = LoopMetrics(gd_errors=errors, detection_delay_m=(1.5,), fast_on_rough_m=0.0,
                          traversal_time_s=10.0, wall_time_s=0.5, latency_median_s=1e-4,
                          latency_max_s=2e-4, ok_fraction=1.0, coverage=1.0)  # fmt: skip
    gd = np.array(GDS)
    return ClosedLoopResult(
        time=np.arange(k, dtype=float), position=np.arange(k, dtype=float), gd_mean=gd + 2.0,
        gd_lo=gd - 50.0, gd_hi=gd + 50.0, gd_true=gd, status=np.array(["ok"] * k),
        reason=np.array([""] * k), domain_edge=np.array([""] * k), prob_change=np.zeros(k),
        command=np.ones(k), mode=np.array(["performance"] * k), latency_s=np.zeros(k),
        sample_time=np.arange(n, dtype=float), sample_position=np.arange(n, dtype=float),
        sample_speed=np.ones(n), sample_accel=np.zeros(n), metrics=metrics,
    )  # fmt: skip


def test_pooled_and_per_run_rmse_share_their_keys():
    summary = load_example("closed_loop").summarise([_result(), _result()], sorted(GDS))
    written = json.loads(json.dumps(strict_json(summary), allow_nan=False))
    assert set(written["rmse"]) == {"300", "300.1000061", "450.123456"}
    for run in written["runs"]:
        assert set(run["rmse"]) == set(written["rmse"])
        for key, value in written["rmse"].items():  # one run's RMSE twice: the pooled one
            assert value == run["rmse"][key]
    assert written["rmse"]["300"] == 2.0 and written["runs"][0]["n_estimates"]["300"] == 1


def test_a_key_reads_back_as_its_gd():
    from control.closed_loop import gd_key

    for gd in (*GDS, 0.1 + 0.2, 1e-7, 999999.5, 250.0):
        assert float(gd_key(gd)) == gd
    assert gd_key(300.0) == "300" and gd_key(450.123456) == "450.123456"
