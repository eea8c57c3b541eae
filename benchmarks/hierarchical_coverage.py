"""Coverage of a hierarchical study's 90% intervals: the default uniform group-sd prior against
SEPIA's Gamma(1, 1e-3) on the precision, on synthetic data sets with known truth.

The slow test (tests/gpmsa/test_study_hierarchical.py) checks 6 groups of spread 0.12; this runs
other group counts and spreads on other seeds (the held-out check of the default's choice). Each
data set: mu ~ U(0.35, 0.65), the groups' theta_i from Normal(mu, sd) truncated to (0, 1), 6
noisy observations per group of y = x exp(1.5 t), an emulator with a negligible nugget (the
study case of the tests). Prints, per (groups, sd) and prior, the fraction of 90% intervals that
cover theta_i, mu and the group sd. Usage: python benchmarks/hierarchical_coverage.py [--sets 12]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the tests' study case
from _host import load_average

import gpmsa  # noqa: E402
from tests.gpmsa.test_study_hierarchical import coverage  # noqa: E402

CONFIGS = ((4, 0.06), (4, 0.25), (10, 0.06), (10, 0.25))
"""(groups, group sd) of each row."""


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=" ".join(__doc__.split("\n\n")[0].split()))
    ap.add_argument("--sets", type=int, default=12, help="data sets per row (default 12)")
    args = ap.parse_args(argv)
    if args.sets < 1:
        ap.error(f"--sets must be >= 1, got {args.sets}")
    print(f"# 90% interval coverage, {args.sets} data sets a row; load "
          f"{load_average()[0]:.2f}")  # fmt: skip
    print("groups  sd    prior     theta_i (n)    mu     group sd")
    for n_groups, sd in CONFIGS:
        for name, hyper in (("uniform", gpmsa.HyperPriors()), ("sepia", gpmsa.HyperPriors.sepia())):
            rng = np.random.default_rng(777)  # the same data sets for both priors
            th, mu, s = coverage(rng, n_groups, sd, args.sets, hyper, 900)
            print(f"{n_groups:6d}  {sd:.2f}  {name:8s}  {np.mean(th):.3f} ({len(th):3d})  "
                  f"{np.mean(mu):.3f}  {np.mean(s):.3f}", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
