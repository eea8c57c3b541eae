"""Online calibration speed on the 198-run road case (emulator fixed at SEPIA's values).

Prints, single-threaded (BLAS limited to one thread; --pin also pins the process to one CPU):
- ``Calibrator.update`` latency over ``--updates`` (>= 1,000, for a p99) updates with varying
  (v, f), after 50 warm-up calls: median, p90, p99, max,
  also with the posterior's mean and P(GD > 350) read (what a control loop does);
- ``Calibrator.log_likelihood_grid`` latency (the sequential-filter hook);
- ``Calibrator.update`` latency on a categorical and a continuous parameter (the trading-off
  case of the tests: y = sin(3x) + k + 0.5 kind, three kinds; each level's axis refined);
- ``gpmsa.calibrate`` with the paper's settings (tuning 50 x 20, 5,000 draws, 1,000 burned), the
  fast sampler over ``--runs`` calls after the process's first (printed alone: it imports
  ArviZ for the convergence check, ~0.5 s) and the generic numpy backend; the same on a
  two-parameter case with three
  observations (the fast sampler's dense path: no Chebyshev series), the two engines' runs
  alternated, with their ratio of median wall-clock and of median CPU times;
- memory: the Calibrator's cached arrays and the peak Python allocation of preparing and of an
  update (tracemalloc).
SEPIA's figures are from tests/data/reference_posteriors.json (same case, this machine class).
The load average is printed before and after: the machine is shared.

Usage: python benchmarks/calibrate_speed.py [--updates 2000] [--runs 10] [--pin] (~10 s at the
defaults; README.md's ``gpmsa.calibrate`` figures: ``--runs 15``).
"""

from __future__ import annotations

import argparse
import json
import os
import time
import tracemalloc
from pathlib import Path

import numpy as np
from _host import load_average

import gpmsa
from gpmsa.fitting.emulator import Emulator

DATA = Path(__file__).resolve().parent.parent / "tests" / "data"
MIN_UPDATES = 1000
WARM_UP = 50


def road_emulator() -> tuple[Emulator, dict]:
    case = dict(np.load(DATA / "case.npz", allow_pickle=False))
    ref = json.loads((DATA / "reference_posteriors.json").read_text(encoding="utf-8"))
    sim = gpmsa.SimData(
        x=case["v"][:, None], t=case["GD"][:, None], y=case["f"][:, None],
        x_names=["v"], t_names=["GD"], y_names=["f"],
    )  # fmt: skip
    params = ref["sepia_calibration_only"]["fixed_emulator_params_unit_scale"]
    return Emulator.from_params(sim, params), ref


def two_parameter_case() -> tuple[Emulator, np.ndarray, np.ndarray]:
    """A scalar output of one x and two calibration parameters (60 runs, emulator parameters
    set), observed at 3 x values: the fast sampler's dense path (no Chebyshev series)."""
    rng = np.random.default_rng(7)
    x, t = rng.uniform(0, 1, 60), rng.uniform(0, 1, (60, 2))
    y = np.sin(2.0 * x + 1.5 * t[:, 0]) + 0.8 * t[:, 1] * x
    sim = gpmsa.SimData(x=x[:, None], t=t, y=y[:, None], x_names=["x"], t_names=["a", "b"])
    params = {"betaU": [[1.0], [1.5], [0.8]], "lamUz": [1.0], "lamWs": [5000.0],
              "lamWOs": [5000.0]}  # fmt: skip
    x_obs = np.array([[0.2], [0.5], [0.8]])
    return Emulator.from_params(sim, params), x_obs, np.sin(2 * x_obs + 0.6) + 0.48 * x_obs


def level_case() -> tuple[Emulator, np.ndarray, np.ndarray]:
    """The trading-off case (tests/gpmsa/_level_cases.py: 60 runs, y = sin(3x) + k + 0.5 kind,
    kind in {0, 1, 2}, categorical), its emulator parameters set to its 600-sweep fit's point
    estimate, observed at 6 x values at k = 0.4, kind 1 (kind 0 at k = 0.9 fits alike)."""
    rng = np.random.default_rng(2)
    x = rng.random((60, 1))
    t = np.column_stack([rng.random(60), np.arange(60) % 3])
    sim = gpmsa.SimData(x, t, np.sin(3 * x[:, 0]) + t[:, 0] + 0.5 * t[:, 1], x_names=["s"],
                        t_names=["k", "kind"], t_categorical=["kind"])  # fmt: skip
    params = {"betaU": [[0.854], [0.0655], [0.334]], "lamUz": [0.336], "lamWs": [3919.0],
              "lamWOs": [3171.0]}  # fmt: skip
    x_obs = np.linspace(0.1, 0.9, 6)[:, None]
    y_obs = np.sin(3 * x_obs[:, 0]) + 0.9 + rng.normal(0, 0.05, 6)
    return Emulator.from_params(sim, params), x_obs, y_obs


def observations(emu: Emulator, n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """n windows: v uniform on the domain, f from the road case's formula with 5% noise."""
    rng = np.random.default_rng(seed)
    lo, hi = emu.domain["v"]
    v = rng.uniform(lo, hi, n)
    gd = rng.uniform(*emu.domain["GD"], n)
    f = 0.02 * gd * v**1.6 * (1 + 0.05 * rng.standard_normal(n))
    return v, f


def latencies(fn, v: np.ndarray, f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Wall-clock and thread CPU seconds per call of fn([[v]], [[f]]) for each (v, f) pair after
    the first WARM_UP (warm-up calls, not timed). On a loaded machine the wall clock includes
    time the process waited for a CPU (scheduler ticks of ~4 ms); the CPU time does not."""
    for i in range(WARM_UP):
        fn([[v[i]]], [[f[i]]])
    v, f = v[WARM_UP:], f[WARM_UP:]
    wall, cpu = np.empty(v.size), np.empty(v.size)
    for i in range(v.size):
        t0, c0 = time.perf_counter(), time.thread_time()
        fn([[v[i]]], [[f[i]]])
        wall[i], cpu[i] = time.perf_counter() - t0, time.thread_time() - c0
    return wall, cpu


def calibrate_times(call, n: int) -> tuple[float, list[float]]:
    """Wall seconds of ``call(seed)``: the first call (seed ``n``: a process's first
    ``gpmsa.calibrate`` imports ArviZ, ~0.5 s), then ``n`` calls, seeds 0 to n - 1."""
    t0 = time.perf_counter()
    call(n)
    first = time.perf_counter() - t0
    times = []
    for seed in range(n):
        t0 = time.perf_counter()
        call(seed)
        times.append(time.perf_counter() - t0)
    return first, times


def row(name: str, ms: np.ndarray, sepia: str = "") -> str:
    q = np.percentile(ms, [50, 90, 99])
    return (f"{name:50s} {q[0]:9.3f} {q[1]:9.3f} {q[2]:9.3f} {ms.max():9.3f} {ms.size:7d}"
            f"  {sepia}")  # fmt: skip


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--updates", type=int, default=2000,
                        help=f"timed updates a row, >= {MIN_UPDATES} (default 2000)")  # fmt: skip
    parser.add_argument("--runs", type=int, default=10,
                        help="timed gpmsa.calibrate calls with the fast sampler; a fifth of them "
                        "(at least 2) with the numpy backend (default 10)")  # fmt: skip
    parser.add_argument("--pin", action="store_true", help="pin the process to one CPU")
    args = parser.parse_args()
    if args.updates < MIN_UPDATES:
        parser.error(f"--updates must be >= {MIN_UPDATES} (for a p99), got {args.updates}")
    if args.runs < 1:
        parser.error(f"--runs must be >= 1, got {args.runs}")
    if args.pin and hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
    emu, ref = road_emulator()
    sepia = ref["timings_this_machine_1_blas_thread_s"][
        "sepia_calibration_only_tuning_plus_5000_draws"
    ]
    t0 = time.perf_counter()
    cal = gpmsa.Calibrator(emu, seed=0)
    prep_s = time.perf_counter() - t0
    v, f = observations(emu, args.updates + WARM_UP)

    def update_and_read(x, y):
        post = cal.update(x, y)
        return post.mean("GD"), post.prob_above("GD", 350.0)

    print(f"road case: m = {emu.m} runs, grid of {cal.theta_grid.size} GD nodes; "
          f"Calibrator prepared in {1e3 * prep_s:.1f} ms; {load()}")  # fmt: skip
    print(f"{'latency, ms':50s} {'median':>9s} {'p90':>9s} {'p99':>9s} {'max':>9s} {'calls':>7s}"
          "  SEPIA")  # fmt: skip
    for name, fn in (
        ("Calibrator.update", cal.update),
        ("Calibrator.update + mean + P(GD > 350)", update_and_read),
        ("Calibrator.log_likelihood_grid", cal.log_likelihood_grid),
    ):
        wall, cpu = latencies(fn, v, f)
        print(row(name + " (wall)", 1e3 * wall, f"~{1e3 * sepia:.0f}"))
        print(row(name + " (CPU)", 1e3 * cpu))
    emu_l, x_l, y_l = level_case()
    cal_l = gpmsa.Calibrator(emu_l, seed=0)
    for _ in range(5):
        post = cal_l.update(x_l, y_l)
    wall, cpu = np.empty(50), np.empty(50)
    for i in range(wall.size):
        t0, c0 = time.perf_counter(), time.thread_time()
        cal_l.update(x_l, y_l)
        wall[i], cpu[i] = time.perf_counter() - t0, time.thread_time() - c0
    name = f"Calibrator.update, categorical ({post.info['n_nodes']} nodes)"
    print(row(name + " (wall)", 1e3 * wall))
    print(row(name + " (CPU)", 1e3 * cpu))
    x_obs, y_obs = [[float(ref_v)] for ref_v in [1.25]], [[12.09696044]]
    first_s, runs = calibrate_times(lambda seed: gpmsa.calibrate(emu, x_obs, y_obs, seed=seed),
                                    args.runs)  # fmt: skip
    first = "calibrate, process's first call (imports ArviZ)"
    print(f"{first:50s} {1e3 * first_s:9.3f}")
    print(
        row("calibrate, paper settings (fast sampler)", 1e3 * np.array(runs), f"{1e3 * sepia:.0f}")
    )
    runs = []
    for seed in range(max(2, args.runs // 5)):
        t0 = time.perf_counter()
        gpmsa.calibrate(emu, x_obs, y_obs, seed=seed, fast=False)
        runs.append(time.perf_counter() - t0)
    print(
        row("calibrate, paper settings (numpy backend)", 1e3 * np.array(runs), f"{1e3 * sepia:.0f}")
    )
    emu2, x2, y2 = two_parameter_case()
    walls: dict[bool, list[float]] = {True: [], False: []}
    cpus: dict[bool, list[float]] = {True: [], False: []}
    for seed in range(max(2, args.runs // 5)):
        for fast in (True, False):  # alternated: a change in the machine's load hits both
            t0, c0 = time.perf_counter(), time.process_time()
            gpmsa.calibrate(emu2, x2, y2, seed=seed, fast=fast)
            walls[fast].append(time.perf_counter() - t0)
            cpus[fast].append(time.process_time() - c0)
    for fast in (True, False):
        engine = "fast sampler" if fast else "numpy backend"
        print(row(f"calibrate, 2 parameters, 3 obs ({engine})", 1e3 * np.array(walls[fast])))
    ratio = np.median(walls[True]) / np.median(walls[False])
    ratio_cpu = np.median(cpus[True]) / np.median(cpus[False])
    print(f"  fast / numpy backend, 2 parameters: {ratio:.2f} (wall), {ratio_cpu:.2f} (CPU)")
    predictors = [*cal._predictors, *(cal._refined[1] if cal._refined else [])]
    cached = sum(a.nbytes for p in predictors for a in [p.rt_alpha, *(p.H or [])])
    cached += sum(g.chol.nbytes + g.alpha.nbytes for g in cal._gps)
    tracemalloc.start()
    gpmsa.Calibrator(emu)
    prep_peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.reset_peak()
    cal.update([[1.25]], [[12.1]]).mean("GD")
    upd_peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    print(
        f"memory: Calibrator cached arrays {cached / 2**20:.2f} MiB; peak allocation while "
        f"preparing {prep_peak / 2**20:.2f} MiB, per update {upd_peak / 2**20:.3f} MiB"
    )
    print(load())


def load() -> str:
    """The load average with the cores, printed with the timings (the machine is shared)."""
    averages = "{:.2f} {:.2f} {:.2f}".format(*load_average())
    return f"load average {averages} on {os.cpu_count()} cores"


if __name__ == "__main__":
    main()
