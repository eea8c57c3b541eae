"""What an estimator that knew where the roughness changes could do on the paper's track: the
GD-300 and GD-500 RMSE of two oracles, on the shipped estimator's own drives.

    python benchmarks/oracle_bounds.py                 # seeds 1-3 and 11-20, cases A and B
    python benchmarks/oracle_bounds.py --seeds 101-132 --cases A --workers 2

Each run drives the paper's track in closed loop with the shipped band emulator and estimator
(`control.run_closed_loop`, run k: track and noise seed k). Its samples are then replayed,
update by update, through the BCR's pieces without its sensor guards: the newest block's
feature (`control.block_features`), the emulator's likelihood (`control.ObservationModel`),
one change-point filter per phase (`control.ChangePointFilter`), the phases pooled as the BCR
pools them (the phase with the newest block weighs most). Blocks whose speed changes by more
than the BCR allows, or that no GD explains, are skipped, as the BCR skips them. Three filters:

- ``filters``: the shipped settings, no oracle: a check that the replay is the BCR's
  estimator (it lacks the guards' undo of the blocks before a fault, so it is close to, not
  equal to, the loop's figures);
- ``reset``: each phase's filter goes back to its prior (log-uniform on the emulator's GD
  domain) at the true change points; blocks that straddle a change are skipped, so each run
  starts from the new segment's first whole block;
- ``no change``: the same resets, and no change points in between (the segment length's mean
  set to 1e9 m): every block of a segment pooled.

Until a phase has a block of the new segment the pooled posterior is the prior, and the
estimate its mean (GD 364 on 200-600): an estimate with no information yet, scored as any
other. The drives are the shipped estimator's (its speed commands), so the oracles' errors are
those of the same samples at the same places, weighted as the metric weighs the shipped
estimates (one per update: more where the robot crawls). They bound what any estimator of
these blocks and this likelihood could do on these drives: ``no change`` knows what no
estimator can. Targets (issue 12): <= 35 on the GD-300 parts, <= 60 on the GD-500 part.
"""

from __future__ import annotations

import argparse
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, replace

import numpy as np
from _host import load_average

import control
import roadgen
from control.bcr import MAX_SPEED_CHANGE
from control.changepoint import mixture_posterior
from gpmsa.model.data import MAX_SEED

PAPER_TRACK = ((50.0, 300.0), (50.0, 500.0), (50.0, 300.0))
NOISE_STD = {"A": 0.0, "B": 1.0}
ORACLES = ("filters", "reset", "no change")
NO_CHANGE_SEGMENT_M = 1e9
_EMULATORS: dict[str, object] = {}
_MODELS: dict[str, control.ObservationModel] = {}


def _emulator(case: str):
    if case not in _EMULATORS:
        _EMULATORS[case] = control.shipped_emulator(case, "band")
        _MODELS[case] = control.ObservationModel(_EMULATORS[case])
    return _EMULATORS[case]


@dataclass
class _Phase:
    filter: control.ChangePointFilter
    pos_block: float = np.nan  # position at the end of its newest block, m
    data_time: float = np.nan  # time of its newest block's last sample, s


def replay(
    result: control.ClosedLoopResult, model: control.ObservationModel, oracle: str,
    change_m: tuple[float, ...],
) -> np.ndarray:  # fmt: skip
    """Posterior means of GD at the run's updates (k,) from the ``oracle`` filter (`ORACLES`);
    ``change_m``: the track's change points, m (used by the oracles only); NaN before the
    drive's first whole block."""
    s: control.BCRSettings = result.settings["bcr"]
    cp = s.changepoint
    if oracle == "no change":
        cp = replace(cp, mean_segment_m=NO_CHANGE_SEGMENT_M)
    phases = [_Phase(control.ChangePointFilter(model.gd, cp)) for _ in range(s.phases)]
    B, (v_lo, v_hi) = s.feature.block_samples, model.speed_range
    ends = np.searchsorted(result.sample_time, result.time, side="right")
    pos, spd = result.sample_position, result.sample_speed
    changes = list(change_m) if oracle != "filters" else []
    segment_start = -np.inf
    means = np.full(ends.size, np.nan)
    for i, end in enumerate(ends):
        now = float(pos[end - 1])
        while changes and now >= changes[0]:  # the oracle: a change was passed
            segment_start = changes.pop(0)
            for ph in phases:
                ph.filter.reset()
                ph.pos_block, ph.data_time = np.nan, np.nan
        ph = phases[i % len(phases)]
        ds = max(now - ph.pos_block, 0.0) if np.isfinite(ph.pos_block) else 0.0
        ph.pos_block = now
        block = slice(end - B, end)
        v = float(np.mean(spd[block])) if end >= B else np.nan
        usable = (
            end >= B and pos[end - B] >= segment_start and v_lo <= v <= v_hi
            and np.min(spd[block]) >= MAX_SPEED_CHANGE * np.max(spd[block])
        )  # fmt: skip
        y = control.block_features(result.sample_accel[block], s.feature)[0] if usable else None
        if y is not None and model.plausibility(y, v)[1] >= s.plausibility_p:
            ph.filter.update(model.loglik(y, v), ds)
            ph.data_time = float(result.sample_time[end - 1])
        else:
            ph.filter.predict(ds)
        if end >= B:  # (before the drive's first whole block the BCR has no estimate either)
            means[i] = _pooled_mean(phases)
    return means


def _pooled_mean(phases: list[_Phase]) -> float:
    """The BCR's pooled posterior mean (`control.changepoint.mixture_posterior`, as the BCR
    pools): phases with data, the newest weighing K, the next K - 1, ...; the prior's mean when
    none has data since its reset."""
    used = sorted((ph for ph in phases if ph.filter.has_data), key=lambda ph: -ph.data_time)
    if not used:
        return phases[0].filter.posterior().mean("GD")
    weights = np.arange(len(phases), len(phases) - len(used), -1, dtype=float)
    return mixture_posterior([ph.filter for ph in used], weights).mean("GD")


def _run(job: tuple[str, int]) -> dict:
    case, seed = job
    emu = _emulator(case)
    track = roadgen.track(PAPER_TRACK, seed=seed)
    r = control.run_closed_loop(track, emu, noise_std=NOISE_STD[case], seed=seed)
    change_m = tuple(float(b) for b in track.boundaries_m[1:])
    out = {"job": job, "loop": r.metrics.gd_errors}
    for oracle in ORACLES:
        means = replay(r, _MODELS[case], oracle, change_m)
        out[oracle] = control.gd_errors(track, r.position, means)
    return out


def seed_group(text: str) -> list[int]:
    """One group of seeds as text, "11-20" or "7", as a list; ValueError unless it names
    seeds in [0, 2**128) in increasing order."""
    lo, dash, hi = text.partition("-")
    try:
        first, last = int(lo), int(hi) if dash else int(lo)
    except ValueError:
        raise ValueError(f"{text!r} is not a seed or a range of seeds like 11-20") from None
    if first < 0 or last < first:
        raise ValueError(f"{text!r} must name seeds >= 0, the first no larger than the last")
    if last >= MAX_SEED:
        raise ValueError(f"{text!r} names seeds beyond the seeds' range [0, 2**128)")
    return list(range(first, last + 1))


def main() -> None:
    parser = argparse.ArgumentParser(description=" ".join(__doc__.split("\n\n")[0].split()))
    parser.add_argument("--seeds", default="1-3,11-20",
                        help="seed groups, each reported alone (e.g. 1-3,11-20)")  # fmt: skip
    parser.add_argument("--cases", default="A,B", help="test cases: A (noise-free), B (noise)")
    parser.add_argument("--workers", type=int, default=2, help="worker processes")
    args = parser.parse_args()
    try:
        groups = [seed_group(g) for g in args.seeds.split(",")]
    except ValueError as exc:
        parser.error(f"--seeds: {exc}")
    cases = [c for c in args.cases.split(",") if c]
    if not cases or not set(cases) <= set(NOISE_STD):
        parser.error(f"--cases must be among {list(NOISE_STD)}, got {args.cases!r}")
    if args.workers < 1:
        parser.error(f"--workers must be >= 1, got {args.workers}")
    jobs = [(case, seed) for case in cases for g in groups for seed in g]
    tic = time.perf_counter()
    with ProcessPoolExecutor(max_workers=args.workers) as pool:
        results = {r["job"]: r for r in pool.map(_run, jobs)}
    load = load_average()
    print(
        "paper track, RMSE of GD on the GD-300 / GD-500 parts (targets 35 / 60), the shipped "
        "estimator's drives"
    )
    print(f"{'case':4}  {'seeds':>7}  " + "  ".join(f"{n:>13}" for n in ("loop", *ORACLES)))
    for case in cases:
        for g in groups:
            cells = []
            for name in ("loop", *ORACLES):
                errors = [results[(case, seed)][name] for seed in g]
                rmse = [control.pooled_rmse(errors, gd) for gd in (300.0, 500.0)]
                cells.append(f"{rmse[0]:6.1f}/{rmse[1]:6.1f}")
            print(f"{case:4}  {g[0]:>3}-{g[-1]:<3}  " + "  ".join(f"{c:>13}" for c in cells))
    print(
        f"{len(jobs)} runs in {time.perf_counter() - tic:.0f} s on {args.workers} worker(s); "
        f"load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}"
    )


if __name__ == "__main__":
    main()
