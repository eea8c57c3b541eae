"""Speed of `control.replay_bag` against real time (issue 17: >= 200x).

    python benchmarks/replay_speed.py [--repeats 3] [--case A]

Drives the paper's 150 m track in the closed loop (one run per track seed), writes each run as a
ROS 2 bag of standard messages (MCAP and sqlite3 storage, IMU and odometry at 120 Hz) and, from
a constant-speed drive with the accelerometer at 400 Hz, a bag that the replay resamples. Then
times the replay of each: recorded seconds per wall-clock second of reading, resampling and the
BCR (the ratio the issue asks for), and of the whole call with the CSV and the output bag
written. The emulator is loaded and its likelihood prepared once, outside the timing (the
command does that once per recording). Prints the load average: the machine is shared.
"""

from __future__ import annotations

import argparse
import os
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np
from _host import load_average

import control
import roadgen
import vehicle
from control.robot import replay_bag, write_run_bag, write_sensor_bag

SEGMENTS = [(50.0, 300.0), (50.0, 500.0), (50.0, 300.0)]


def drive_400hz(track, noise: float, seed: int) -> list[np.ndarray]:
    """(t, position, speed, accel) of a 1.5 m/s drive with the accelerometer at 400 Hz."""
    sim = vehicle.Simulation(vehicle.Jackal(), track, rate_hz=400.0, noise_std=noise, seed=seed)
    parts = []
    while not sim.finished:
        s = sim.advance(1.0, 1.5)
        if len(s) == 0:
            break
        parts.append((s.t, s.position, s.speed, s.accel_front))
    return [np.concatenate(x) for x in zip(*parts, strict=True)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="runs (track seeds 1..N)")
    parser.add_argument("--case", default="A", choices=["A", "B"], help="test case")
    args = parser.parse_args()
    if args.repeats < 1:
        parser.error(f"--repeats must be >= 1, got {args.repeats}")
    emu = control.shipped_emulator(args.case)
    assert emu.metadata is not None, "a shipped emulator records how it was trained"
    noise = float(emu.metadata["noise_std"])
    likelihood = control.ObservationModel(emu)
    work = Path(tempfile.mkdtemp(prefix="replay_speed_"))
    try:
        bags: dict[str, list[Path]] = {"mcap 120 Hz": [], "sqlite3 120 Hz": [], "mcap 400 Hz": []}
        for k in range(1, args.repeats + 1):
            track = roadgen.track(SEGMENTS, seed=k)
            run = control.run_closed_loop(
                track, emu, noise_std=noise, seed=k, likelihood=likelihood
            )
            bags["mcap 120 Hz"].append(write_run_bag(run, work / f"mcap{k}", storage="mcap"))
            bags["sqlite3 120 Hz"].append(
                write_run_bag(run, work / f"sqlite{k}", storage="sqlite3")
            )
            t, pos, spd, acc = drive_400hz(track, noise, k)
            odom = slice(None, None, 8)  # odometry at 50 Hz
            bags["mcap 400 Hz"].append(
                write_sensor_bag(work / f"imu400_{k}", t, acc, t[odom], pos[odom], spd[odom])
            )
        print(f"{args.repeats} drives of the paper's 150 m track, test case {args.case}")
        print(f"{'bag':>16} {'recorded s':>10} {'replay s':>9} {'ratio':>7} "
              f"{'with outputs':>12}  (read / resample / BCR s)")  # fmt: skip
        for name, paths in bags.items():
            for path in paths:
                out = work / f"out_{path.name}"
                tic = time.perf_counter()
                r = replay_bag(
                    path, emu, likelihood=likelihood, csv=work / f"{path.name}.csv", out_bag=out
                )
                whole = time.perf_counter() - tic
                print(f"{name:>16} {r.duration_s:10.1f} {r.wall_s:9.3f} "
                      f"{r.real_time_factor:6.0f}x {r.duration_s / whole:11.0f}x  "
                      f"({r.read_s:.3f} / {r.condition_s:.3f} / {r.bcr_s:.3f})")  # fmt: skip
        print("target: >= 200x real time (ratio: read, resample and BCR; 'with outputs': the "
              "whole call, CSV and output bag written)")  # fmt: skip
        print("load average (1, 5, 15 min): {:.2f} {:.2f} {:.2f}".format(*load_average())
              + f" on {os.cpu_count()} cores")  # fmt: skip
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
