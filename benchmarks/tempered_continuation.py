"""A tempered fit's continuation with its hot copies resumed, against re-tuning them and one fit.

On the symmetric two-mode case of the parallel-tempering tests (t on 11 runs of 10 (t - 0.5)^2,
eight observations at 0.9: modes at t = 0.2 and 0.8, exact P(t > 0.5) = 1/2; ladder (1, 4, 16,
64), every chain started at t = 0.2) each repeat times, one after another:
(a) a tempered fit of N sweeps (``--sweeps``) continued by N more with ``gpmsa.fit(sim, obs,
    init=emu)`` at the source's ladder: the default, which resumes every hot copy where it
    stopped, untuned (no warm-up);
(b) the same fit and continuation with ``tune=True``: the continuation re-tunes its copies
    (``tune_rounds`` x ``tune_levels`` sweeps a copy) before its first draw;
(c) one tempered fit of 2N sweeps (as many draws after its burn-in of 2N // 5).
Prints per variant the median wall time over ``--repeats`` (a and b: the source fit and the
continuation together, and the continuation alone), the ratios a/b and a/c of the medians, the
share of the continued draws (c: its last N sweeps) in the upper mode with its standard error
(from the spread of the chains' shares; exact 1/2), and how many chains' first continued draw
lies in another mode than their last draw before (c: between sweeps N and N + 1), with the load
average before and after (the machine is shared: compare figures of one run only). Every sweep
is kept (``n_keep``), one process (``n_jobs=1``), after an untimed warm-up fit; a and b continue
the same source (same seed).

Usage: python benchmarks/tempered_continuation.py [--repeats 5] [--sweeps 500] [--chains 4]
[--quick]

Run time: ~80 s at the defaults (docs/performance.md's figures), seconds with ``--quick``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time
import warnings

import numpy as np
from _host import load_average

import gpmsa

LADDER = (1.0, 4.0, 16.0, 64.0)
MIN_SWEEPS = 10
"""Fewest sweeps a part (``--sweeps``): the source keeps N - N // 5 of them."""
VARIANTS = ("a", "b", "c")
NAMES = {
    "a": "(a) N + N continued, hot copies resumed",
    "b": "(b) N + N continued, tune=True",
    "c": "(c) one fit of 2N",
}


def two_mode_case() -> tuple[gpmsa.SimData, gpmsa.ObsData]:
    """tests/gpmsa/_tempering_cases.py's case (benchmarks do not import the tests)."""
    t = np.linspace(0.0, 1.0, 11)[:, None]
    sim = gpmsa.SimData(t=t, y=10 * (t - 0.5) ** 2)
    obs = gpmsa.ObsData(y=0.9 + 0.002 * np.array([[1], [-1], [0.5], [-0.5]] * 2))
    return sim, obs


def load() -> str:
    """The load average with the cores, printed with the timings (the machine is shared)."""
    averages = "{:.2f} {:.2f} {:.2f}".format(*load_average())
    return f"load average {averages} on {os.cpu_count()} cores"


def upper(emu: gpmsa.Emulator, n_chains: int) -> np.ndarray:
    """(chains, kept draws) booleans: the draw lies in the upper mode (t > 0.5)."""
    assert emu.calibration is not None, "a joint fit's emulator has calibration draws"
    return emu.calibration["theta_native"][:, 0].reshape(n_chains, -1) > 0.5


def tempered_fit(n_iter: int, n_chains: int, seed: int, tuning: dict, **kw) -> gpmsa.Emulator:
    """One tempered fit of the two-mode case keeping every sweep after its burn-in."""
    sim, obs = two_mode_case()
    burn = 0 if "init" in kw else n_iter // 5
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        return gpmsa.fit(sim, obs, n_iter=n_iter, n_chains=n_chains, seed=seed, n_jobs=1,
                         n_keep=n_chains * (n_iter - burn), **tuning, **kw)  # fmt: skip


def run_variant(variant: str, n: int, n_chains: int, seed: int, tuning: dict) -> dict:
    """Wall s of the whole run and of the continuation, the continued draws' upper-mode flags
    (chains, n) and the chains that changed mode across the join."""
    t0 = time.perf_counter()
    if variant == "c":
        emu = tempered_fit(2 * n, n_chains, seed, tuning, temperatures=LADDER, theta_init=[0.2])
        wall = time.perf_counter() - t0
        up = upper(emu, n_chains)
        before, new, cont = up[:, -n - 1], up[:, -n:], wall
    else:
        src = tempered_fit(n, n_chains, seed, tuning, temperatures=LADDER, theta_init=[0.2])
        t1 = time.perf_counter()
        extra = {"tune": True} if variant == "b" else {}
        emu = tempered_fit(n, n_chains, seed + 1000, tuning, init=src, **extra)
        wall, cont = time.perf_counter() - t0, time.perf_counter() - t1
        resumed = emu.settings["tune"] is False
        if resumed != (variant == "a"):
            raise RuntimeError(f"variant ({variant}): the continuation's tune is {not resumed}")
        before, new = upper(src, n_chains)[:, -1], upper(emu, n_chains)
    return {"wall": wall, "cont": cont, "up": new, "jumps": int(np.sum(new[:, 0] != before))}


def warm_up() -> None:
    """A small fit and its continuation, untimed: the first fit of a process pays imports
    (ArviZ for the convergence check) that would land on variant (a) alone."""
    tiny = {"tune_rounds": 1, "tune_levels": 2}
    src = tempered_fit(MIN_SWEEPS, 1, 0, tiny, temperatures=LADDER)
    tempered_fit(MIN_SWEEPS, 1, 1, tiny, init=src)


def mode_share(flags: list[np.ndarray]) -> tuple[float, float]:
    """The share of draws in the upper mode and its standard error from the spread of the
    chains' shares (independent chains of equal length; NaN for one chain)."""
    shares = np.concatenate([f.mean(axis=1) for f in flags])
    se = shares.std(ddof=1) / np.sqrt(shares.size) if shares.size > 1 else np.nan
    return float(shares.mean()), float(se)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5,
                    help="runs of each variant, medians printed (default 5)")  # fmt: skip
    ap.add_argument("--sweeps", type=int, default=500, help="N, sweeps a part (default 500)")
    ap.add_argument("--chains", type=int, default=4, help="chains a fit (default 4)")
    quick = "1 repeat, 20 sweeps, 2 chains, tuning 1 x 4 (seconds; noisy)"
    ap.add_argument("--quick", action="store_true", help=quick)
    args = ap.parse_args(argv)
    if args.quick:
        args.repeats, args.sweeps, args.chains = 1, 20, 2
    if args.repeats < 1:
        ap.error(f"--repeats must be >= 1, got {args.repeats}")
    if args.sweeps < MIN_SWEEPS:
        ap.error(f"--sweeps must be >= {MIN_SWEEPS}, got {args.sweeps}")
    if args.chains < 1:
        ap.error(f"--chains must be >= 1, got {args.chains}")
    tuning = {"tune_rounds": 1, "tune_levels": 4} if args.quick else {}
    n, n_chains = args.sweeps, args.chains
    rounds, levels = tuning.get("tune_rounds", 50), tuning.get("tune_levels", 20)
    print(f"# two-mode case, ladder {LADDER}, {n_chains} chains x N = {n} sweeps a part, tuning "
          f"{rounds} x {levels} sweeps a copy, median of {args.repeats} repeats (a, b, c "
          f"alternating), one process; {load()}")  # fmt: skip
    warm_up()
    runs: dict[str, list[dict]] = {v: [] for v in VARIANTS}
    for r in range(args.repeats):
        for variant in VARIANTS:
            runs[variant].append(run_variant(variant, n, n_chains, r, tuning))
        print(f"repeat {r}: " + ", ".join(f"({v}) {runs[v][-1]['wall']:.2f} s" for v in VARIANTS)
              + f"; {load()}", flush=True)  # fmt: skip
    med = {v: statistics.median(x["wall"] for x in runs[v]) for v in VARIANTS}
    cont = {v: statistics.median(x["cont"] for x in runs[v]) for v in VARIANTS}
    total = args.repeats * n_chains
    for v in VARIANTS:
        share, se = mode_share([x["up"] for x in runs[v]])
        jumps = sum(x["jumps"] for x in runs[v])
        part = f" (continuation {cont[v]:.2f} s)" if v != "c" else ""
        print(f"{NAMES[v]:42s} {med[v]:7.2f} s{part}; continued draws in the upper mode "
              f"{share:.3f} +- {se:.3f} (exact 0.5); changed mode across the join: {jumps} of "
              f"{total} chains")  # fmt: skip
    print(
        f"a/b {med['a'] / med['b']:.2f} (continuations alone {cont['a'] / cont['b']:.2f}); "
        f"a/c {med['a'] / med['c']:.2f}"
    )
    print(load())


if __name__ == "__main__":
    main()
