"""Simulation-based calibration (SBC; Talts et al. 2018) of the online calibration.

Each replicate draws theta from its calibration prior (GPM/SA's Normal(0.5, 10) truncated to
the unit domain), lamOs from its prior (Gamma(1, 1e-3), or the case's), the experiments' x
uniformly on the domain, the observations' basis weights u from the emulator's predictive at
(x_obs, theta) given the simulation weights w (mean and covariance, jointly over the
experiments, the nugget included; computed here by dense solves of the paper's formulas, not
by gpmsa's predictor) and y_obs = K u + e, e ~ N(0, I / lamOs) in standardised units on every
output value (so a functional output's values beyond the basis carry the noise that GPM/SA's
lamOs correction reads). The emulator is a small fit held at its point estimate
(``emulator_params="point"``). Then (a) the exact grid ``gpmsa.Calibrator(method="grid")``: the
PIT of the truth, its posterior CDF (uniform iff the posterior is exact); (b) ``gpmsa.calibrate``
(the fast MCMC, short chains): the rank of the truth among 99 draws thinned from the kept ones
(theta and lamOs; "lamOs known": lamOs held at its true value with ``fixed=``). Printed per
row: a 10-bin histogram's chi-square p-value and the 50% / 90% central intervals' coverage
with its binomial standard error.

Usage: python benchmarks/sbc_calibration.py [--replicates 500] [--mcmc-replicates 200]
[--seed 2018] [--dev] [--cases NAME ...]
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.linalg import cho_factor, cho_solve
from scipy.stats import chisquare, truncnorm

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from _host import load_average

import gpmsa  # noqa: E402

REPORT_SEED = 2018
"""The seed of the reported table (docs/calibration.md)."""
DEV_SEED = 77
"""The seed the checks were developed on (``--dev``): distinct from ``REPORT_SEED``."""
N_RANK_DRAWS = 99
"""MCMC draws a rank is taken among (ranks 0..99: 10 bins of 10)."""
N_BINS = 10
LEVELS = (0.5, 0.9)
MCMC_SAMPLES, MCMC_BURN = 3000, 1000
"""Sweeps of each ``gpmsa.calibrate`` run and those burned: 2,000 kept, thinned by 20 (the
fast sampler's ESS is about a quarter of its draws)."""


@dataclass(frozen=True)
class Case:
    """One SBC row's emulator: ``q`` calibration parameters, ``n_pc`` basis vectors on ``l``
    output values (l = 1: a scalar output), ``n_obs`` experiments a replicate; ``lamos``: the
    (a, b) of a calibration lamOs prior other than the emulator's (None: GPM/SA's)."""

    name: str
    q: int
    l: int  # noqa: E741
    n_pc: int
    n_obs: int
    lamos: tuple[float, float] | None = None


CASES = (
    Case("scalar_q1", 1, 1, 1, 2),
    Case("scalar_q2", 2, 1, 1, 2),
    Case("functional_q1", 1, 10, 3, 2),
    Case("functional_q2", 2, 10, 3, 1),
    Case("functional_q1_precise", 1, 10, 3, 2, (20.0, 20.0 / 2500.0)),
)
CASE_NAMES = tuple(c.name for c in CASES)


def simulator(x: np.ndarray, t: np.ndarray, grid: np.ndarray | None) -> np.ndarray:
    """A smooth test simulator: (m,) x and (m, q) t on [0, 1] -> (m, l) outputs (l = 1 without
    a grid)."""
    s = np.zeros(1) if grid is None else grid
    out = (1.0 + t[:, :1]) * np.sin(np.pi * (0.3 + s[None, :]) * (0.5 + x[:, None]))
    if t.shape[1] > 1:
        out = out + 0.8 * t[:, 1:2] * (0.5 + s[None, :]) * x[:, None]
    return out


def emulator(case: Case, n_iter: int = 1000) -> gpmsa.Emulator:
    """The case's emulator: ``gpmsa.fit`` of 30 runs (seeded), held at its point estimate."""
    rng = np.random.default_rng(11)
    m = 30
    x, t = rng.uniform(0, 1, m), rng.uniform(0, 1, (m, case.q))
    grid = None if case.l == 1 else np.linspace(0, 1, case.l)
    y = simulator(x, t, grid)
    sim = gpmsa.SimData(x=x[:, None], t=t, y=y, index=grid, x_names=["x"],
                        t_names=["a", "b"][: case.q])  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a short chain's ConvergenceWarning
        emu = gpmsa.fit(sim, n_iter=n_iter, seed=3, n_pc=None if case.l == 1 else case.n_pc)
    if case.lamos is not None:
        emu = emu.with_calibration_priors(lamOs=gpmsa.GammaPrior(*case.lamos))
    return emu


def predictive(emu, xu: np.ndarray, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The predictive of the observations' weights u at (xu (n, p) unit, theta (q,) unit) given
    w: mean (p_u, n) and covariance (p_u, n, n), by dense solves of Sigma_W (Higdon et al.
    2008): mu = Sigma_UW Sigma_W^-1 w, S = Sigma_U - Sigma_UW Sigma_W^-1 Sigma_WU, with
    Sigma_W = R / lamUz + (1 / (lam_sim lamWOs) + 1 / lamWs) I and Sigma_U = R / lamUz + I /
    lamWs, R = exp(-sum_k beta_k (z_k - z'_k)^2)."""
    prm = emu.params
    zs = np.hstack([emu.x_unit, emu.t_unit])
    zo = np.hstack([xu, np.tile(theta, (xu.shape[0], 1))])
    p_u = emu.w.shape[1]
    beta = np.asarray(prm["betaU"], dtype=float).reshape(zs.shape[1], p_u)
    lam_uz, lam_ws = np.ravel(prm["lamUz"]), np.ravel(prm["lamWs"])
    lam_wos = float(np.ravel(prm["lamWOs"])[0])

    def corr(a, b, bk):
        return np.exp(-np.sum(bk * (a[:, None, :] - b[None, :, :]) ** 2, axis=-1))

    mean, cov = [], []
    for c in range(p_u):
        sig_w = corr(zs, zs, beta[:, c]) / lam_uz[c]
        sig_w += np.eye(len(zs)) * (1.0 / (emu.lam_sim[c] * lam_wos) + 1.0 / lam_ws[c])
        sig_u = corr(zo, zo, beta[:, c]) / lam_uz[c] + np.eye(len(zo)) / lam_ws[c]
        sig_uw = corr(zo, zs, beta[:, c]) / lam_uz[c]
        fac = cho_factor(sig_w, lower=True)
        mean.append(sig_uw @ cho_solve(fac, emu.w[:, c]))
        cov.append(sig_u - sig_uw @ cho_solve(fac, sig_uw.T))
    return np.array(mean), np.array(cov)


def draw_replicate(emu, rng: np.random.Generator, n_obs: int):
    """(theta unit (q,), lamOs, x_obs native (n, 1), y_obs native (n, l)) from the model."""
    pri = emu.priors
    theta = np.empty(emu.t_unit.shape[1])
    for k in range(theta.size):
        m, s = pri.theta_prior(k)
        theta[k] = truncnorm.rvs(-m / s, (1 - m) / s, loc=m, scale=s, random_state=rng)
    lam = pri.lamOs.upper
    while not pri.lamOs.lower < lam < pri.lamOs.upper:  # its truncation (none by default)
        lam = rng.gamma(pri.lamOs.a, 1.0 / pri.lamOs.b)
    xu = rng.uniform(0, 1, (n_obs, emu.x_unit.shape[1]))
    mean, cov = predictive(emu, xu, theta)
    u = np.array(
        [rng.multivariate_normal(mu, s, method="cholesky") for mu, s in zip(mean, cov, strict=True)]
    )
    y_std = (emu.K @ u).T + rng.standard_normal((n_obs, emu.K.shape[0])) / np.sqrt(lam)
    std = emu.standardizer
    return theta, lam, std.x_from_unit(xu), std.y_from_std(y_std)


def grid_pits(emu, case: Case, reps: int, rng: np.random.Generator) -> dict:
    """PIT of each theta element's truth and whether the 50% / 90% central intervals cover it."""
    cal = gpmsa.Calibrator(emu, method="grid")
    std, names = emu.standardizer, emu.t_names
    pit, cover = np.empty((reps, len(names))), np.empty((reps, len(names), len(LEVELS)), bool)
    for r in range(reps):
        theta, _, x, y = draw_replicate(emu, rng, case.n_obs)
        truth = std.t_from_unit(theta[None])[0]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # outside / resolution notes: not the posterior
            post = cal.update(x, y)
        for k, name in enumerate(names):
            pit[r, k] = float(post.grids[name].cdf(truth[k]))
            for j, level in enumerate(LEVELS):
                lo, hi = post.interval(name, level)
                cover[r, k, j] = lo <= truth[k] <= hi
    return {name: (pit[:, k], cover[:, k]) for k, name in enumerate(names)}


def mcmc_ranks(emu, case: Case, reps: int, rng: np.random.Generator, known: bool) -> dict:
    """Rank of each truth (theta elements, and lamOs unless ``known``: then held at its true
    value with ``fixed=``) among ``N_RANK_DRAWS`` thinned draws, as a fraction of
    ``N_RANK_DRAWS + 1`` ranks' top, and interval coverage, from ``gpmsa.calibrate``."""
    std = emu.standardizer
    names = list(emu.t_names) + ([] if known else ["lamOs"])
    kept = MCMC_SAMPLES - MCMC_BURN
    pick = np.linspace(0, kept - 1, N_RANK_DRAWS).round().astype(int)
    rank, cover = np.empty((reps, len(names))), np.empty((reps, len(names), len(LEVELS)), bool)
    for r in range(reps):
        theta, lam, x, y = draw_replicate(emu, rng, case.n_obs)
        truth = list(std.t_from_unit(theta[None])[0]) + ([] if known else [lam])
        seed = int(rng.integers(2**63))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # convergence / outside / at-bound notes
            post = gpmsa.calibrate(emu, x, y, n_samples=MCMC_SAMPLES, n_burn=MCMC_BURN, seed=seed,
                                   fixed={"lamOs": lam} if known else None)  # fmt: skip
        for k, name in enumerate(names):
            draws = post.samples[name]
            rank[r, k] = np.sum(draws[pick] < truth[k]) + 0.5 * np.sum(draws[pick] == truth[k])
            for j, level in enumerate(LEVELS):
                lo, hi = post.interval(name, level)
                cover[r, k, j] = lo <= truth[k] <= hi
    return {name: (rank[:, k], cover[:, k]) for k, name in enumerate(names)}


def histogram_p(values: np.ndarray, top: float) -> tuple[np.ndarray, float]:
    """A ``N_BINS``-bin histogram of ``values`` on [0, top] (closed) and its chi-square p-value
    against uniform."""
    edges = np.linspace(0.0, top, N_BINS + 1)
    edges[-1] = np.nextafter(top, np.inf)
    counts = np.histogram(values, bins=edges)[0]
    return counts, float(chisquare(counts).pvalue)


def coverage_text(cover: np.ndarray) -> str:
    n = cover.shape[0]
    parts = []
    for j, level in enumerate(LEVELS):
        c = cover[:, j].mean()
        parts.append(f"{c:.3f} +- {np.sqrt(level * (1 - level) / n):.3f}")
    return "  ".join(parts)


def row(label: str, name: str, values, top: float, cover) -> str:
    counts, p = histogram_p(values, top)
    return (f"{label:50s} {name:6s} {len(values):5d}  {p:8.3g}  {coverage_text(cover)}  "
            f"{' '.join(f'{c:3d}' for c in counts)}")  # fmt: skip


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=" ".join(__doc__.split("\n\n")[0].split()))
    ap.add_argument("--replicates", type=int, default=500,
                    help="replicates per grid row (default 500)")  # fmt: skip
    ap.add_argument("--mcmc-replicates", type=int, default=200,
                    help="replicates per MCMC row (default 200; 0: no MCMC rows)")  # fmt: skip
    ap.add_argument("--seed", type=int, default=REPORT_SEED,
                    help=f"root seed (default {REPORT_SEED}, the reported one)")  # fmt: skip
    ap.add_argument("--dev", action="store_true",
                    help=f"use the development seed {DEV_SEED} instead of --seed")  # fmt: skip
    ap.add_argument("--cases", nargs="+", default=list(CASE_NAMES), metavar="NAME",
                    help=f"rows among {', '.join(CASE_NAMES)} (default: all)")  # fmt: skip
    args = ap.parse_args(argv)
    if args.replicates < 1:
        ap.error(f"--replicates must be >= 1, got {args.replicates}")
    if args.mcmc_replicates < 0:
        ap.error(f"--mcmc-replicates must be >= 0, got {args.mcmc_replicates}")
    if not 0 <= args.seed < 2**63:
        ap.error(f"--seed must be in [0, 2**63), got {args.seed}")
    unknown = sorted(set(args.cases) - set(CASE_NAMES))
    if unknown:
        ap.error(f"--cases must be among {', '.join(CASE_NAMES)}, got {', '.join(unknown)}")
    seed = DEV_SEED if args.dev else args.seed
    print(
        f"# SBC of the online calibration; seed {seed} ({'development' if args.dev else 'root'}"
        f"; reported: {REPORT_SEED}, development: {DEV_SEED}); load {load_average()[0]:.2f}"
    )
    print(
        f"# grid: PIT of the truth (exact CDF); MCMC: rank among {N_RANK_DRAWS} draws of "
        f"{MCMC_SAMPLES - MCMC_BURN} kept ({MCMC_SAMPLES} sweeps, {MCMC_BURN} burned)"
    )
    print(f"{'row':50s} {'param':6s} {'n':>5s}  {'chi2 p':>8s}  {'50% cover':>13s}  "
          f"{'90% cover':>13s}  histogram ({N_BINS} bins)")  # fmt: skip
    start = time.perf_counter()
    for i, case in enumerate(CASES):
        if case.name not in args.cases:
            continue
        emu = emulator(case)
        streams = np.random.SeedSequence([seed, i]).spawn(3)
        label = f"{case.name} ({case.n_obs} obs, p_u {emu.K.shape[1]})"
        for name, (pit, cover) in grid_pits(emu, case, args.replicates,
                                            np.random.default_rng(streams[0])).items():  # fmt: skip
            print(row(f"grid {label}", name, pit, 1.0, cover), flush=True)
        if args.mcmc_replicates == 0:
            continue
        for known, stream in ((False, streams[1]), (True, streams[2])):
            ranks = mcmc_ranks(
                emu, case, args.mcmc_replicates, np.random.default_rng(stream), known
            )
            tag = "mcmc, lamOs known" if known else "mcmc"
            for name, (rank, cover) in ranks.items():
                print(row(f"{tag} {label}", name, rank, float(N_RANK_DRAWS), cover), flush=True)
    print(f"# {time.perf_counter() - start:.0f} s; load {load_average()[0]:.2f}")


if __name__ == "__main__":
    main()
