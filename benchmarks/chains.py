"""Many chains on the road case fit: numpy chains in parallel processes, torch chains batched.

Prints, each with the load average (the machine is shared: compare rows of one run only):
1. numpy, 1 chain vs 2 chains in parallel processes (n_jobs=2): effective samples per second
   and their ratio (target >= 1.8 on 2 cores), medians over ``--repeats`` alternating runs;
2. torch, 64 batched chains with the default warm-up (dispersed starts, 3 stages of warm-up and
   pooled tuning): max R-hat (target < 1.01), min bulk ESS, ESS/s and its ratio to the numpy
   single chain's of part 1 (target >= 1 on this CPU), as one batch (one core) and as
   ``chain_groups`` = the CPU count (one process per group after the tuning);
3. the cost of one chain-sweep: torch x64 against a numpy sweep (CPU time, alternating); with
   ``--case functional`` the synthetic functional fit (``functional``: 160 runs, a 30-point
   output, 5 basis components, 2 known inputs, 4 calibration parameters, 4 observations),
   simulation-only and joint, ``--torch-chains`` chains (8 there).

Fit: the simulation-only emulator (198 runs, scalar output; betaU, lamUz, lamWs, lamWOs), run
through the backend's ``sample`` with its defaults (tuning, the nugget-ridge moves); ESS: arviz
bulk ESS of the draws after burn-in (n_iter // 5 per chain, as ``gpmsa.fit``), the minimum over
every sampled scalar; per second of wall time of the whole run (tuning, warm-up, process start
included). The torch chains draw as many sweeps as the numpy chain (``--torch-iter`` defaults
to ``--numpy-iter``): the ESS/s of chains of equal length (at 2,000 draws a chain 64 chains each
pay the warm-up: docs/performance.md). Usage: python benchmarks/chains.py [--repeats 3]
[--numpy-iter 6000] [--torch-iter N] [--torch-chains 64] [--only numpy|torch|sweep]
[--case road|functional] (``functional``: part 3 only).
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _host import load_average
from backends import ess_rhat, rhat_text, road  # noqa: E402

from gpmsa import backends  # noqa: E402
from gpmsa.mcmc.parallel import available_cpus  # noqa: E402
from gpmsa.model.problem import prepare  # noqa: E402

MIN_ITER = 5
"""Fewest sweeps a chain (``--numpy-iter``, ``--torch-iter``): the bulk ESS needs 4 draws after
the burn-in of n_iter // 5."""


def load() -> str:
    """The 1-minute load average, printed with every figure."""
    return f"load {load_average()[0]:.2f}"


def run_fit(backend: str, n_iter: int, n_chains: int, seed: int, **options) -> tuple:
    """(wall s, CPU s of this process and its workers, min ESS, max R-hat, chains) of one
    road-case simulation-only fit."""
    problem = prepare(road()[0]).problem
    t0, c0 = time.perf_counter(), os.times()
    chains = backends.get(backend).sample(
        problem, n_iter=n_iter, n_chains=n_chains, seed=seed, **options
    )
    wall, c1 = time.perf_counter() - t0, os.times()
    cpu = (c1.user + c1.system + c1.children_user + c1.children_system
           - c0.user - c0.system - c0.children_user - c0.children_system)  # fmt: skip
    kept = {k: v[:, n_iter // 5 :] for k, v in chains.draws.items()}
    return (wall, cpu, *ess_rhat(kept, problem.sampled), chains)


def numpy_parallel(n_iter: int, repeats: int) -> float:
    """Part 1; returns the single chain's median ESS/s."""
    print(f"\n# numpy, road case fit, {n_iter} sweeps a chain after 1,000 tuning sweeps; {load()}")
    rates: dict[int, list[float]] = {1: [], 2: []}
    per_cpu: dict[int, list[float]] = {1: [], 2: []}
    sweeps: dict[int, list[float]] = {1: [], 2: []}
    for r in range(repeats):
        for n_chains in (1, 2):
            wall, cpu, n_eff, r_hat, _ = run_fit("numpy", n_iter, n_chains, seed=r, n_jobs=n_chains)
            rates[n_chains].append(n_eff / wall)
            per_cpu[n_chains].append(n_eff / cpu)
            sweeps[n_chains].append(n_chains * (n_iter + 1000) / wall)
            print(f"numpy {n_chains} chain(s), n_jobs={n_chains}, seed {r}: wall {wall:6.2f} s, "
                  f"CPU {cpu:6.2f} s, min ESS {n_eff:6.0f}, ESS/s {n_eff / wall:6.1f}, "
                  f"ESS per CPU-s {n_eff / cpu:6.1f}, max R-hat {rhat_text(r_hat).strip()}; "
                  f"{load()}",
                  flush=True)  # fmt: skip
    med = {k: statistics.median(v) for k, v in rates.items()}
    print(f"numpy ESS/s median: 1 chain {med[1]:.1f}, 2 chains in parallel {med[2]:.1f}: ratio "
          f"{med[2] / med[1]:.2f} (target >= 1.8); chain-sweeps/s ratio "
          f"{statistics.median(sweeps[2]) / statistics.median(sweeps[1]):.2f}; ESS per CPU-s "
          f"ratio {statistics.median(per_cpu[2]) / statistics.median(per_cpu[1]):.2f}; "
          f"{load()}")  # fmt: skip
    return med[1]


def torch_batched(n_iter: int, n_chains: int, numpy_rate: float | None) -> None:
    """Part 2: one batch (one core), then ``chain_groups`` = every CPU (one process each; at
    most one group a chain)."""
    print(f"\n# torch, {n_chains} batched chains x {n_iter} draws, default warm-up; {load()}")
    cpus = min(available_cpus(), n_chains)
    rates = {}
    for groups in (1, cpus) if cpus > 1 else (1,):
        wall, cpu, n_eff, r_hat, chains = run_fit("torch", n_iter, n_chains, seed=0,
                                                  chain_groups=groups)  # fmt: skip
        worst = _worst_rhat(chains, n_iter // 5)
        rates[groups] = n_eff / wall
        line = (
            f"torch x{n_chains}, chain_groups={groups}: wall {wall:7.1f} s, min ESS {n_eff:7.0f}, "
            f"ESS/s {n_eff / wall:6.1f}, max R-hat {r_hat:.4f} ({worst}; target < 1.01), CPU "
            f"{cpu:.1f} s"
        )
        if numpy_rate:
            line += f", ESS/s vs numpy 1 chain {n_eff / wall / numpy_rate:.2f} (target >= 1)"
        print(line + f"; {load()}", flush=True)
    if len(rates) == 2:
        print(f"torch ESS/s, {cpus} groups vs one batch: {rates[cpus] / rates[1]:.2f}x; {load()}")


def _worst_rhat(chains, burn: int) -> str:
    from gpmsa.mcmc.diagnostics import rhat

    worst = (0.0, "")
    for name, d in chains.draws.items():
        flat = d[:, burn:].reshape(d.shape[0], d.shape[1] - burn, -1)
        for i in range(flat.shape[2]):
            if np.ptp(flat[:, :, i]) > 0:
                worst = max(worst, (rhat(flat[:, :, i]), f"{name}[{i}]"))
    return worst[1] or "no finite R-hat"  # (one chain, or too few draws)


def functional(seed: int = 0):
    """The synthetic functional case: 160 runs of a smooth 30-point output over 2 known inputs
    and 4 calibration parameters (5 basis components), and 4 noisy observations at theta =
    (0.3, 0.5, 0.6, 0.4). Returns (SimData, ObsData)."""
    import gpmsa

    rng = np.random.default_rng(seed)
    m, grid = 160, np.linspace(0.0, 1.0, 30)
    design = (np.argsort(rng.random((m, 6)), axis=0) + rng.random((m, 6))) / m  # a Latin square

    def model(x: np.ndarray, t: np.ndarray) -> np.ndarray:
        g = grid[None, :]
        return (np.sin(2.0 * g * (1.0 + t[:, :1] + x[:, :1])) * (1.0 + t[:, 1:2])
                + t[:, 2:3] * np.cos(3.0 * g + x[:, 1:2]) + 0.5 * t[:, 3:4] * g**2)  # fmt: skip

    x, t = design[:, :2], design[:, 2:]
    x_obs = rng.random((4, 2))
    theta = np.tile([0.3, 0.5, 0.6, 0.4], (4, 1))
    y_obs = model(x_obs, theta) + 0.02 * rng.normal(size=(4, grid.size))
    sim = gpmsa.SimData(x=x, t=t, y=model(x, t), index=grid)
    return sim, gpmsa.ObsData(x=x_obs, y=y_obs)


def sweep_cost(n_chains: int, rounds: int = 12, case: str = "road") -> None:
    """Part 3: CPU ms per chain-sweep, torch batched vs numpy, alternating (one thread each);
    ``case`` "functional": the synthetic functional fit, simulation-only then joint."""
    if case == "road":
        _sweep_cost(prepare(road()[0]).problem, "road case", n_chains, rounds, 128)
        return
    sim, obs = functional()
    for what, data in (("simulation-only", None), ("joint", obs)):
        problem = prepare(sim, data, n_pc=5).problem
        _sweep_cost(problem, f"functional case, {what}", n_chains, max(rounds // 3, 2), 8)


def _sweep_cost(problem, label: str, n_chains: int, rounds: int, np_sweeps: int) -> None:
    import torch
    from threadpoolctl import threadpool_limits

    from gpmsa.backends.torch_backend import BatchState
    from gpmsa.mcmc.sampler import ChainState, elements, sample

    tuned = sample(problem, n_iter=10, seed=0, tune_rounds=10)
    start = problem.with_init({k: v[0, -1] for k, v in tuned.draws.items()})
    w = np.array([tuned.step_widths[n][0][i] for n, i in elements(start)])
    print(f"\n# one chain-sweep, {label} (CPU time, 1 thread, the ridge moves included); "
          f"{load()}")  # fmt: skip
    torch.set_num_threads(1)
    with threadpool_limits(1), torch.no_grad():
        chain = ChainState(start, start.init, np.random.default_rng(1), ridge_moves=5)
        batch = BatchState(start, n_chains, torch.float64, "cpu", ridge_moves=5)
        gen = torch.Generator().manual_seed(0)
        acc = np.zeros(len(w))
        np_ms, t_ms = [], []
        for _ in range(rounds):
            t0 = time.process_time()
            for _ in range(np_sweeps):
                chain.sweep(w, False, acc)
            np_ms.append((time.process_time() - t0) / np_sweeps * 1e3)
            t0 = time.process_time()
            for _ in range(2):
                batch.sweep(w, False, gen)
            t_ms.append((time.process_time() - t0) / 2 / n_chains * 1e3)
    print(f"numpy sweep: median {np.median(np_ms):.3f} ms, best {min(np_ms):.3f} ms; torch "
          f"x{n_chains} chain-sweep: median {np.median(t_ms):.3f} ms, best {min(t_ms):.3f} ms; "
          f"ratio of medians {np.median(t_ms) / np.median(np_ms):.2f}, of bests "
          f"{min(t_ms) / min(np_ms):.2f} (target <= 1); {load()}")  # fmt: skip


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3,
                    help="part 1's alternating runs, medians printed (default 3)")  # fmt: skip
    ap.add_argument("--numpy-iter", type=int, default=6000,
                    help="sweeps a numpy chain after its tuning (default 6000)")  # fmt: skip
    ap.add_argument("--torch-iter", type=int, default=None, help="default: --numpy-iter")
    ap.add_argument("--torch-chains", type=int, default=64,
                    help="batched torch chains of parts 2 and 3 (default 64)")  # fmt: skip
    ap.add_argument("--only", choices=("numpy", "torch", "sweep"), default=None,
                    help="one part: 1 numpy, 2 torch (no numpy ratio then), 3 sweep (default: "
                    "all)")  # fmt: skip
    ap.add_argument("--case", choices=("road", "functional"), default="road",
                    help="part 3's fit (functional: part 3 only)")  # fmt: skip
    args = ap.parse_args(argv)
    if args.repeats < 1:
        ap.error(f"--repeats must be >= 1, got {args.repeats}")
    for option, n_iter in (("--numpy-iter", args.numpy_iter), ("--torch-iter", args.torch_iter)):
        if n_iter is not None and n_iter < MIN_ITER:
            ap.error(f"{option} must be >= {MIN_ITER} (the ESS's 4 draws after burn-in), "
                     f"got {n_iter}")  # fmt: skip
    if args.torch_chains < 1:
        ap.error(f"--torch-chains must be >= 1, got {args.torch_chains}")
    print(f"# {os.cpu_count()} CPUs; {load()}; one BLAS / torch thread per chain or batch")
    rate = None
    if args.case == "functional":
        sweep_cost(args.torch_chains, case="functional")
        return
    if args.only in (None, "numpy"):
        rate = numpy_parallel(args.numpy_iter, args.repeats)
    if args.only in (None, "torch"):
        n_iter = args.numpy_iter if args.torch_iter is None else args.torch_iter
        torch_batched(n_iter, args.torch_chains, rate)
    if args.only in (None, "sweep"):
        sweep_cost(args.torch_chains)


if __name__ == "__main__":
    main()
