"""Time roadgen's hot paths on the paper's sizes (150 m at 6 mm, 25,001 points); prints medians.

python benchmarks/roadgen_speed.py [--repeats 21]

Prints the load average before and after: the machine is shared.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
from collections.abc import Callable

from _host import load_average

import roadgen


def median_seconds(func: Callable[[], object], repeats: int) -> float:
    """Median wall time of ``repeats`` calls of ``func``, s, after one call not timed (a first
    call's set-up: estimate_gd's fit took 579 ms cold against 4 ms warm)."""
    func()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        func()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=21,
                        help="timed calls of each, median printed (default 21)")  # fmt: skip
    args = parser.parse_args(argv)
    if args.repeats < 1:
        parser.error(f"--repeats must be >= 1, got {args.repeats}")
    segments = [(50, 300), (50, 500), (50, 300)]
    road = roadgen.iso8608_profile(150.0, 450.0, seed=0)
    trk = roadgen.track(segments, seed=0)
    cases = {
        "iso8608_profile 150 m, 6 mm": lambda: roadgen.iso8608_profile(150.0, 450.0, seed=0),
        "track (paper's 3 segments)": lambda: roadgen.track(segments, seed=0),
        "wheel_envelope r=0.098 m, 150 m": lambda: roadgen.wheel_envelope(trk, 0.098),
        "wheel_envelope r=0.35 m, 150 m": lambda: roadgen.wheel_envelope(trk, 0.35),
        "estimate_gd fit, 150 m": lambda: roadgen.estimate_gd(road),
        "estimate_gd welch, 150 m": lambda: roadgen.estimate_gd(road, method="welch"),
        "height_at 10,000 positions": lambda: road.height_at(road.x[::2][:10_000]),
    }
    print(f"median of {args.repeats} runs; {load()}")
    for name, func in cases.items():
        print(f"{name:34s} {1e3 * median_seconds(func, args.repeats):8.2f} ms")
    print(load())


def load() -> str:
    """The load average with the cores, printed with the timings (the machine is shared)."""
    averages = "{:.2f} {:.2f} {:.2f}".format(*load_average())
    return f"load average {averages} on {os.cpu_count()} cores"


if __name__ == "__main__":
    main()
