"""The Simplex's release dwell (``Simplex.release_m``) against low gains, and its cost when healthy.

What it removes of a low accelerometer gain's speed-up on rough ground, and what it costs a
healthy run:

(a) Gain faults: the track of docs/closed-loop.md's gain sweeps (6 m of GD 300, then 14 m of GD
    500; road and run seed s = 1-5), an accelerometer gain g (a ``scale`` fault) from t0 = 1-5 s
    to the end, each drive beside its fault-free twin (same seed, same Simplex). Per case, gain
    and ``release_m``: the drives that drove farther faster than v_safe on GD 500 than their
    twin (``LoopMetrics.fast_on_rough_m``, more than 0.01 m), those metres summed over the drives
    (the twins' sum beside them) and the excess over the twin summed (the positive part, drive
    by drive).
(b) The same on 6 m of GD 300 then 30 m of GD 500, the gain from t0 = 8, 10, 12, 14 or 16 s on
    (inside the rough part, where the fault-free robot drives in safety mode): the case the
    dwell is for, a drop below GD_max that the fault makes.
(c) Fault-free cost: the paper's track (50 m GD 300 / 500 / 300, track and run seeds 1-3, as
    ``examples/closed_loop.py``): the time to drive the track, the metres driven in safety
    mode on its GD-300 parts, the metres faster than v_safe on GD 500 and the estimate's RMSE per
    part (pooled over the runs, as the example's "ours" column), summed or pooled over the seeds.

``--from-start`` also applies the dwell to the start's safety mode (the buffer filling), which
the Simplex exempts: a variant, to show what that would cost.

Usage: python benchmarks/release_dwell.py [--release 0,5,10,20] [--cases B A] [--from-start]
[--quick]

Run time: ~4.5 min at the defaults on 2 shared cores (264 s at load 2.6); ~1 s with
``--quick`` (one seed, one fault start, gain 0.7, release 10, case B, no paper track).
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import time
from collections.abc import Sequence

import numpy as np
from _host import load_average

import control
import roadgen

GAIN_TRACK = ((6.0, 300.0), (14.0, 500.0))
PAPER_TRACK = ((50.0, 300.0), (50.0, 500.0), (50.0, 300.0))
LATE_TRACK = ((6.0, 300.0), (30.0, 500.0))
LATE_STARTS = (8, 10, 12, 14, 16)
"""(b): the gain from inside the rough part (entered at 3-5 s), where safety mode has begun."""
GAINS = (0.5, 0.7, 0.8)
FASTER_M = 0.01
"""A drive is faster than its twin when it drove more than this farther fast on rough ground, m."""


@dataclasses.dataclass(frozen=True)
class DwellFromStart(control.Simplex):
    """A Simplex whose release dwell also holds the start's safety mode (a variant measured here,
    not offered by `control.Simplex`)."""

    def start(self) -> control.SimplexRun:
        run = control.SimplexRun(self)
        run.performed = True
        return run


def simplex_for(release_m: float, from_start: bool) -> control.Simplex:
    return (DwellFromStart if from_start and release_m > 0 else control.Simplex)(
        release_m=release_m
    )


def safety_m_on(result: control.ClosedLoopResult, track, gd: float) -> float:
    """Metres the run drove in safety mode where the prescribed GD is ``gd``: each sample step
    under the command of the newest update before it (the start's command before the first)."""
    pos, t = result.sample_position, result.sample_time
    which = np.searchsorted(result.time, t, side="left") - 1
    safety = np.where(which < 0, True, result.mode[np.maximum(which, 0)] == "safety")
    starts = np.asarray(track.boundaries_m, dtype=float)
    seg_gd = np.array([g for _, g in track.segments], dtype=float)
    on = seg_gd[np.clip(np.searchsorted(starts, pos, side="right") - 1, 0, seg_gd.size - 1)] == gd
    step = np.diff(pos, prepend=pos[0])
    return float(step[safety & on].sum())


def gain_rows(
    case, releases, seeds, starts, gains, from_start, segments=GAIN_TRACK, likelihood=None
):
    """(case, gain, release_m, faster drives, drives, fast m summed, twins' fast m, excess m) on
    the track of ``segments`` ((length m, GD), ...), the gain from each of ``starts`` (s) on;
    ``likelihood``: case's prepared `control.ObservationModel` (default: one made here)."""
    emulator = control.shipped_emulator(case)
    likelihood = control.ObservationModel(emulator) if likelihood is None else likelihood
    noise = control.emulator_noise_std(emulator) or 0.0
    rows = []
    for release in releases:
        simplex = simplex_for(release, from_start)
        fast = {g: [] for g in gains}
        for seed in seeds:
            track = roadgen.track(list(segments), seed=seed)
            kw = dict(noise_std=noise, seed=seed, likelihood=likelihood, simplex=simplex)
            twin = control.run_closed_loop(track, emulator, **kw).metrics.fast_on_rough_m
            for g in gains:
                for t0 in starts:
                    fault = control.SensorFault(float(t0), 1e6, "scale", g)
                    run = control.run_closed_loop(track, emulator, faults=[fault], **kw)
                    fast[g].append((run.metrics.fast_on_rough_m, twin))
        for g in gains:
            a = np.array(fast[g])
            faster = int((a[:, 0] > a[:, 1] + FASTER_M).sum())
            excess = float(np.clip(a[:, 0] - a[:, 1], 0, None).sum())
            rows.append((case, g, release, faster, len(a), a[:, 0].sum(), a[:, 1].sum(), excess))
    return rows


def paper_rows(case, releases, seeds, from_start):
    """(case, release_m, time s, safety m on GD 300, fast m on GD 500, RMSE 300, RMSE 500)."""
    emulator = control.shipped_emulator(case)
    likelihood = control.ObservationModel(emulator)
    noise = control.emulator_noise_std(emulator) or 0.0
    rows = []
    for release in releases:
        simplex = simplex_for(release, from_start)
        secs = safety = fast = 0.0
        errors = []
        for seed in seeds:
            track = roadgen.track(list(PAPER_TRACK), seed=seed)
            run = control.run_closed_loop(
                track, emulator, noise_std=noise, seed=seed, likelihood=likelihood,
                simplex=simplex,
            )  # fmt: skip
            secs += float(run.sample_time[-1])
            safety += safety_m_on(run, track, 300.0)
            fast += run.metrics.fast_on_rough_m
            errors.append(run.metrics.gd_errors)
        rmse = [control.pooled_rmse(errors, gd) for gd in (300.0, 500.0)]
        rows.append((case, release, secs, safety, fast, *rmse))
    return rows


def floats(text: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError as err:
        raise argparse.ArgumentTypeError(f"a comma-separated list of metres, got {text!r}") from err
    for v in values:
        try:
            control.Simplex(release_m=v)
        except control.ControlError as err:
            raise argparse.ArgumentTypeError(str(err)) from err
    return values


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--release", type=floats, default=[0.0, 5.0, 10.0, 20.0],
                    help="release_m values, m (default 0,5,10,20)")  # fmt: skip
    ap.add_argument("--cases", nargs="+", choices=("A", "B"), default=["B", "A"],
                    help="the shipped emulators' test cases (default B A)")  # fmt: skip
    ap.add_argument("--from-start", action="store_true",
                    help="the variant whose dwell also holds the start's safety mode")  # fmt: skip
    ap.add_argument("--quick", action="store_true",
                    help="one seed, one fault start, gain 0.7, release 10, case B, no "
                    "paper track (~1 s)")  # fmt: skip
    args = ap.parse_args(argv)
    seeds: Sequence[int] = range(1, 6)
    starts: Sequence[int] = range(1, 6)
    gains: Sequence[float] = GAINS
    releases, cases = args.release, args.cases
    if args.quick:
        seeds, starts, gains, releases, cases = [1], [3], [0.7], [10.0], ["B"]
    tic = time.perf_counter()
    variant = "dwell from the start too" if args.from_start else "dwell after performance mode"
    print(
        f"# release dwell ({variant}); (a) gain faults: {len(seeds)} seeds x {len(starts)} starts"
    )
    print("case  gain  release_m  faster than twin  fast m on GD 500 (twins)  excess over twin m")
    for case in cases:
        for c, g, rel, faster, total, fast, twin, excess in gain_rows(
            case, releases, seeds, starts, gains, args.from_start
        ):
            print(f"{c:<5} {g:<5} {rel:>9g}  {faster:>7d} of {total:<6d} "
                  f"{fast:>10.1f} ({twin:6.1f})      {excess:>10.1f}")  # fmt: skip
    if not args.quick:
        print("# (b) the gain from inside the rough part: 6 m GD 300, 30 m GD 500, t0 8-16 s")
        for case in cases:
            for c, g, rel, faster, total, fast, twin, excess in gain_rows(
                case, releases, seeds, LATE_STARTS, gains, args.from_start, LATE_TRACK
            ):
                print(f"{c:<5} {g:<5} {rel:>9g}  {faster:>7d} of {total:<6d} "
                      f"{fast:>10.1f} ({twin:6.1f})      {excess:>10.1f}")  # fmt: skip
        print("# (c) fault-free, the paper's track, seeds 1-3 summed / pooled")
        print("case  release_m  time s  safety m on GD 300  fast m on GD 500  RMSE 300  RMSE 500")
        for case in cases:
            for c, rel, secs, safety, fast, r300, r500 in paper_rows(
                case, releases, range(1, 4), args.from_start
            ):
                print(f"{c:<5} {rel:>9g}  {secs:6.1f}  {safety:>18.1f}  {fast:>16.1f}  "
                      f"{r300:8.2f}  {r500:8.2f}")  # fmt: skip
    averages = "{:.2f} {:.2f} {:.2f}".format(*load_average())
    load = f"load average {averages} on {os.cpu_count()} cores"
    print(f"{time.perf_counter() - tic:.1f} s; {load}")


if __name__ == "__main__":
    main()
