"""Vehicle speed: real-time factor per model and the wall time of the 198-run campaign.

Real-time factor = simulated seconds per wall-clock second, and per CPU second of this process
(less sensitive to other load), medians of ``--repeats`` runs, model build included. Prints the
machine's load average, as timings on a shared machine vary.

    python benchmarks/vehicle_speed.py [--repeats 3] [--runs 198] [--skip-campaign]

About 8 s at the defaults (the campaign 4-7 s); these are the settings of the figures in
README.md and docs/vehicle-models.md.
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np
from _host import load_average

import roadgen
import vehicle


def _median_rtf(fn, repeats: int) -> tuple[float, float, float]:
    """Median wall-clock and CPU-time real-time factors, and the median wall time (s)."""
    rtfs, cpu_rtfs, walls = [], [], []
    for _ in range(repeats):
        tic, cpu = time.perf_counter(), time.process_time()
        simulated = fn()
        wall = time.perf_counter() - tic
        rtfs.append(simulated / wall)
        cpu_rtfs.append(simulated / (time.process_time() - cpu))
        walls.append(wall)
    return float(np.median(rtfs)), float(np.median(cpu_rtfs)), float(np.median(walls))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3,
                        help="runs of each model, medians printed (default 3)")  # fmt: skip
    parser.add_argument("--runs", type=int, default=198,
                        help="runs of the timed campaign (default 198)")  # fmt: skip
    parser.add_argument("--skip-campaign", action="store_true", help="time the models only")
    args = parser.parse_args()
    if args.repeats < 1:
        parser.error(f"--repeats must be >= 1, got {args.repeats}")
    if args.runs < 1:
        parser.error(f"--runs must be >= 1, got {args.runs}")

    print(f"cores: {os.cpu_count()}, load average at start: {load()}")
    road = roadgen.iso8608_profile(151.0, gd=400, seed=0, lead_in_m=1.0)
    track = roadgen.track([(50, 300), (50, 500), (50, 300)], seed=0)

    def jackal() -> float:
        return vehicle.simulate(vehicle.Jackal(), road, 1.0, end_m=150.262).t[-1]

    def halfcar() -> float:
        return vehicle.simulate(vehicle.HalfCar(), road, 15.0).t[-1]

    def closed_loop() -> float:
        sim = vehicle.Simulation(vehicle.Jackal(), track, noise_std=1.0, seed=0)
        rng = np.random.default_rng(0)
        while not sim.finished:
            sim.advance(100 / 120, float(rng.choice([1.0, 2.0])))
        return sim.time

    for name, fn in (
        ("Jackal, simulate, 150 m at 1 m/s", jackal),
        ("HalfCar, simulate, 150 m at 15 m/s", halfcar),
        ("Jackal, Simulation.advance(100 samples), 150 m track, 1-2 m/s", closed_loop),
    ):
        rtf, cpu_rtf, wall = _median_rtf(fn, args.repeats)
        print(
            f"{name}: real-time factor {rtf:.0f} wall-clock, {cpu_rtf:.0f} per CPU second "
            f"(median wall {wall:.2f} s)"
        )

    if not args.skip_campaign:
        design = vehicle.lhs_design(args.runs, seed=0)
        tic = time.perf_counter()
        camp = vehicle.run_campaign(design, seed=0, progress=False)
        wall = time.perf_counter() - tic
        print(
            f"campaign: {args.runs} runs (Jackal, 21 m roads, process pool of {os.cpu_count()}) "
            f"in {wall:.1f} s wall, {int(camp.ok.sum())} ok; load average after: {load()}"
        )
    else:
        print(f"load average after: {load()}")


def load() -> str:
    """The load average (1, 5, 15 min), printed with the timings: the machine is shared."""
    return "{:.2f} {:.2f} {:.2f}".format(*load_average())


if __name__ == "__main__":
    main()
