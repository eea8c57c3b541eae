"""The paper's Test Cases A and B in closed loop: BCR + Simplex on the 150 m track, three runs each.

    python examples/closed_loop.py                # writes ./out/metrics.json and the figures
    python examples/closed_loop.py --out DIR --runs 3 --method changepoint --law linear
    python examples/closed_loop.py --record runs/   # also one MCAP per run, for Foxglove

Track: 50 m at GD 300, 50 m at GD 500, 50 m at GD 300 (roadgen.track). Test Case A: noise-free
accelerations and the noise-free emulators; Test Case B: N(0, 1) accelerometer noise and the
emulators trained with it. Run k drives a track synthesised with seed k (and noise seed k).

Each case is run twice: with our estimator (default: the change-point BCR on log band powers of
1 s blocks, `control.bcr`) and with the paper's method run here (one 1,000-sample window, its
log variance, the paper's uniform prior: ``method="window"``). The RMSE is that of the
posterior-mean GD at each estimate's position against the GD prescribed there, pooled over the
runs; the table prints the paper's figures, the paper's method run here, and ours.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402

import control  # noqa: E402
import roadgen  # noqa: E402
from control.plotting import plot_gd_trace, plot_speed  # noqa: E402

SEGMENTS = [(50.0, 300.0), (50.0, 500.0), (50.0, 300.0)]
NOISE_STD = {"A": 0.0, "B": 1.0}
PAPER_RMSE = {
    "A": {"rmse_gd300": 42.58, "rmse_gd500": 94.42},
    "B": {"rmse_gd300": 50.19, "rmse_gd500": 96.23},
}


def run_case(
    case: str, runs: int, method: str, simplex: control.Simplex, record: Path | None = None
) -> list:
    """The closed-loop results of one test case and estimator (one per run); with ``record``,
    each run is also written there as ``case{A,B}_{method}_run{k}.mcap`` (control.record_run)."""
    kind = "band" if method == "changepoint" else "window"
    emu = control.shipped_emulator(case, kind)
    bcr = control.bcr_settings_for(emu, method=method)
    likelihood = control.BCR.from_emulator(emu, bcr).model  # prepared once for all runs
    return [
        control.run_closed_loop(
            roadgen.track(SEGMENTS, seed=k),
            emu,
            noise_std=NOISE_STD[case],
            seed=k,
            bcr=bcr,
            simplex=simplex,
            likelihood=likelihood,
            record=record / f"case{case}_{method}_run{k}.mcap" if record else None,
        )  # fmt: skip
        for k in range(1, runs + 1)
    ]


def summarise(results) -> dict:
    """Pooled RMSE per prescribed GD, pooled interval coverage and the per-run metrics."""
    errors = [r.metrics.gd_errors for r in results]
    ok = np.concatenate([np.isfinite(r.gd_mean) for r in results])
    lo, hi, true = (
        np.concatenate([getattr(r, k) for r in results]) for k in ("gd_lo", "gd_hi", "gd_true")
    )
    return {
        "rmse_gd300": control.pooled_rmse(errors, 300.0),
        "rmse_gd500": control.pooled_rmse(errors, 500.0),
        "coverage": float(np.mean((lo[ok] <= true[ok]) & (true[ok] <= hi[ok]))),
        "runs": [r.metrics.as_dict() for r in results],
    }


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="out", help="folder for metrics.json and the figures")
    parser.add_argument(
        "--runs", type=int, default=3, help="runs per test case (track and noise seeds 1..RUNS)"
    )
    parser.add_argument(
        "--method", default="changepoint", choices=list(control.METHODS),
        help="our estimator: changepoint (default), or the window methods for comparison",
    )  # fmt: skip
    parser.add_argument(
        "--risk", type=float, default=None,
        help="risk posture alpha: drive on the (1 - alpha) posterior quantile of GD",
    )  # fmt: skip
    parser.add_argument(
        "--law", default="linear", choices=list(control.simplex.LAWS),
        help="Simplex performance law: linear (default), paper (eq. 8 literally), switch",
    )  # fmt: skip
    parser.add_argument(
        "--record", default=None, metavar="DIR",
        help="write each run as an MCAP file in DIR, to watch in Foxglove with "
        "examples/foxglove_layout.json (needs the robot extra)",
    )  # fmt: skip
    args = parser.parse_args(argv)
    if args.runs < 1:
        parser.error(f"--runs must be >= 1, got {args.runs}")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    simplex = control.Simplex(risk=args.risk, law=args.law)

    metrics: dict = {"ours": {}, "paper_method": {}}
    track = roadgen.track(SEGMENTS, seed=1)
    for case in ("A", "B"):
        title = f"Test Case {case} ({'noise-free' if case == 'A' else 'N(0, 1) noise'})"
        for key, method in (("ours", args.method), ("paper_method", "window")):
            record = Path(args.record) if args.record else None
            results = run_case(case, args.runs, method, simplex, record)
            metrics[key][case] = summarise(results)
            label = "ours" if key == "ours" else "paper's method"
            plot_gd_trace(results, track, title=f"{title}, {label}: GD").savefig(
                out / f"gd_trace_{case}_{key}.png", dpi=150
            )
            plot_speed(results, track, title=f"{title}, {label}: speed").savefig(
                out / f"speed_{case}_{key}.png", dpi=150
            )
    metrics["paper"] = PAPER_RMSE
    metrics["settings"] = vars(args)

    print(f"RMSE of the GD estimate, pooled over {args.runs} runs (paper: Lewis et al. 2025)")
    print(f"{'case':<6}{'part':<9}{'paper':>8}{'paper method':>14}{'ours':>8}   ours per run")
    for case in ("A", "B"):
        for gd in (300, 500):
            key = f"rmse_gd{gd}"
            ours = metrics["ours"][case]
            per_run = " ".join(f"{r['rmse'][str(gd)]:6.1f}" for r in ours["runs"])
            print(
                f"{case:<6}{'GD ' + str(gd):<9}{PAPER_RMSE[case][key]:8.1f}"
                f"{metrics['paper_method'][case][key]:14.1f}{ours[key]:8.1f}   {per_run}"
            )
    print()
    head = ("delay up (m)", "delay down", "fast on GD>350", "90% cover", "time (s)", "x real time")
    print(f"{'case':<6}{'run':<5}" + "".join(f"{h:>{len(h) + 2}}" for h in head))
    for case in ("A", "B"):
        for k, r in enumerate(metrics["ours"][case]["runs"], start=1):
            up, down = (r["detection_delay_m"] + [np.nan, np.nan])[:2]
            print(
                f"{case:<6}{k:<5}{up:14.1f}{down:12.1f}{r['fast_on_rough_m']:14.1f} m"
                f"{r['coverage']:11.2f}{r['traversal_time_s']:10.1f}{r['real_time_factor']:13.0f}"
            )
    (out / "metrics.json").write_text(json.dumps(metrics, indent=2, default=float))
    print(f"\nwrote {out / 'metrics.json'} and the figures gd_trace_*.png, speed_*.png")
    if args.record:
        print(f"wrote one MCAP per run in {args.record} (open in Foxglove with "
              "examples/foxglove_layout.json)")  # fmt: skip
    return metrics


if __name__ == "__main__":
    main()
