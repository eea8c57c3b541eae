"""The paper's Test Cases A and B in closed loop: BCR + Simplex on the 150 m track, three runs each.

    python examples/closed_loop.py                # writes ./out/metrics.json and the figures
    python examples/closed_loop.py --out DIR --runs 3 --method filter

Track: 50 m at GD 300, 50 m at GD 500, 50 m at GD 300 (roadgen.track). Test Case A: the noise-free
emulator (control/emulators/jackal_A.gpmsa) and noise-free accelerations; Test Case B: the emulator
trained with N(0, 1) accelerometer noise (jackal_B.gpmsa) and noisy accelerations. Run k drives a
track synthesised with seed k (and noise seed k): our estimator is deterministic given the data, so
three runs over one noise-free road would be identical; the paper's three runs differed by its
MCMC. The RMSE is that of the posterior-mean GD at each estimate's position against the GD
prescribed there, pooled over the three runs.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402

import control  # noqa: E402
import gpmsa  # noqa: E402
import roadgen  # noqa: E402
from control.plotting import plot_gd_trace, plot_speed  # noqa: E402

SEGMENTS = [(50.0, 300.0), (50.0, 500.0), (50.0, 300.0)]
NOISE_STD = {"A": 0.0, "B": 1.0}
PAPER_RMSE = {
    "A": {"rmse_gd300": 42.58, "rmse_gd500": 94.42},
    "B": {"rmse_gd300": 50.19, "rmse_gd500": 96.23},
}


def run_case(case: str, runs: int, bcr: control.BCRSettings, simplex: control.Simplex):
    """The closed-loop results of one test case (one per run)."""
    emu = control.shipped_emulator(case)
    calibrator = gpmsa.Calibrator(emu)
    results = []
    for k in range(1, runs + 1):
        track = roadgen.track(SEGMENTS, seed=k)
        results.append(
            control.run_closed_loop(
                track,
                emu,
                noise_std=NOISE_STD[case],
                seed=k,
                bcr=bcr,
                simplex=simplex,
                calibrator=calibrator,
            )
        )
    return results


def summarise(results) -> dict:
    """Pooled RMSE per prescribed GD and the per-run metrics."""
    errors = [r.metrics.gd_errors for r in results]
    return {
        "rmse_gd300": control.pooled_rmse(errors, 300.0),
        "rmse_gd500": control.pooled_rmse(errors, 500.0),
        "runs": [r.metrics.as_dict() for r in results],
    }


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out", help="folder for metrics.json and the figures")
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--method", default="filter", choices=list(control.bcr.METHODS))
    parser.add_argument("--risk", type=float, default=None, help="alpha of the risk posture")
    parser.add_argument("--law", default="linear", choices=["linear", "paper", "switch"])
    args = parser.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    simplex = control.Simplex(risk=args.risk, law=args.law)

    metrics: dict = {}
    track = roadgen.track(SEGMENTS, seed=1)
    for case in ("A", "B"):
        bcr = control.bcr_settings_for(control.shipped_emulator(case), method=args.method)
        results = run_case(case, args.runs, bcr, simplex)
        metrics[case] = summarise(results)
        title = f"Test Case {case} ({'noise-free' if case == 'A' else 'N(0, 1) noise'})"
        plot_gd_trace(results, track, title=f"{title}: GD").savefig(
            out / f"gd_trace_{case}.png", dpi=150
        )
        plot_speed(results, track, title=f"{title}: speed").savefig(
            out / f"speed_{case}.png", dpi=150
        )
    metrics["paper"] = PAPER_RMSE
    metrics["settings"] = {
        "runs": args.runs,
        "method": args.method,
        "risk": args.risk,
        "law": args.law,
    }

    print(f"RMSE of the GD estimate, pooled over {args.runs} runs (paper: Lewis et al. 2025)")
    print(f"{'case':<6}{'part':<9}{'paper':>8}{'ours':>8}   per run")
    for case in ("A", "B"):
        for gd in (300, 500):
            key = f"rmse_gd{gd}"
            per_run = " ".join(f"{r['rmse'][str(gd)]:6.1f}" for r in metrics[case]["runs"])
            paper, ours = PAPER_RMSE[case][key], metrics[case][key]
            print(f"{case:<6}{'GD ' + str(gd):<9}{paper:8.1f}{ours:8.1f}   {per_run}")
    print()
    head = ("delay up (m)", "delay down", "fast on GD>350", "time (s)", "x real time")
    print(f"{'case':<6}{'run':<5}" + "".join(f"{h:>{len(h) + 2}}" for h in head))
    for case in ("A", "B"):
        for k, r in enumerate(metrics[case]["runs"], start=1):
            up, down = (r["detection_delay_m"] + [np.nan, np.nan])[:2]
            print(
                f"{case:<6}{k:<5}{up:14.1f}{down:12.1f}{r['fast_on_rough_m']:14.1f} m"
                f"{r['traversal_time_s']:10.1f}{r['real_time_factor']:13.0f}"
            )
    (out / "metrics.json").write_text(json.dumps(metrics, indent=2, default=float))
    print(f"\nwrote {out / 'metrics.json'} and the figures gd_trace_A/B.png, speed_A/B.png")
    return metrics


if __name__ == "__main__":
    main()
