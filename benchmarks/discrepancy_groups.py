"""One discrepancy precision or one per group (GPM/SA's lamVzGroup): theta's accuracy.

A functional output on 15 points, y(x, t) = sin(3 s (1 + x)) + t (1 + s) over the grid s in
[0, 1]; 6 experiments at t = 0.4 with a discrepancy and noise sd 0.02. The discrepancy basis
D = [1, s, s^2] (normalised) is split into two groups: the constant (group 0) and the slope and
curvature (group 1). Two truths:

- "offset": the discrepancy is a constant offset per experiment (0.3 sin(2x)), nothing in
  slope or curvature;
- "shape": the discrepancy is a slope (0.3 s sin(2x)).

For each seed: the emulator is fitted to 40 runs (a Latin hypercube; n_iter 1,500), then
``gpmsa.calibrate`` (numpy, 3,000 samples, 1,000 burned) with one precision group, with the
two groups, and with the two groups and a prior per group (GPM/SA's per-group lamVz priors:
group 1's believes the slope and curvature small, right for the "offset" truth and wrong for
the "shape" one). Prints per truth and grouping: theta's mean error and RMSE of the posterior mean
against 0.4, its mean posterior sd, the coverage of 0.4 by the central 90% interval, and the
median posterior lamVz per group (over seeds).

Usage: python benchmarks/discrepancy_groups.py [--seeds 20] [--out FILE.json] (3-6 min for 20
seeds on the 2-core machine).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np
from scipy.stats import qmc

import gpmsa
from roadgen.checks import home_path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "examples"))
from _cli import path_option, write_text  # noqa: E402
from _host import load_average

TRUE_T = 0.4
GRID = np.linspace(0.0, 1.0, 15)
BASIS = np.column_stack([np.ones(GRID.size), GRID, GRID**2])
SMALL_SHAPE = [gpmsa.GammaPrior(1.0, 1e-3), gpmsa.GammaPrior(10.0, 1e-3)]
"""Per-group lamVz priors: group 0 GPM/SA's vague default; group 1 (slope and curvature)
believed small: lamVz mean 1e4 (weights' sd ~0.01), relative sd 0.32."""
GROUPINGS = {
    "one group": (None, None),
    "groups [0, 1, 1]": ([0, 1, 1], None),
    "+ small-shape prior": ([0, 1, 1], SMALL_SHAPE),
}


def simulator(x: np.ndarray, t: np.ndarray) -> np.ndarray:
    """(n, 15) outputs at inputs x (n, 1), t (n, 1)."""
    return np.sin(3.0 * GRID[None] * (1.0 + x)) + t * (1.0 + GRID[None])


def case(seed: int, truth: str) -> tuple[gpmsa.SimData, gpmsa.ObsData]:
    """The runs and the field data of one seed."""
    rng = np.random.default_rng(seed)
    x, t = np.hsplit(qmc.LatinHypercube(d=2, rng=rng).random(40), 2)
    data = gpmsa.SimData(x=x, t=t, y=simulator(x, t), x_names=["x"], t_names=["t"], index=GRID)
    xo = np.linspace(0.1, 0.9, 6)[:, None]
    shape = np.ones(GRID.size) if truth == "offset" else GRID
    delta = 0.3 * np.sin(2.0 * xo) * shape[None]
    yo = simulator(xo, np.full_like(xo, TRUE_T)) + delta + 0.02 * rng.standard_normal(delta.shape)
    return data, gpmsa.ObsData(x=xo, y=yo)


def run(seeds: int) -> dict:
    """Per truth and grouping, the per-seed posterior summaries."""
    out: dict[str, dict[str, list[dict]]] = {
        truth: {name: [] for name in GROUPINGS} for truth in ("offset", "shape")
    }
    for truth, by_grouping in out.items():
        for seed in range(seeds):
            data, obs = case(seed, truth)
            emu = gpmsa.fit(data, n_iter=1500, seed=seed)
            for name, (groups, lam_vz) in GROUPINGS.items():
                post = gpmsa.calibrate(
                    emu if lam_vz is None else emu.with_calibration_priors(lamVz=lam_vz), obs,
                    discrepancy=BASIS, discrepancy_groups=groups, n_samples=3000, n_burn=1000,
                    seed=seed,
                )  # fmt: skip
                t = post.samples["t"]
                lo, hi = np.quantile(t, [0.05, 0.95])
                lam = [k for k in post.names if k.startswith("lamVz")]
                by_grouping[name].append({
                    "mean": float(t.mean()), "sd": float(t.std()),
                    "covered": bool(lo <= TRUE_T <= hi),
                    "lamVz": [float(np.median(post.samples[k])) for k in lam],
                })  # fmt: skip
    return out


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=20,
                        help="data sets (seeds 0 to N - 1) a truth (default 20)")  # fmt: skip
    parser.add_argument("--out", type=path_option, default=None, help="JSON file of the results")
    args = parser.parse_args(argv)
    if args.seeds < 1:
        parser.error(f"--seeds must be >= 1, got {args.seeds}")
    out = None if args.out is None else home_path(args.out)
    if out is not None and out.is_dir():  # refused before the minutes of work, not after
        parser.error(f"--out {args.out!r}: a folder, not a file")
    if out is not None and not out.parent.is_dir():
        parser.error(f"--out {args.out!r}: its folder does not exist")
    warnings.simplefilter("ignore")  # small fits: convergence and outside-emulator warnings
    load0, t0 = load_average()[0], time.perf_counter()
    res = run(args.seeds)
    print(f"{args.seeds} seeds, true t = {TRUE_T}; load {load0:.2f} -> {load_average()[0]:.2f}, "
          f"{time.perf_counter() - t0:.0f} s")  # fmt: skip
    print(f"{'truth':8s} {'grouping':18s} {'bias':>8s} {'RMSE':>8s} {'mean sd':>8s} "
          f"{'90% cov':>8s}  median lamVz per group (over seeds)")  # fmt: skip
    for truth, by_grouping in res.items():
        for name, rows in by_grouping.items():
            err = np.array([r["mean"] for r in rows]) - TRUE_T
            lam = np.median(np.array([r["lamVz"] for r in rows]), axis=0)
            print(f"{truth:8s} {name:18s} {err.mean():8.4f} {np.sqrt(np.mean(err**2)):8.4f} "
                  f"{np.mean([r['sd'] for r in rows]):8.4f} "
                  f"{np.mean([r['covered'] for r in rows]):8.0%}  "
                  f"{', '.join(f'{v:.3g}' for v in lam)}")  # fmt: skip
    if out is not None:
        write_text(out, json.dumps(res, indent=1))  # in one step: the previous file or the new


if __name__ == "__main__":
    main()
