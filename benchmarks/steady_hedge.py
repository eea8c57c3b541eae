"""Where the steady roads' bias comes from: the change-point posterior split by run length.

Each steady road (one GD, 100 m, driven at a constant speed, as the ``steady`` set of
``closed_loop_accuracy.py``) is driven in closed loop with the shipped band emulator; its samples
are then replayed through a BCR with the loop's settings (the replay's estimates are checked to
be the loop's), and every estimate made after the first 25 m is split by the distance since the
last change (`control.BCR.mass_by_run`): runs that began within 5 m, 5-15 m and earlier. Per
cell it prints the relative bias of the estimate with its standard error clustered by road, and
per class the mean posterior mass, the class's mass-weighted conditional mean of GD, and its
part of the bias, mean(mass x (conditional mean - GD)) / GD (the three parts sum to the bias).

The runs of 15 m and more pool every block since their start: their part is what the emulator's
error and the road's realised roughness leave. The shorter runs are the filter's hedge that the
roughness changed recently; at the domain's edges a change can go one way only, so the hedge
leans inwards ("Why steady roads miss 5% / 10%" in docs/closed-loop.md).

    python benchmarks/steady_hedge.py                        # GD 250 / 400 / 550 at 1 and 2 m/s
    python benchmarks/steady_hedge.py --roads 16 --gd 250 550 --speeds 2.0 --cases B
"""

from __future__ import annotations

import argparse
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

import control
import roadgen
from control.bcr import emulator_domain
from gpmsa.model.data import MAX_SEED

sys.path.insert(0, str(Path(__file__).resolve().parent))
from closed_loop_accuracy import (  # noqa: E402  (the steady set's definition)
    NOISE_STD,
    STEADY_ROAD_M,
    STEADY_SCORED_AFTER_M,
    steady_simplex,
)

EDGES_M = (5.0, 15.0)
CLASSES = ("< 5 m", "5-15 m", ">= 15 m")
_EMULATORS: dict[str, object] = {}


def _emulator(case: str):
    if case not in _EMULATORS:
        _EMULATORS[case] = control.shipped_emulator(case, "band")
    return _EMULATORS[case]


def replay(result: control.ClosedLoopResult, emulator) -> tuple[np.ndarray, ...]:
    """Feed a run's samples, update by update, to a fresh BCR with the run's settings; return
    its estimates' means (k,), `BCR.mass_by_run` of each (k, classes, GD nodes; NaN where
    there is no estimate) and the GD nodes."""
    bcr = control.BCR.from_emulator(emulator, result.settings["bcr"])
    ends = np.searchsorted(result.sample_time, result.time, side="right")
    means, parts, start = [], [], 0
    for end in ends:
        sl = slice(start, end)
        est = bcr.update(
            result.sample_time[sl], result.sample_position[sl], result.sample_accel[sl],
            result.sample_speed[sl], now=float(result.sample_time[end - 1]),
        )  # fmt: skip
        means.append(est.gd_mean)
        none = np.full((len(CLASSES), bcr.model.gd.size), np.nan)
        parts.append(bcr.mass_by_run(EDGES_M) if est.ok else none)
        start = end
    return np.array(means), np.array(parts), bcr.model.gd


def _run(job: tuple[str, float, float, int]) -> dict:
    case, gd, speed, seed = job
    emu = _emulator(case)
    track = roadgen.track(((STEADY_ROAD_M, gd),), seed=seed)
    simplex = steady_simplex(speed)
    r = control.run_closed_loop(track, emu, noise_std=NOISE_STD[case], seed=seed, simplex=simplex)
    means, parts, nodes = replay(r, emu)
    if not np.array_equal(means, r.gd_mean, equal_nan=True):
        raise RuntimeError(f"the replay of {job} did not reproduce the loop's estimates")
    keep = (r.position > STEADY_SCORED_AFTER_M) & np.isfinite(means)
    mass = parts[keep].sum(axis=2)  # (k, classes)
    with np.errstate(invalid="ignore", divide="ignore"):
        cond = parts[keep] @ nodes / mass  # conditional mean of GD per class
    return {"job": job, "mean": means[keep], "mass": mass, "cond": cond}


def report(results: list[dict], case: str, gd: float, speed: float) -> str:
    runs = [r for r in results if r["job"][:3] == (case, gd, speed)]
    bias, se = control.clustered_mean([r["mean"] / gd - 1.0 for r in runs])
    mass = np.vstack([r["mass"] for r in runs])
    cond = np.vstack([r["cond"] for r in runs])
    cells = [f"{case}  GD {gd:4.0f}  {speed:.1f} m/s  bias {100 * bias:+5.1f}% ({100 * se:.1f})"]
    for c, name in enumerate(CLASSES):
        m = mass[:, c]
        share = np.where(m > 0, m * (np.nan_to_num(cond[:, c]) - gd), 0.0)
        weighted = np.nansum(m * cond[:, c]) / m.sum() if m.sum() > 0 else np.nan
        part = 100 * share.mean() / gd
        cells.append(f"{name}: mass {m.mean():.2f}, mean {weighted:4.0f}, part {part:+5.1f}%")
    return "  |  ".join(cells)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--roads", type=int, default=8,
                        help="roads per cell (seeds from --first-seed)")  # fmt: skip
    parser.add_argument("--first-seed", type=int, default=9001, help="first road and noise seed")
    parser.add_argument("--gd", type=float, nargs="+", default=[250.0, 400.0, 550.0],
                        help="GD levels, within the emulator's domain")  # fmt: skip
    parser.add_argument("--speeds", type=float, nargs="+", default=[1.0, 2.0],
                        help="constant speeds, m/s, within the emulator's speeds")  # fmt: skip
    parser.add_argument("--cases", default="A,B", help="test cases: A (noise-free), B (noise)")
    parser.add_argument("--workers", type=int, default=2, help="worker processes")
    args = parser.parse_args()
    if args.roads < 2:
        parser.error(f"--roads must be >= 2 (a standard error needs two), got {args.roads}")
    if args.first_seed < 0:
        parser.error(f"--first-seed must be >= 0, got {args.first_seed}")
    if args.first_seed + args.roads - 1 >= MAX_SEED:
        parser.error(f"--first-seed {args.first_seed}: its {args.roads} seeds run beyond the "
                     "seeds' range [0, 2**128)")  # fmt: skip
    if args.workers < 1:
        parser.error(f"--workers must be >= 1, got {args.workers}")
    cases = [c for c in args.cases.split(",") if c]
    if not cases or not set(cases) <= set(NOISE_STD):
        parser.error(f"--cases must be among {list(NOISE_STD)}, got {args.cases!r}")
    for case in cases:
        emu = _emulator(case)
        (v_lo, v_hi), (g_lo, g_hi) = emulator_domain(emu)
        for gd in args.gd:
            if not g_lo <= gd <= g_hi:
                parser.error(f"--gd {gd:g}: outside emulator {case}'s GDs [{g_lo:g}, {g_hi:g}]")
        for v in args.speeds:
            if not v_lo <= v <= v_hi:
                parser.error(f"--speeds {v:g}: outside {case}'s speeds [{v_lo:g}, {v_hi:g}] m/s")
    jobs = [
        (case, float(gd), float(v), seed)
        for case in cases for gd in args.gd for v in args.speeds
        for seed in range(args.first_seed, args.first_seed + args.roads)
    ]  # fmt: skip
    tic = time.perf_counter()
    with ProcessPoolExecutor(max_workers=args.workers) as pool:
        results = list(pool.map(_run, jobs))
    print(
        f"steady roads {args.first_seed}-{args.first_seed + args.roads - 1} ({args.roads} a cell), "
        f"estimates after {STEADY_SCORED_AFTER_M:g} m of {STEADY_ROAD_M:g}; bias (se clustered "
        "by road), and per class of the distance since the last change: mean mass, mean GD, part "
        "of the bias"
    )
    for case in cases:
        for gd in args.gd:
            for v in args.speeds:
                print(report(results, case, float(gd), float(v)))
    print(f"{len(jobs)} runs in {time.perf_counter() - tic:.0f} s on {args.workers} worker(s)")


if __name__ == "__main__":
    main()
