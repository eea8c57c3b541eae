"""How far round-off moves the campaign's f, and what on this machine changes it at all.

Part 1 (in this process): the first ``--runs`` runs of the default campaign (Jackal, 21 m roads,
seed 0, noise-free f), once as made and once with every road height moved by one ulp
(``np.nextafter``), with lift-off (the default) and with bilateral contact. Prints how many runs
change and by how much in log f.

Part 2 (``--env``, one subprocess per setting): the same runs under settings that differ between
machines and can be switched here: the OpenBLAS kernel (``OPENBLAS_CORETYPE``), BLAS/OpenMP
threads, numpy's SIMD level (``NPY_DISABLE_CPU_FEATURES``) and Exudyn's AVX2 build
(``EXUDYN_MODULE=fast``). Prints whether f is bit-identical to the default.

    python benchmarks/reproducibility.py [--runs 198] [--env]

Results and their reading: docs/vehicle-models.md, "Reproducibility".
"""

from __future__ import annotations

import argparse
import hashlib
import os
import subprocess
import sys

import numpy as np

import roadgen
import vehicle
from vehicle.simulate import simulate

CAMPAIGN_RUNS = 198  # the default campaign's design (vehicle.run_campaign)
ENV_SETTINGS = {
    "OpenBLAS kernel Sandybridge": {"OPENBLAS_CORETYPE": "Sandybridge"},
    "OpenBLAS kernel Prescott (SSE3)": {"OPENBLAS_CORETYPE": "Prescott"},
    "BLAS and OpenMP threads = 1": {"OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"},
    "numpy SIMD at baseline (no AVX2/FMA3)": {"NPY_DISABLE_CPU_FEATURES": "X86_V3"},
    "Exudyn AVX2 build (exudynCPPfast)": {"EXUDYN_MODULE": "fast"},
}


def campaign_f(n: int, lift_off: bool = True, ulp: bool = False) -> np.ndarray:
    """Noise-free f_window of the first n runs of the default campaign (seed 0)."""
    model = vehicle.Jackal(lift_off=lift_off)
    design = vehicle.lhs_design(CAMPAIGN_RUNS, seed=0)[:n]
    seeds = np.random.SeedSequence(0).generate_state(CAMPAIGN_RUNS).astype(np.int64)[:n]
    out = []
    for (v, gd), s in zip(design, seeds, strict=True):
        road = roadgen.iso8608_profile(21.0, gd, dx_m=0.006, seed=int(s), lead_in_m=1.0)
        if ulp:
            road = roadgen.Profile(x=road.x, z=np.nextafter(road.z, np.inf), dx_m=road.dx_m,
                                   gd=road.gd, settings=road.settings)  # fmt: skip
        trace = simulate(model, road, float(v))
        out.append(np.var(trace.accel_front[-1000:]))
    return np.array(out)


def _report(label: str, a: np.ndarray, b: np.ndarray) -> None:
    d = np.abs(np.log(b) - np.log(a))
    print(
        f"{label:34s} bit-identical {np.sum(a == b):3d}/{a.size}; |dlog f| > 1e-6: "
        f"{np.sum(d > 1e-6):3d}, > 0.01: {np.sum(d > 0.01):3d}; median {np.median(d):.1e}, "
        f"99% {np.quantile(d, 0.99):.1e}, max {d.max():.2g}"
    )


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=198,
                        help="the default campaign's first N runs (default 198: all)")  # fmt: skip
    parser.add_argument("--env", action="store_true", help="also the machine settings (part 2)")
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if not 1 <= args.runs <= CAMPAIGN_RUNS:
        parser.error(f"--runs must be in [1, {CAMPAIGN_RUNS}] (the default campaign's runs), "
                     f"got {args.runs}")  # fmt: skip
    if args.child:  # part 2's worker: print a hash of f
        f = campaign_f(args.runs)
        print(hashlib.sha256(f.tobytes()).hexdigest())
        return
    print(f"{args.runs} runs of the default campaign; noise-free f_window; road heights +1 ulp")
    for lift in (True, False):
        a = campaign_f(args.runs, lift)
        _report(
            f"{'lift-off' if lift else 'bilateral'}: again, unchanged",
            a,
            campaign_f(args.runs, lift),
        )
        _report(
            f"{'lift-off' if lift else 'bilateral'}: road +1 ulp",
            a,
            campaign_f(args.runs, lift, True),
        )
    if not args.env:
        return
    cmd = [sys.executable, os.path.abspath(__file__), "--child", "--runs", str(args.runs)]
    base = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout.split()[-1]
    for label, env in ENV_SETTINGS.items():
        got = subprocess.run(cmd, capture_output=True, text=True, check=True,
                             env={**os.environ, **env}).stdout.split()[-1]  # fmt: skip
        print(f"{label:40s} f {'bit-identical' if got == base else 'DIFFERS'}")


if __name__ == "__main__":
    main()
