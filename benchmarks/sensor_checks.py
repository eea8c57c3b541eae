"""False alarms and power of the sensor checks (`control.sensor_checks`) on clean campaign drives.

    PYTHONPATH=. python benchmarks/sensor_checks.py [--seed 7] [--keep-s 120] [--workers 2]
        [--cases AB] [--drives 198] [--chunks]

Runs the training campaign's design (``--drives`` drives of ``--keep-s`` s, campaign ``--seed``:
``lhs_design(drives, seed=seed)``, GD 200-600 at 0.5-2 m/s; 198 is the training campaign's)
without and with N(0, 1) sensor noise, cuts each drive into blocks of 125 samples and prints, per
case:
- the blocks that `signal_fault` flags (every check, with the sensor's noise sd where it has
  noise): the false alarms, which should be none;
- the most lattice-like stretch of the lattice check (`lattice_stretch`, 6 and 8 samples, with
  its Bonferroni factor; flagged below ``SensorLimits.lattice_p``; flights exempt as the check
  exempts them: without noise only, `flight_reading`) on the blocks as floats and
  rounded to ADC resolutions of 0.001-0.1 m/s^2 (every fourth block), as a real IMU's would be;
- the share of blocks in which the lattice check finds 6, 7 or 10 samples rounded to steps of
  1-8 m/s^2 at a random place (1,000 blocks per cell; every block where a short ``--keep-s``
  gives fewer);
- the largest ratio of the short level check per stretch length (`short_level_drop`, flights
  exempt; flagged above the limits of ``SHORT_LEVEL_STRETCHES``), and the share of blocks that
  `signal_fault` flags with 8-31 samples at a random place scaled by a gain of 0.01-0.2
  (``PICKS`` blocks per cell).

With ``--chunks`` it prints instead, per case and ``update_every`` in ``EVERY``, what the BCR's
signal checks see when a user feeds each drive from its start, one update at a time: the window
methods check each update's new samples with the ``CHECK_CONTEXT`` (32) before them, at
least the newest ``CHECK_LEAST`` (125, the blocks the limits were calibrated on;
`BCR._window_signal_reason`), the change-point method
the newest 125 samples at each update (`BCR._estimate_changepoint`; ``update_every`` >= 16).
Per method: the checks made, those `signal_fault` flags (the false alarms), the largest ratio of
the short level check per stretch in the window methods' chunks ("-": no chunk holds one), and
the share of ``DROPS`` gain drops per drive (gain 0.02-0.035 for 16-31 samples at a random place
after the first block) flagged by an update whose samples hold part of the drop.
"""

from __future__ import annotations

import argparse
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np
from _host import load_average

import vehicle
from control.bcr import CHECK_CONTEXT, CHECK_LEAST, MAX_PHASES
from control.sensor_checks import (
    SHORT_LEVEL_BEFORE,
    SHORT_LEVEL_STRETCHES,
    SensorLimits,
    flight_reading,
    most_lattice_like,
    short_level_drop,
    signal_fault,
)
from gpmsa.model.data import MAX_SEED
from vehicle.design import lhs_design

BLOCK = 125
RESOLUTIONS = (0.001, 0.0048, 0.02, 0.05, 0.1)  # m/s^2; 0.0048: a 16-bit part at +-16 g
STEPS = (1.0, 2.0, 2.6, 4.0, 8.0)  # m/s^2; 2.6: soak seed 19, #131
LENGTHS = (6, 7, 10)  # samples
PICKS = 1000  # blocks per (step, length) cell of the power table
GAINS = (0.01, 0.02, 0.035, 0.05, 0.1, 0.2)  # of the scale faults
GAIN_LENGTHS = (8, 12, 16, 24, 31)  # samples: shorter than the level check's 32
EVERY = (10, 20, 40, 60, 125)  # update_every of the --chunks table, samples
DROPS = 10  # gain drops per drive of the --chunks table
DROP_GAIN = (0.02, 0.035)  # their gains (uniform) ...
DROP_SAMPLES = (16, 31)  # ... and lengths (uniform integers), samples


def lattice_hits(blocks, step, length, rng, flight, limit) -> tuple[int, int]:
    """(blocks the lattice check flags, blocks tried): ``PICKS`` of ``blocks`` (n, BLOCK)
    drawn without replacement (all of them when there are fewer), each with ``length``
    samples at a random place rounded to multiples of ``step``, m/s^2."""
    n = min(PICKS, blocks.shape[0])
    picks = blocks[rng.choice(blocks.shape[0], n, replace=False)].copy()
    hits = 0
    for b in picks:
        start = rng.integers(0, BLOCK - length)
        part = b[start : start + length]
        b[start : start + length] = np.round(part / step) * step
        hits += most_lattice_like(b, flight)[0] < limit
    return int(hits), n


def scale_hits(blocks, gain, length, rng, limits) -> tuple[int, int]:
    """(blocks `signal_fault` flags, blocks tried): ``PICKS`` of ``blocks`` (n, BLOCK) drawn
    without replacement (all of them when there are fewer), each with ``length`` samples at a
    random place multiplied by ``gain``."""
    n = min(PICKS, blocks.shape[0])
    picks = blocks[rng.choice(blocks.shape[0], n, replace=False)].copy()
    hits = 0
    for b in picks:
        start = rng.integers(0, BLOCK - length + 1)
        b[start : start + length] *= gain
        hits += bool(signal_fault(b, limits))
    return int(hits), n


def window_spans(n: int, every: int) -> list[tuple[int, int]]:
    """(start, stop) of the samples the window methods' signal checks see at each update of a
    stream of ``n`` samples fed from its start: the update's ``every`` new samples and the
    ``CHECK_CONTEXT`` before them, at least the newest ``CHECK_LEAST``."""
    checked = max(every + CHECK_CONTEXT, CHECK_LEAST)
    return [(max(e - checked, 0), e) for e in range(every, n + 1, every)]


def changepoint_spans(n: int, every: int) -> list[tuple[int, int]]:
    """(start, stop) of the samples the change-point method's signal checks see at each update
    of a stream of ``n`` samples fed from its start: the newest ``BLOCK`` (once it holds them)."""
    return [(e - BLOCK, e) for e in range(every, n + 1, every) if e >= BLOCK]


def chunk_row(drives, spans, limits, drops, ratios: bool) -> str:
    """One method's cell of the --chunks table: its checks of ``drives`` (n, samples) at the
    ``spans`` (`window_spans`, `changepoint_spans`), those flagged, (with ``ratios``) the
    largest short level ratio per stretch, and the ``drops`` (per drive: (start, samples,
    gain)) flagged by a check whose span holds part of the drop."""
    checks = flagged = found = 0
    longest = max((stop - start for start, stop in spans), default=0)  # ("-": no stretch)
    largest = {n: 1.0 for n, _ in SHORT_LEVEL_STRETCHES if n + SHORT_LEVEL_BEFORE + 2 <= longest}
    anchored = limits.noise_sd_mps2 is None  # (as `signal_fault` exempts flights)
    for accel, faults in zip(drives, drops, strict=True):
        for start, stop in spans:
            checks += 1
            flagged += bool(signal_fault(accel[start:stop], limits))
            for n in largest if ratios else ():
                ratio = short_level_drop(accel[start:stop], n, anchored=anchored)[0]
                largest[n] = max(largest[n], ratio)
        for first, length, gain in faults:
            a = accel.copy()
            a[first : first + length] *= gain
            found += any(
                signal_fault(a[start:stop], limits)
                for start, stop in spans
                if start < first + length and stop > first
            )
    tried = sum(len(faults) for faults in drops)
    cell = f"{checks:,} checks, {flagged} flagged, drops found {100 * found / tried:.1f}%"
    if ratios:
        found_ratios = (
            f"{largest[n]:.4g}" if n in largest else "-" for n, _ in SHORT_LEVEL_STRETCHES
        )
        cell += ", short level ratios " + " / ".join(found_ratios)
    return cell


def chunk_table(drives, limits, rng) -> None:
    """Print the --chunks table of the drives' accelerations (n, samples)."""
    n = drives.shape[1]
    drops = [
        [
            (
                int(rng.integers(min(BLOCK, n - DROP_SAMPLES[1] - 1), n - DROP_SAMPLES[1])),
                int(rng.integers(DROP_SAMPLES[0], DROP_SAMPLES[1] + 1)),
                float(rng.uniform(*DROP_GAIN)),
            )
            for _ in range(DROPS)
        ]
        for _ in range(drives.shape[0])
    ]
    print(f"   {DROPS} drops per drive (gain {DROP_GAIN[0]:g}-{DROP_GAIN[1]:g} for "
          f"{DROP_SAMPLES[0]}-{DROP_SAMPLES[1]} samples); short level ratios of "
          + " / ".join(f"{s} samples (limit {m:g})" for s, m in SHORT_LEVEL_STRETCHES))  # fmt: skip
    for every in EVERY:
        window = chunk_row(drives, window_spans(n, every), limits, drops, True)
        print(f"   update_every {every}: window methods: {window}")
        if every >= BLOCK / MAX_PHASES:  # (the change-point method's least update_every)
            blocks = chunk_row(drives, changepoint_spans(n, every), limits, drops, False)
            print(f"   update_every {every}: change-point: {blocks}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=7, help="campaign seed")
    parser.add_argument("--keep-s", type=float, default=120.0, help="seconds kept per drive")
    parser.add_argument("--workers", type=int, default=2,
                        help="worker processes of the campaign (default 2)")  # fmt: skip
    parser.add_argument("--cases", default="AB", choices=["A", "B", "AB"],
                        help="A: without sensor noise, B: with N(0, 1) noise")  # fmt: skip
    parser.add_argument("--drives", type=int, default=198, help="drives of the design")
    parser.add_argument("--chunks", action="store_true",
                        help="print only what each method's checks see at update_every "
                             f"{', '.join(map(str, EVERY))}")  # fmt: skip
    args = parser.parse_args()
    if args.seed < 0:
        parser.error(f"--seed must be >= 0, got {args.seed}")
    if args.seed >= MAX_SEED:
        parser.error(f"--seed must be < 2**128 (the seeds' range), got {args.seed}")
    if not BLOCK / 120.0 <= args.keep_s < np.inf:  # NaN fails too
        parser.error(
            f"--keep-s must be >= {BLOCK / 120.0:.2f} s (one block) and finite, got {args.keep_s}"
        )
    if args.workers < 1:
        parser.error(f"--workers must be >= 1, got {args.workers}")
    if args.drives < 1:
        parser.error(f"--drives must be >= 1, got {args.drives}")
    try:  # the campaign's design and traces (its own check, made before the design is built)
        vehicle.checks.memory(
            (64.0 + 16.0 * round(args.keep_s * 120.0)) * args.drives,
            f"--drives {args.drives} and --keep-s {args.keep_s:g}: a campaign's traces",
        )  # fmt: skip
    except vehicle.VehicleError as exc:
        parser.error(str(exc))
    tic = time.perf_counter()
    limit = SensorLimits().lattice_p
    rng = np.random.default_rng(args.seed)
    print(
        f"campaign seed {args.seed}, {args.drives} drives of {args.keep_s:g} s, lattice_p {limit:g}"
    )
    design = lhs_design(args.drives, seed=args.seed)
    for case, noise in (("A", 0.0), ("B", 1.0)):
        if case not in args.cases:
            continue
        with ProcessPoolExecutor(args.workers) as pool:
            camp = vehicle.run_campaign(
                design, seed=args.seed, keep_s=args.keep_s, noise_std=noise, executor=pool,
                progress=False,
            )  # fmt: skip
        assert camp.accel_measured is not None, "keep_s > 0 keeps the accelerations"
        acc = camp.accel_measured[camp.ok]
        per_drive = acc.shape[1] // BLOCK
        blocks = acc[:, : per_drive * BLOCK].reshape(-1, BLOCK)
        limits = SensorLimits(noise_sd_mps2=noise or None)
        if args.chunks:
            print(f"{case} (noise sd {noise:g}): {acc.shape[0]} clean drives of "
                  f"{acc.shape[1]:,} samples")  # fmt: skip
            chunk_table(acc, limits, rng)
            continue
        flagged = [b for b in blocks if signal_fault(b, limits)]
        flight = flight_reading(limits)  # the check's exemption: none for a noisy sensor
        floats = min(most_lattice_like(b, flight)[0] for b in blocks)
        print(f"{case} (noise sd {noise:g}): {blocks.shape[0]:,} clean blocks of {BLOCK}, "
              f"flagged by any check: {len(flagged)}; most lattice-like: {floats:.2g}")  # fmt: skip
        for r in RESOLUTIONS:
            rounded = np.round(blocks[::4] / r) * r
            worst = min(most_lattice_like(b, flight)[0] for b in rounded)
            print(f"   rounded to {r:g} m/s^2 ({rounded.shape[0]:,} blocks): most lattice-like "
                  f"{worst:.2g}")  # fmt: skip
        for step in STEPS:
            found = []
            for length in LENGTHS:
                hits, tried = lattice_hits(blocks, step, length, rng, flight, limit)
                found.append(f"{length} samples {100 * hits / tried:5.1f}%")
            fewer = f" ({tried:,} blocks each)" if tried < PICKS else ""
            print(f"   rounded to {step:g} m/s^2 steps for " + ", ".join(found) + fewer)
        anchored = limits.noise_sd_mps2 is None  # (as `signal_fault` exempts flights)
        ratios = [
            f"{n} samples {max(short_level_drop(b, n, anchored=anchored)[0] for b in blocks):.4g} "
            f"(limit {most:g})"
            for n, most in SHORT_LEVEL_STRETCHES
        ]
        print("   short level check, largest ratio: " + ", ".join(ratios))
        for length in GAIN_LENGTHS:
            found = []
            for gain in GAINS:
                hits, tried = scale_hits(blocks, gain, length, rng, limits)
                found.append(f"{gain:g}: {100 * hits / tried:5.1f}%")
            fewer = f" ({tried:,} blocks each)" if tried < PICKS else ""
            print(f"   {length} samples scaled by " + ", ".join(found) + fewer)
    load = " ".join(f"{x:.2f}" for x in load_average())
    print(f"{time.perf_counter() - tic:.0f} s; load average {load}")


if __name__ == "__main__":
    main()
