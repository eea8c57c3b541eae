"""Accuracy of the closed-loop GD estimate on the paper's track and on held-out tracks and seeds.

    python benchmarks/closed_loop_accuracy.py [--method filter] [--mean-segment 25]
        [--drift 0.01] [--prior uniform] [--workers 2] [--sets paper,heldout,other1,other2]

Prints the RMSE of the posterior-mean GD against the GD prescribed at each estimate's position,
pooled over the runs of each set, per prescribed GD, for Test Cases A (noise-free) and B (N(0, 1)
accelerometer noise) with the shipped emulators. Run k drives a track synthesised with seed k and
noise seed k. The sets:

- ``paper``: the paper's track [(50, 300), (50, 500), (50, 300)], seeds 1-3 (what
  ``examples/closed_loop.py`` prints; the paper's figures are shown next to it);
- ``heldout``: the paper's track, seeds 11-20;
- ``other1``: [(40, 250), (60, 450), (50, 350)], seeds 11-15;
- ``other2``: [(30, 400), (40, 250), (30, 550), (50, 300)], seeds 11-15.

``floor``: the RMSE of an estimator that read each window's content exactly (the mean prescribed
GD over the window's samples), under the speeds the loop drove: the part of the error that comes
from the window's length alone (`window_content`).

The held-out sets were not looked at while the BCR's settings were chosen. About 1.3 s of CPU
per run, 46 runs for all sets and both cases (under a minute on two workers).
"""

from __future__ import annotations

import argparse
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

import control
import gpmsa
import roadgen
from control.bcr import METHODS
from control.metrics import segment_index
from control.tracker import PRIORS

PAPER_TRACK = ((50.0, 300.0), (50.0, 500.0), (50.0, 300.0))
SETS = {
    "paper": (PAPER_TRACK, range(1, 4)),
    "heldout": (PAPER_TRACK, range(11, 21)),
    "other1": (((40.0, 250.0), (60.0, 450.0), (50.0, 350.0)), range(11, 16)),
    "other2": (((30.0, 400.0), (40.0, 250.0), (30.0, 550.0), (50.0, 300.0)), range(11, 16)),
}
NOISE_STD = {"A": 0.0, "B": 1.0}
PAPER_RMSE = {("A", 300.0): 42.58, ("A", 500.0): 94.42, ("B", 300.0): 50.19, ("B", 500.0): 96.23}

_CALIBRATORS: dict = {}


def window_content(result, track, buffer: int) -> np.ndarray:
    """Per update, the mean prescribed GD over the samples of its window (last `buffer` samples).

    An estimator that read every window's content exactly would report this; its RMSE against the
    GD at the estimate's position is the floor set by the window's length (a window spans
    buffer / rate * v metres behind the vehicle) under the speeds the loop drove.
    """
    seg_gd = np.array([gd for _, gd in track.segments], dtype=float)
    gd_at_sample = seg_gd[segment_index(track, result.sample_position)]
    cum = np.concatenate([[0.0], np.cumsum(gd_at_sample)])
    end = np.searchsorted(result.sample_time, result.time, side="right")
    start = np.maximum(end - buffer, 0)
    return (cum[end] - cum[start]) / np.maximum(end - start, 1)


def _run(job: tuple) -> tuple:
    """(case, set, GD errors, window-content errors) of one run; one calibrator per worker."""
    case, name, seed, method, mean_segment_m, drift, prior = job
    if case not in _CALIBRATORS:
        emu = control.shipped_emulator(case)
        _CALIBRATORS[case] = (emu, gpmsa.Calibrator(emu))
    emu, calibrator = _CALIBRATORS[case]
    tracker = control.TrackerSettings(
        mean_segment_m=mean_segment_m, drift_per_sqrt_m=drift, prior=prior
    )
    bcr = control.bcr_settings_for(emu, method=method, tracker=tracker)
    track = roadgen.track(SETS[name][0], seed=seed)
    result = control.run_closed_loop(
        track, emu, noise_std=NOISE_STD[case], seed=seed, bcr=bcr, calibrator=calibrator
    )
    floor = window_content(result, track, bcr.buffer)
    floor[~np.isfinite(result.gd_mean)] = np.nan
    return case, name, result.metrics.gd_errors, control.gd_errors(track, result.position, floor)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    defaults = control.TrackerSettings()
    parser.add_argument("--method", default="filter", choices=list(METHODS))
    parser.add_argument("--mean-segment", type=float, default=defaults.mean_segment_m)
    parser.add_argument("--drift", type=float, default=defaults.drift_per_sqrt_m)
    parser.add_argument("--prior", default=defaults.prior, choices=list(PRIORS))
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--sets", default=",".join(SETS))
    args = parser.parse_args()
    names = [n for n in args.sets.split(",") if n]
    unknown = set(names) - set(SETS)
    if unknown:
        parser.error(f"unknown sets {sorted(unknown)}; choose from {list(SETS)}")

    jobs = [
        (case, name, seed, args.method, args.mean_segment, args.drift, args.prior)
        for case in NOISE_STD
        for name in names
        for seed in SETS[name][1]
    ]
    tic = time.perf_counter()
    with ProcessPoolExecutor(max_workers=args.workers) as pool:
        results = list(pool.map(_run, jobs))
    wall = time.perf_counter() - tic

    print(
        f"RMSE of the GD estimate, pooled over runs: method={args.method}, "
        f"mean_segment_m={args.mean_segment:g}, drift_per_sqrt_m={args.drift:g}, "
        f"prior={args.prior}"
    )
    print(
        f"{'case':<6}{'set':<9}{'seeds':<8}{'GD':>6}{'runs':>6}{'n est':>7}{'RMSE':>8}{'paper':>8}"
    )
    for case in NOISE_STD:
        for name in names:
            segments, seeds = SETS[name]
            errors = [e for c, n, e, _ in results if c == case and n == name]
            floors = [f for c, n, _, f in results if c == case and n == name]
            for gd in sorted({g for _, g in segments}):
                n_est = sum(e.n for run in errors for e in run if e.gd == gd)
                rmse = control.pooled_rmse(errors, gd)
                paper = PAPER_RMSE.get((case, gd)) if name == "paper" else None
                paper_txt = f"{paper:8.1f}" if paper is not None else f"{'':>8}"
                print(
                    f"{case:<6}{name:<9}{f'{seeds[0]}-{seeds[-1]}':<8}{gd:6.0f}"
                    f"{len(errors):6d}{n_est:7d}{rmse:8.1f}{paper_txt}"
                    f"{control.pooled_rmse(floors, gd):8.1f}"
                )
    print(f"\n{len(jobs)} runs in {wall:.0f} s on {args.workers} worker(s)")


if __name__ == "__main__":
    main()
