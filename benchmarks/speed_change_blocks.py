"""Blocks that hold a speed change: how far off is what one block says about GD, and why.

    python benchmarks/speed_change_blocks.py                    # both parts, case A
    python benchmarks/speed_change_blocks.py --part open --roads 160 --workers 2
    python benchmarks/speed_change_blocks.py --part loop --case B

The emulator knows constant speeds only; the BCR reads a block at its mean speed. The band
powers, though, weigh a block's samples by the DPSS tapers' mean power, which falls towards the
block's ends; the benchmark also reads each block at that weighted mean speed (``tapered``), to
first order the speed its spectrum saw. Two parts:

- ``open``: steady single-GD roads (GD 300 and 500; ``--roads`` road seeds each; with case B's
  sensor noise for ``--case B``) driven in open loop at v0, then commanded to v1 (2.0 -> 1.0,
  1.0 -> 2.0, 1.5 -> 1.2, 1.2 -> 1.5 m/s; the vehicle ramps at its own ``max_accel_mps2``, the
  Jackal's 20 m/s^2). For blocks starting at fixed offsets from the command (in samples:
  negative, the step lies inside the block), the maximum-likelihood log GD of the block alone
  (the shipped band emulator's `control.ObservationModel` on its grid) minus the true log GD,
  averaged over roads, read at the block's plain mean speed and at the tapered one; and, with
  the step at every fifth sample of a block (its place uniform in the block), the mean error
  (its standard error over runs: one run's blocks overlap) and the mean squared error of
  either reading. No selection: the speed does not depend on the
  road.
- ``loop``: the closed loop (shipped estimator and Simplex) on the paper's track, seeds
  ``--first-seed`` onwards. The disjoint 125-sample blocks at the three phases' offsets, within
  one segment and past the first 5 m, grouped by the ratio of their highest to lowest speed and
  by its direction; each block's error as above (at its mean speed, as the BCR reads it). Then
  the same speed commands are replayed on another road of the same GD sequence (road seed +
  10000): the same speed changes, but chosen without looking at that road. A difference
  between the two says the error comes from *why* the speed changed (the estimator slowed down
  because the blocks read rough), not from the change itself.

Printed: the load average, the tables with each mean's standard error (over roads; in the loop
part clustered by run).

Run time: ~65 s for both parts on 2 workers at the defaults (docs/closed-loop.md's figures);
``--part open --roads 2`` a few seconds.
"""

from __future__ import annotations

import argparse
import os
import time
from concurrent.futures import ProcessPoolExecutor
from functools import cache

import numpy as np
from _host import load_average
from scipy.signal.windows import dpss

import control
import roadgen
import vehicle
from control.bcr import MAX_SPEED_CHANGE
from control.shipped import shipped_emulator
from gpmsa.model.data import MAX_SEED

RATE_HZ = 120.0
STEPS = ((2.0, 1.0), (1.0, 2.0), (1.5, 1.2), (1.2, 1.5))
OFFSETS = (-250, -125, -100, -63, -25, 0, 30, 60, 120, 250)
INSIDE = tuple(range(-120, 0, 5))  # the step at every fifth sample of a block
BEFORE_S, AFTER_S = 4.0, 5.0
PAPER_TRACK = ((50.0, 300.0), (50.0, 500.0), (50.0, 300.0))
RATIO_CLASSES = ((1.0, 1.001), (1.001, 1.05), (1.05, 1.15), (1.15, 1.5), (1.5, 2.001))
OTHER_ROAD = 10000
NOISE_STD = {"A": 0.0, "B": 1.0}


def load() -> str:
    return "load average {:.2f} {:.2f} {:.2f}".format(*load_average())


class _BlockReader:
    """ML log GD error of single blocks under a case's shipped band emulator."""

    def __init__(self, case: str) -> None:
        self.emulator = shipped_emulator(case, "band")
        self.model = control.ObservationModel(self.emulator)
        self.bcr = control.bcr_settings_for(self.emulator)
        self.spec = self.bcr.feature
        w = (dpss(self.spec.block_samples, self.spec.taper_nw, self.spec.n_tapers) ** 2).mean(0)
        self.sample_weights = w / w.sum()

    def tapered_speed(self, speed: np.ndarray) -> float:
        """The block's mean speed weighted as its band powers weigh the samples, m/s."""
        return float(np.clip(self.sample_weights @ speed, speed.min(), speed.max()))

    def error(self, accel: np.ndarray, speed: float, gd: float) -> float:
        y = control.block_features(accel, self.spec)[0]
        return float(np.log(self.model.gd[np.argmax(self.model.loglik(y, speed))] / gd))


@cache
def _reader(case: str) -> _BlockReader:
    """One reader per case and worker process."""
    return _BlockReader(case)


def _open_run(job: tuple[str, int, float, float, float]) -> list[tuple[int, float, float]]:
    """(offset, error at the plain mean speed, error at the tapered speed) of one road and step,
    for the offsets of OFFSETS and INSIDE."""
    case, seed, gd, v0, v1 = job
    r = _reader(case)
    length = v0 * BEFORE_S + v1 * AFTER_S + 5.0
    track = roadgen.track([(length, gd)], seed=seed)
    sim = vehicle.Simulation(vehicle.Jackal(), track, noise_std=NOISE_STD[case], seed=seed)
    first = sim.advance(BEFORE_S, v0)
    second = sim.advance(AFTER_S, v1)
    accel = np.concatenate([first.accel_front, second.accel_front])
    speed = np.concatenate([first.speed, second.speed])
    start_steady = int(np.argmax(first.speed >= v0))  # past the start from rest
    n_block = r.spec.block_samples
    out = []
    for rel in sorted(set(OFFSETS + INSIDE)):
        i0 = len(first) + rel
        if i0 < start_steady + 1 or i0 + n_block > accel.size:
            continue
        a, v = accel[i0 : i0 + n_block], speed[i0 : i0 + n_block]
        plain, tapered = float(v.mean()), r.tapered_speed(v)
        out.append((rel, r.error(a, plain, gd), r.error(a, tapered, gd)))
    return out


def _blocks(r: _BlockReader, track, accel, speed, position) -> list[tuple[float, bool, float]]:
    """(speed ratio, speeding up, error) of the disjoint blocks at the three phases' offsets."""
    n_block = r.spec.block_samples
    rows = []
    for off in (0, n_block // 3, 2 * n_block // 3):
        n = (accel.size - off) // n_block
        a, s, p = (x[off : off + n * n_block].reshape(n, n_block) for x in (accel, speed, position))
        for i in range(n):
            v = float(s[i].mean())
            gd = track.gd_at(p[i, 0])
            if not (1.0 <= v <= 2.0) or s[i].min() < MAX_SPEED_CHANGE * s[i].max():
                continue
            if track.gd_at(p[i, -1]) != gd or p[i, 0] < 5.0:
                continue
            rows.append((s[i].max() / s[i].min(), bool(s[i, -1] > s[i, 0]), r.error(a[i], v, gd)))
    return rows


def _loop_run(job: tuple[str, int]) -> tuple[list, list]:
    """The blocks of one closed-loop run, and of its speed commands replayed on another road."""
    case, seed = job
    r = _reader(case)
    track = roadgen.track(PAPER_TRACK, seed=seed)
    res = control.run_closed_loop(track, r.emulator, seed=seed, noise_std=NOISE_STD[case])
    own = _blocks(r, track, res.sample_accel, res.sample_speed, res.sample_position)
    other = roadgen.track(PAPER_TRACK, seed=seed + OTHER_ROAD)
    sim = vehicle.Simulation(
        vehicle.Jackal(), other, noise_std=NOISE_STD[case], seed=seed + OTHER_ROAD
    )
    dt = r.bcr.samples_per_update / RATE_HZ
    accel, speed, position = [], [], []
    for command in np.concatenate([[res.command[0]], res.command[:-1]]):
        if sim.finished:
            break
        x = sim.advance(dt, float(command))
        accel.append(x.accel_front)
        speed.append(x.speed)
        position.append(x.position)
    replay = _blocks(r, other, *(np.concatenate(x) for x in (accel, speed, position)))
    return own, replay


def _mean_se(x: np.ndarray) -> str:
    return f"{x.mean():+.3f} ({x.std() / np.sqrt(x.size):.3f})" if x.size > 1 else "-"


def _clustered(per_run: list[np.ndarray]) -> str:
    """Mean of all runs' values with its standard error clustered by run (a run's blocks at the
    three phases' offsets overlap, so they are not independent)."""
    mean, se = control.clustered_mean(per_run)
    return "-" if np.isnan(se) else f"{mean:+.3f} ({se:.3f})"


def open_part(case: str, roads: int, first_seed: int, workers: int) -> None:
    jobs = [
        (case, seed, gd, v0, v1)
        for seed in range(first_seed, first_seed + roads)
        for gd in (300.0, 500.0)
        for v0, v1 in STEPS
    ]
    with ProcessPoolExecutor(workers) as pool:
        results = list(pool.map(_open_run, jobs, chunksize=4))
    print(f"\nopen loop, case {case}: {roads} roads x GD 300, 500; mean log GD error of one block")
    print("(se), read at its plain mean speed / at the tapered speed; offset = block start -")
    print("command, in samples")
    for v0, v1 in STEPS:
        print(f"  step {v0} -> {v1} m/s")

        def errors(offsets, step=(v0, v1)):
            """(roads, len(offsets), 2) errors of the step's runs at ``offsets``."""
            runs = [
                [(plain, tapered) for k, plain, tapered in out if k in offsets]
                for job, out in zip(jobs, results, strict=True)
                if job[3:] == step
            ]
            return np.array([run for run in runs if len(run) == len(offsets)])

        for rel in OFFSETS:
            e = errors((rel,))[:, 0]
            print(f"    offset {rel:5d}: {_mean_se(e[:, 0])}  /  {_mean_se(e[:, 1])}  n {len(e)}")
        e = errors(INSIDE)
        per_run = e.mean(axis=1)  # a run's blocks overlap: its mean is one draw
        print(
            f"    step anywhere in the block: mean {_mean_se(per_run[:, 0])} / "
            f"{_mean_se(per_run[:, 1])}, mean square {np.mean(e[:, :, 0] ** 2):.4f} / "
            f"{np.mean(e[:, :, 1] ** 2):.4f}  ({len(e)} runs)"
        )


def loop_part(case: str, runs: int, first_seed: int, workers: int) -> None:
    jobs = [(case, seed) for seed in range(first_seed, first_seed + runs)]
    with ProcessPoolExecutor(workers) as pool:
        results = list(pool.map(_loop_run, jobs))
    print(f"\nclosed loop, case {case}, paper track, seeds {first_seed}-{first_seed + runs - 1}:")
    print("mean log GD error of one block (se), by highest / lowest speed in the block")
    head = ("speed ratio", "", "own road (closed loop)", "same speeds, other road")
    print("  {:>16s} {:4s}  {:>26s}  {:>26s}".format(*head))
    for lo, hi in RATIO_CLASSES:
        for up in (False, True):
            if lo == 1.0 and up:
                continue
            cells = []
            for side in (0, 1):
                rows = [np.array(run[side]).reshape(-1, 3) for run in results]
                picked = [r[(r[:, 0] >= lo) & (r[:, 0] < hi) & (r[:, 1] == up), 2] for r in rows]
                cells.append(f"{_clustered(picked):>16s} n {sum(x.size for x in picked):5d}")
            way = "" if lo == 1.0 else ("up" if up else "down")
            print(f"  [{lo:.3f}, {hi:.3f}) {way:4s}  {cells[0]:>26s}  {cells[1]:>26s}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--part", choices=("open", "loop", "both"), default="both",
                    help="open loop, closed loop or both (default both)")  # fmt: skip
    ap.add_argument("--case", choices=("A", "B"), default="A",
                    help="A: noise-free, B: N(0, 1) sensor noise (default A)")  # fmt: skip
    ap.add_argument("--roads", type=int, default=160,
                    help="open part: road seeds per GD, >= 2 (default 160)")  # fmt: skip
    ap.add_argument("--runs", type=int, default=16,
                    help="loop part: closed-loop runs, >= 2 (default 16)")  # fmt: skip
    ap.add_argument("--first-seed", type=int, default=101, help="first seed of either part")
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1,
                    help="worker processes (default: the CPU count)")  # fmt: skip
    args = ap.parse_args()
    for option, value, least in (("--roads", args.roads, 2), ("--runs", args.runs, 2),
                                 ("--workers", args.workers, 1),
                                 ("--first-seed", args.first_seed, 0)):  # fmt: skip
        if value < least:
            ap.error(f"{option} must be >= {least}, got {value}")
    last = args.first_seed + max(args.roads, args.runs) - 1 + OTHER_ROAD  # the other roads' too
    if last >= MAX_SEED:
        ap.error(f"--first-seed {args.first_seed}: its seeds run to {last}, beyond the seeds' "
                 "range [0, 2**128)")  # fmt: skip
    tic = time.perf_counter()
    print(load())
    if args.part in ("open", "both"):
        open_part(args.case, args.roads, args.first_seed, args.workers)
    if args.part in ("loop", "both"):
        loop_part(args.case, args.runs, args.first_seed, args.workers)
    print(f"\n{time.perf_counter() - tic:.0f} s on {args.workers} worker(s), {load()}")


if __name__ == "__main__":
    main()
