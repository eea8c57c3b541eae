"""Effective samples per second of each gpmsa backend on the road case (fit and calibrate).

ESS: arviz bulk ESS, the minimum over every sampled scalar parameter, of the draws kept after
burn-in (n_iter // 5 per chain, as ``gpmsa.fit``); per second of wall time of the whole run
(tuning or warm-up included). Fit: the simulation-only emulator (198 runs, scalar output;
betaU, lamUz, lamWs, lamWOs sampled). Calibrate: ``gpmsa.calibrate`` at the SEPIA full-joint
posterior means (theta and lamOs sampled). Prints one line per configuration, medians over
``--repeats`` runs, and ``vs numpy``: the ESS/s over that of the task's first row in this run
(numpy, one chain; for calibrate its fast sampler, ``gpmsa.calibrate``'s default), with the load
average before and after. R-hat needs two chains: a one-chain row prints "-". A short
calibration runs first, untimed: a process's first ``gpmsa.calibrate`` imports ArviZ for its
convergence check (~0.5 s), which would otherwise fall on the baseline's first repeat.
``--only TASK:BACKEND`` runs that pair and the task's baseline row (numpy, one chain).

Usage: python benchmarks/backends.py [--repeats 3] [--quick] [--only fit:pyro]. The pyro fit
(4 chains x 1,500 draws, one after another) takes ~10 min, the pyro calibrate (4 x 1,000) ~80 s
a repeat; ``--quick --only calibrate:numpy`` a few seconds. README.md's pyro R-hat: ``--only
fit:pyro``.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time
from pathlib import Path

import numpy as np
from _host import load_average

import gpmsa
from gpmsa import backends
from gpmsa.mcmc.diagnostics import ess, rhat
from gpmsa.model.problem import prepare

ROOT = Path(__file__).resolve().parents[1]
CASE = ROOT / "tests" / "data" / "case.npz"
REF = ROOT / "tests" / "data" / "reference_posteriors.json"


def road() -> tuple[gpmsa.SimData, np.ndarray, np.ndarray]:
    """The road case: simulation data, x_obs (1, 1), y_obs (1, 1)."""
    d = np.load(CASE)
    sim = gpmsa.SimData(x=d["v"][:, None], t=d["GD"][:, None], y=d["f"][:, None],
                        x_names=["v"], t_names=["GD"])  # fmt: skip
    return sim, d["v_obs"][:, None], d["f_obs"][:, None]


def ess_rhat(draws: dict[str, np.ndarray], names) -> tuple[float, float]:
    """(min bulk ESS, max R-hat) over every scalar element of ``names`` in draws (chains, n, ...).

    R-hat needs two chains or more (NaN for one chain).
    """
    e, r = [], []
    for name in names:
        d = draws[name]
        flat = d.reshape(d.shape[0], d.shape[1], -1)
        e += [ess(flat[:, :, i]) for i in range(flat.shape[2])]
        if d.shape[0] > 1:
            r += [rhat(flat[:, :, i]) for i in range(flat.shape[2])]
    r = [x for x in r if not np.isnan(x)]  # (NaN: too few draws for a split R-hat)
    return float(np.nanmin(e)), float(max(r)) if r else float("nan")


def rhat_text(r_hat: float) -> str:
    """R-hat for the table, 6 wide: "-" where it is undefined (one chain, too few draws)."""
    return f"{r_hat:6.3f}" if np.isfinite(r_hat) else f"{'-':>6}"


def selected(configs: list[tuple], task: str, only: str | None) -> list[tuple]:
    """The task's configurations to run: all, or with ``--only TASK:BACKEND`` that backend's and
    the first (the baseline of the ``vs numpy`` ratio), each once, in the table's order."""
    if only is None:
        return list(configs)
    return [c for i, c in enumerate(configs) if only == f"{task}:{c[0]}" or (
        i == 0 and only.startswith(f"{task}:"))]  # fmt: skip


def warm_up() -> None:
    """One short, untimed calibration: the process's first ``gpmsa.calibrate`` imports ArviZ
    (~0.5 s), which would otherwise fall on the first timed row."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a short chain's convergence warning
        bench_calibrate("numpy", 100, 1, True, seed=0)


def bench_fit(backend: str, n_iter: int, n_chains: int, options: dict, seed: int) -> tuple:
    """(wall s, min ESS, max R-hat) of one simulation-only fit."""
    sim, _, _ = road()
    problem = prepare(sim).problem
    t0 = time.perf_counter()
    chains = backends.get(backend).sample(
        problem, n_iter=n_iter, n_chains=n_chains, seed=seed, **options
    )
    wall = time.perf_counter() - t0
    burn = n_iter // 5
    kept = {k: v[:, burn:] for k, v in chains.draws.items()}
    return (wall, *ess_rhat(kept, problem.sampled))


def bench_calibrate(backend: str, n_samples: int, n_chains: int, fast: bool, seed: int) -> tuple:
    """(wall s, min ESS, max R-hat over GD and lamOs) of one gpmsa.calibrate."""
    sim, x_obs, y_obs = road()
    ref = json.loads(REF.read_text(encoding="utf-8"))["sepia_calibration_only"][
        "fixed_emulator_params_unit_scale"
    ]
    emu = gpmsa.Emulator.from_params(sim, {k: np.asarray(v) for k, v in ref.items()})
    t0 = time.perf_counter()
    post = gpmsa.calibrate(
        emu, x_obs, y_obs, n_samples=n_samples, n_burn=n_samples // 5, seed=seed,
        backend=backend, n_chains=n_chains, fast=fast,
    )  # fmt: skip
    wall = time.perf_counter() - t0
    assert post.chains is not None, "an MCMC posterior has chains"
    return (wall, *ess_rhat(post.chains, ("GD", "lamOs")))


def main(argv=None) -> None:
    """Run every configuration and print wall time, min ESS and ESS/s (medians)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--repeats", type=int, default=3, help="runs per configuration, medians printed (default 3)"
    )
    ap.add_argument("--quick", action="store_true", help="shorter runs (noisier figures)")
    ap.add_argument(
        "--only",
        metavar="TASK:BACKEND",
        default=None,
        help="run one task/backend pair (and the task's numpy baseline row), e.g. fit:pyro or "
        "calibrate:torch",
    )
    args = ap.parse_args(argv)
    if args.repeats < 1:
        ap.error(f"--repeats must be >= 1, got {args.repeats}")
    pairs = {f"{t}:{b}" for t in ("fit", "calibrate") for b in ("numpy", "torch", "pyro")}
    if args.only is not None and args.only not in pairs:
        ap.error(f"--only must be one of {sorted(pairs)}, got {args.only!r}")
    s = 0.25 if args.quick else 1.0
    fits = [
        ("numpy", 1, int(3000 * s), {}),
        ("torch", 1, int(1500 * s), {}),
        ("torch", 8, int(1000 * s), {}),
        ("torch", 64, int(400 * s), {}),
        ("pyro", 4, int(1500 * s), {"n_warmup": int(500 * s)}),
    ]
    cals = [
        ("numpy", 1, int(5000 * s), True),
        ("numpy", 1, int(5000 * s), False),
        ("torch", 1, int(3000 * s), False),
        ("torch", 8, int(1500 * s), False),
        ("torch", 64, int(500 * s), False),
        ("pyro", 4, int(1000 * s), False),
    ]
    print(f"# {load()} at start; {os.cpu_count()} CPUs; torch threads 1")
    warm_up()
    print(f"{'task':9} {'backend':14} {'chains':>6} {'draws':>6} {'wall s':>8} {'min ESS':>8} "
          f"{'ESS/s':>8} {'R-hat':>6} {'vs numpy':>8}")  # fmt: skip
    for task, configs in (("fit", fits), ("calibrate", cals)):
        baseline = None  # the ESS/s of the task's first row, numpy with one chain
        for backend, chains, n, extra in selected(configs, task, args.only):
            runs = []
            for r in range(args.repeats):
                if task == "fit":
                    runs.append(bench_fit(backend, n, chains, extra, seed=r))
                else:
                    runs.append(bench_calibrate(backend, n, chains, extra, seed=r))
            wall = statistics.median(w for w, _, _ in runs)
            n_eff = statistics.median(e for _, e, _ in runs)
            rate = statistics.median(e / w for w, e, _ in runs)
            r_hat = max(r for _, _, r in runs)
            label = backend + (" (fast)" if task == "calibrate" and extra else "")
            if (backend, chains, n, extra) == configs[0]:
                baseline = rate
            ratio = f"{rate / baseline:7.2f}x" if baseline else f"{'-':>8}"
            print(f"{task:9} {label:14} {chains:6d} {n:6d} {wall:8.2f} {n_eff:8.0f} {rate:8.1f} "
                  f"{rhat_text(r_hat)} {ratio}", flush=True)  # fmt: skip
    print(f"# {load()} at the end")


def load() -> str:
    """The load average (1, 5, 15 min), printed with the figures: the machine is shared."""
    return "load average {:.2f} {:.2f} {:.2f}".format(*load_average())


if __name__ == "__main__":
    main()
