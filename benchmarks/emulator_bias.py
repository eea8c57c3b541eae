"""Does the shipped band emulator have a bias anywhere in its domain, edges included?

    PYTHONPATH=. python benchmarks/emulator_bias.py             # 63 cells x 3 roads x 60 s
    PYTHONPATH=. python benchmarks/emulator_bias.py --quick     # 63 cells x 1 road x 60 s
    PYTHONPATH=. python benchmarks/emulator_bias.py --emulator-dir DIR --features band  # yours
    PYTHONPATH=. python benchmarks/emulator_bias.py --help

On held-aside roads (a campaign seed whose road seeds are not among the training campaign's,
checked), the Jackal drives k roads (``--roads``) for ``--keep-s`` seconds at constant speed in
each cell of a 7 x 9 grid spanning the emulators' domain evenly, both ends included (the shipped
ones: v in {0.5, 0.75, ..., 2.0} m/s x GD in {200, 250, ..., 600}), through the
training pipeline itself (`vehicle.run_campaign`: `roadgen.iso8608_profile` roads with the same
lead-in and `vehicle.simulate`; case A: noise-free accelerations, case B: with N(0, 1) noise).
``--emulator-dir`` scores the emulators in a folder (`examples/train_emulator.py
--emulator-dir`) instead of the shipped ones: the roads are driven by the vehicle their metadata
records, case B with their noise level, and emulators that disagree on either, or on their
domain, stop the run.

Band emulator (``control.shipped_emulator(case, "band")``, the change-point BCR's): every
125-sample block's feature vector (`control.block_features`: the log band powers, then the
quantiles less the mean); per cell

- ``z``: per output, (mean over the cell's blocks - ``emu.predict_mean(v, GD)``) in units
  of its Monte-Carlo standard error (the cell's long-run block variance, batch means of 8
  blocks as `control.training`, over the number of blocks);
- ``chi2``: d' (Sigma(v) / n)^-1 d over the K outputs with the emulator's own block scatter
  Sigma(v) (its metadata), and its chi-square(K) upper-tail probability ``p``; ``var`` is the
  cell's long-run block variance over Sigma(v)'s, averaged over outputs (1 when the scatter the
  likelihood assumes is right);
- ``GD bias``: the maximum-likelihood GD of all the cell's blocks pooled
  (`control.ObservationModel.loglik` summed over the blocks, on an 801-node log grid refined by a
  parabola) relative to the truth, %, with its Monte-Carlo standard error from a block bootstrap
  (400 resamples of batches of 8 consecutive blocks);
- ``lin``: the same bias linearised at the truth, exp(g' S^-1 d / g' S^-1 g) - 1 with
  g = d mu / d log GD of the emulator and S = Sigma(v), with its standard error from the cell's
  long-run covariance: not truncated by the domain's edges (the ML at GD 200 and 600 is);
- ``emu``: the emulator's own sd of its mean at the cell (each component's GP variance at the
  point estimate, no nugget, through the basis: `gpmsa.emulator_prediction`), as a linearised GD
  error like ``lin``. A bias within it is the uncertainty the emulator states; a cell marked
  ``+`` in its table lies beyond 2 x the root of se^2 + emu^2, an error the emulator does not
  claim (a misfit, not too few runs).

Window emulator (``shipped_emulator(case, "window")``, the paper's): log f of disjoint 1,000-sample
windows (7 per minute of driving); ``z`` of the mean against ``emu.predict(v, GD)``'s mean in
units of its standard error (window sd / sqrt(n)), ``sd``: the windows' sd over the emulator's
predictive sd (nugget included; 1 when the paper's likelihood has the right width), the GD
bias: the maximum-likelihood GD of all the cell's windows under the Gaussian likelihood
N(mean(v, GD), var(v, GD)) of ``emu.predict`` with its nugget, with a bootstrap over windows,
and its linearised form (d / slope).

Printed (with the load average): per case and emulator, a line per cell, then a table (rows GD,
columns v) of the relative GD bias in %, marked ``*`` where it exceeds twice its Monte-Carlo
standard error (about 3 of 63 cells by chance alone) and ``|`` where the maximum lies on the
domain's edge (200 or 600: a truncated, one-sided estimate), the same for the linearised bias,
and RMS figures (a bias beyond Monte-Carlo noise shows as an RMS bias above the RMS se).
Campaign runs are cached under ``--cache-dir``.
"""

from __future__ import annotations

import argparse
import time
import warnings
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from _host import load_average
from scipy import stats

import control
import gpmsa
import vehicle
from control.training import block_statistics
from gpmsa.model.data import MAX_SEED

N_SPEEDS = 7
N_GDS = 9
RATE_HZ = 120.0
WINDOW = 1000
BATCH = 8  # blocks per batch of the long-run covariance and of the block bootstrap
N_GRID = 801
N_BOOT = 400


def load() -> str:
    return "load average {:.2f} {:.2f} {:.2f}".format(*load_average())


def training_seeds(emu) -> np.ndarray:
    """Road seeds of the campaign an emulator was trained on (its metadata's design)."""
    design = emu.metadata["design"]
    return np.random.SeedSequence(int(design["seed"])).generate_state(int(design["n"]))


@dataclass(frozen=True)
class Grid:
    """The cells: speeds (m/s) x GDs (1e-6 m^3), each spanning the emulator's domain evenly."""

    speeds: tuple[float, ...]
    gds: tuple[float, ...]

    @classmethod
    def over(cls, emu) -> Grid:
        """The cells over ``emu``'s domain, rounded to 9 decimals: emulators trained on one
        design with other library versions may bound it 1 ulp apart (2.0, 1.9999999999999998)."""
        (v_lo, v_hi), (g_lo, g_hi) = emu.domain["v"], emu.domain["GD"]
        return cls(
            tuple(np.round(np.linspace(v_lo, v_hi, N_SPEEDS), 9).tolist()),
            tuple(np.round(np.linspace(g_lo, g_hi, N_GDS), 9).tolist()),
        )


def drive(grid: Grid, roads: int, keep_s: float, seed: int, workers: int,
          cache_dir: str | None, model, noise_std: float):  # fmt: skip
    """The campaign: every grid cell driven on `roads` fresh roads by ``model``, its noisy
    accelerations with N(0, noise_std^2) noise."""
    design = np.array([(v, gd) for v in grid.speeds for gd in grid.gds for _ in range(roads)])
    with ProcessPoolExecutor(max_workers=workers) as pool:
        return vehicle.run_campaign(
            design, model, seed=seed, keep_s=keep_s, executor=pool, progress=False,
            cache_dir=cache_dir, noise_std=noise_std,
        )  # fmt: skip


def emulators_to_score(args) -> tuple[dict, object, float, Grid]:
    """({(case, kind): emulator}, the vehicle they were trained for, the noise sd of the drives'
    noisy accelerations: case B's, or the paper's 1 m/s^2 when B is not scored, the cells over
    their domain): what the held-aside drives must match; exits naming any emulator that does
    not."""
    try:
        emus = {(case, kind): control.shipped_emulator(case, kind, args.emulator_dir)
                for case in args.cases for kind in args.features}  # fmt: skip
    except control.ControlError as exc:
        raise SystemExit(f"{exc} (or drop that case or kind: --cases, --features)") from exc
    first = next(iter(emus.values()))
    model = control.emulator_vehicle(first)
    grid = Grid.over(first)
    noise = {case: 0.0 for case in args.cases}
    if "B" in noise:
        noise["B"] = control.emulator_noise_std(emus[("B", args.features[0])]) or 0.0
    for (case, kind), emu in emus.items():
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error", control.ControlWarning)
                control.check_emulator(emu, model=model, noise_std=noise[case])
        except (control.EmulatorMismatchError, control.ControlWarning) as exc:
            raise SystemExit(f"emulator {case}/{kind} does not match the others: {exc}") from exc
        if Grid.over(emu) != grid:
            raise SystemExit(
                f"emulator {case}/{kind} does not match the others: its domain {emu.domain} "
                f"differs from {first.domain}"
            )
    return emus, model, noise.get("B", 1.0), grid


def scatter_at(scatter: control.BlockScatter, v: float) -> np.ndarray:
    """Sigma(v) (K, K): the block scatter interpolated linearly in speed, as the likelihood does."""
    flat = scatter.cov.reshape(scatter.speed.size, -1)
    cols = [np.interp(v, scatter.speed, flat[:, k]) for k in range(flat.shape[1])]
    return np.array(cols).reshape(scatter.cov.shape[1:])


def max_likelihood(loglik: np.ndarray, log_gd: np.ndarray) -> tuple[float, bool]:
    """(GD at the maximum of loglik on the grid, refined by a parabola; at the grid's edge?)."""
    i = int(np.argmax(loglik))
    if i == 0 or i == log_gd.size - 1:
        return float(np.exp(log_gd[i])), True
    a, b, c = loglik[i - 1 : i + 2]
    den = a - 2 * b + c
    step = 0.5 * (a - c) / den if den < 0 else 0.0
    return float(np.exp(log_gd[i] + step * (log_gd[1] - log_gd[0]))), False


def ml_with_bootstrap(parts: np.ndarray, log_gd, rng) -> tuple[float, float, bool]:
    """(relative-to-1 GD at the ML of the summed parts, bootstrap SE of it, at the edge) where
    ``parts`` (n, G) are log-likelihoods of resampling units (batches of blocks, windows)."""
    gd_ml, edge = max_likelihood(parts.sum(axis=0), log_gd)
    boot = [
        max_likelihood(parts[rng.integers(0, len(parts), len(parts))].sum(axis=0), log_gd)[0]
        for _ in range(N_BOOT)
    ]
    return gd_ml, float(np.std(boot)), edge


@dataclass
class Cell:
    """One cell's result (``z``: per output; bias and se relative, e.g. 0.05 = 5%)."""

    v: float
    gd: float
    z: np.ndarray
    chi2: float
    p: float
    spread: float  # var ratio (band) or sd ratio (window)
    bias: float
    se: float
    edge: bool
    lin: float
    lin_se: float
    emu_sd: float  # the emulator's own sd of its mean at the cell, as a linearised GD error

    @property
    def mark(self) -> str:
        return ("*" if abs(self.bias) > 2 * self.se else " ") + ("|" if self.edge else " ")

    @property
    def lin_mark(self) -> str:
        return "*" if abs(self.lin) > 2 * self.lin_se else " "

    @property
    def beyond_emulator(self) -> bool:
        """Whether the linearised bias exceeds twice its Monte-Carlo se and the emulator's own
        sd combined: an error the emulator does not claim (misfit rather than uncertainty)."""
        return abs(self.lin) > 2 * np.hypot(self.lin_se, self.emu_sd)


def slope(emu, v: float, gd: float, h: float = 0.02) -> np.ndarray:
    """d mean / d log GD (K,) of ``emu.predict_mean`` at (v, GD), central within the domain."""
    lo, hi = emu.domain["GD"]
    a, b = max(gd * np.exp(-h), lo), min(gd * np.exp(h), hi)
    mean = emu.predict_mean([v, v], [a, b])
    return (mean[1] - mean[0]) / np.log(b / a)


def mean_cov(emu, v: float, gd: float) -> np.ndarray:
    """The emulator's own predictive covariance (K, K) of its mean at (v, GD), native units: the
    GP's variance of each principal component's weight at the point estimate (no nugget)
    through the basis, y_sd^2 K diag(var_w) K'."""
    pred = gpmsa.emulator_prediction(emu, [[v]], [[gd]], draws=False, resid=False, seed=0)
    basis = pred.K * np.reshape(pred.y_sd, (-1, 1))
    return basis @ np.diag(pred.var_w[0, 0]) @ basis.T


def linearised(
    d: np.ndarray, g: np.ndarray, w: np.ndarray, cov_d: np.ndarray, width: float
) -> tuple[float, float]:
    """(relative GD bias, its se) of the weighted least-squares step g' W d / (g' W g) in
    log GD, W = the likelihood's inverse covariance, cov_d the covariance of d; (NaN, NaN)
    where the emulator is too flat in GD to linearise: a step or se beyond ``width``, the
    domain's width in log GD (the window feature saturates at high GD)."""
    wg = w @ g
    den = float(g @ wg)
    if not den > 0:
        return np.nan, np.nan
    step, step_se = float(wg @ d) / den, float(np.sqrt(wg @ cov_d @ wg)) / den
    if not (abs(step) <= width and step_se <= width):
        return np.nan, np.nan
    return float(np.expm1(step)), step_se * float(np.exp(step))


def band_cells(case: str, emu, c, grid: Grid, rng) -> list[Cell]:
    om = control.ObservationModel(emu, n_grid=N_GRID)
    v_hi = om.speed_range[1]
    log_gd = np.log(om.gd)
    width = float(log_gd[-1] - log_gd[0])
    accel = c.accel if case == "A" else c.accel_measured
    spec = control.emulator_feature(emu)
    out = []
    for v in grid.speeds:
        sigma = scatter_at(om.scatter, v)
        weight = np.linalg.inv(sigma)  # the likelihood's, for the linearised bias
        for gd in grid.gds:
            runs = np.flatnonzero(c.ok & (c.v == v) & (c.gd == gd))
            st = block_statistics(accel[runs], spec, batch=BATCH)
            n_batch = st.features.shape[1] // BATCH
            feats = st.features[:, : n_batch * BATCH].reshape(-1, spec.dim)
            n = feats.shape[0]
            mu = emu.predict_mean([min(v, v_hi)], [gd])
            d = feats.mean(axis=0) - mu[0]
            cell_cov = st.cov.mean(axis=0)
            z = d / np.sqrt(np.diag(cell_cov) / n)
            chi2 = float(d @ np.linalg.solve(sigma / n, d))
            loglik = np.array([om.loglik(y, v) for y in feats])  # (n, G)
            parts = loglik.reshape(-1, BATCH, loglik.shape[1]).sum(axis=1)
            gd_ml, se, edge = ml_with_bootstrap(parts, log_gd, rng)
            g = slope(emu, min(v, v_hi), gd)
            lin = linearised(d, g, weight, cell_cov / n, width)
            emu_sd = linearised(d, g, weight, mean_cov(emu, min(v, v_hi), gd), width)[1]
            out.append(
                Cell(v, gd, z, chi2, float(stats.chi2.sf(chi2, spec.dim)),
                     float(np.mean(np.diag(cell_cov) / np.diag(sigma))), gd_ml / gd - 1,
                     se / gd, edge, *lin, emu_sd)
            )  # fmt: skip
    return out


def window_cells(case: str, emu, c, grid: Grid, rng) -> list[Cell]:
    v_hi, (g_lo, g_hi) = emu.domain["v"][1], emu.domain["GD"]
    gd_grid = np.geomspace(g_lo, g_hi, N_GRID)
    log_gd = np.log(gd_grid)
    width = float(log_gd[-1] - log_gd[0])
    accel = c.accel if case == "A" else c.accel_measured
    out = []
    for v in grid.speeds:
        v_in = min(v, v_hi)
        mean_g, var_g = emu.predict(np.full(N_GRID, v_in), gd_grid)  # nugget included
        for gd in grid.gds:
            runs = np.flatnonzero(c.ok & (c.v == v) & (c.gd == gd))
            n_win = accel.shape[1] // WINDOW
            windows = accel[runs, : n_win * WINDOW].reshape(-1, WINDOW)
            y = np.array([control.window_feature(w, "log_var") for w in windows])
            mu, var = emu.predict([v_in], [gd])
            z = (y.mean() - mu[0, 0]) / (y.std(ddof=1) / np.sqrt(y.size))
            loglik = -0.5 * (y[:, None] - mean_g[None, :, 0]) ** 2 / var_g[
                None, :, 0
            ] - 0.5 * np.log(var_g[None, :, 0])
            gd_ml, se, edge = ml_with_bootstrap(loglik, log_gd, rng)
            d, g = np.array([y.mean() - mu[0, 0]]), slope(emu, v_in, gd)
            lin = linearised(d, g, np.eye(1), np.array([[y.var(ddof=1) / y.size]]), width)
            emu_sd = linearised(d, g, np.eye(1), mean_cov(emu, v_in, gd), width)[1]
            out.append(
                Cell(v, gd, np.array([z]), float(z**2), float(stats.chi2.sf(z**2, 1)),
                     float(y.std(ddof=1) / np.sqrt(var[0, 0])), gd_ml / gd - 1, se / gd, edge,
                     *lin, emu_sd)
            )  # fmt: skip
    return out


def print_cells(title: str, cells: list[Cell], grid: Grid, band: bool) -> None:
    print(f"\n{title} ({load()})")
    if band:
        zs = "".join(f"{'z' + str(k + 1):>6}" for k in range(cells[0].z.size))
        head = f"{'v':>5}{'GD':>5} {zs} {'chi2':>7}{'p':>8}{'var':>6}"
    else:
        head = f"{'v':>5}{'GD':>5} {'z':>6} {'p':>8}{'sd':>6}"
    print(head + f" {'GD bias %':>10}{'se %':>6} {'lin %':>7}{'se %':>6}{'emu %':>6}")
    for cell in cells:
        zs = "".join(f"{z:6.1f}" for z in cell.z)
        mid = f" {cell.chi2:7.1f}{cell.p:8.1e}" if band else f"{cell.p:9.1e}"
        print(
            f"{cell.v:5.2f}{cell.gd:5.0f} {zs}{mid}{cell.spread:6.2f} "
            f"{100 * cell.bias:+9.1f}{cell.mark}{100 * cell.se:5.1f} "
            f"{100 * cell.lin:+6.1f}{cell.lin_mark}{100 * cell.lin_se:5.1f}"
            f"{100 * cell.emu_sd:6.1f}"
        )
    print("\nrelative GD bias, % (* > 2 se; | maximum on the domain's edge); rows GD, columns v")
    print(f"{'GD':>5} " + "".join(f"{v:>9.2f}" for v in grid.speeds))
    for gd in grid.gds:
        row = [c for c in cells if c.gd == gd]
        print(f"{gd:5.0f} " + "".join(f"{100 * c.bias:+7.1f}{c.mark}" for c in row))
    print("linearised (not truncated at the edges), % (* > 2 se; nan: the emulator is too flat "
          "in GD there to linearise, its step beyond the domain's width)")  # fmt: skip
    for gd in grid.gds:
        row = [c for c in cells if c.gd == gd]
        print(f"{gd:5.0f} " + "".join(f"{100 * c.lin:+7.1f}{c.lin_mark} " for c in row))
    flagged = sum(abs(c.bias) > 2 * c.se for c in cells)
    flagged_lin = sum(abs(c.lin) > 2 * c.lin_se for c in cells)
    inner = [c for c in cells if grid.gds[0] < c.gd < grid.gds[-1]]

    def rms(x) -> float:  # over the cells that have a value (NaN: too flat to linearise)
        x = np.asarray(x, dtype=float)
        return 100 * float(np.sqrt(np.mean(np.square(x[np.isfinite(x)]))))

    print(
        f"ML: {flagged} of {len(cells)} cells beyond 2 se (about {0.0455 * len(cells):.0f} by "
        f"chance); over GD {grid.gds[1]:g}-{grid.gds[-2]:g}, RMS bias "
        f"{rms([c.bias for c in inner]):.1f}% against RMS se {rms([c.se for c in inner]):.1f}%"
    )
    flat = sum(not np.isfinite(c.lin) for c in cells)
    print(
        f"linearised: {flagged_lin} of {len(cells)} cells beyond 2 se"
        + (f" ({flat} too flat to linearise, left out of the RMS)" if flat else "")
        + "; RMS bias "
        f"{rms([c.lin for c in cells]):.1f}% against RMS se {rms([c.lin_se for c in cells]):.1f}%"
        f" (all cells); per speed "
        + ", ".join(f"{v:.3g}: {rms([c.lin for c in cells if c.v == v]):.1f}%" for v in grid.speeds)
    )
    print("the emulator's own sd of its mean, as a linearised GD error, % (+ where the linearised "
          "bias exceeds 2 x the root of its se^2 + this^2)")  # fmt: skip
    for gd in grid.gds:
        row = [c for c in cells if c.gd == gd]
        marks = "".join(f"{100 * c.emu_sd:7.1f}{'+' if c.beyond_emulator else ' '} " for c in row)
        print(f"{gd:5.0f} " + marks)
    print(
        f"{sum(c.beyond_emulator for c in cells)} of {len(cells)} cells beyond what the emulator "
        f"claims (about {0.0455 * len(cells):.0f} by chance); RMS emulator sd "
        f"{rms([c.emu_sd for c in cells]):.1f}%, per speed "
        + ", ".join(
            f"{v:.3g}: {rms([c.emu_sd for c in cells if c.v == v]):.1f}%" for v in grid.speeds
        )
    )


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--quick", action="store_true", help="one road per cell instead of --roads (63 drives)"
    )
    parser.add_argument("--roads", type=int, default=3, help="roads driven per cell (full run)")
    parser.add_argument("--keep-s", type=float, default=60.0, help="seconds of driving per road")
    parser.add_argument(
        "--seed", type=int, default=31337,
        help="campaign seed of the held-aside roads (their seeds are checked against training)",
    )  # fmt: skip
    parser.add_argument("--boot-seed", type=int, default=0, help="seed of the bootstraps")
    parser.add_argument(
        "--workers", type=int, default=2, help="worker processes of the drives (at most 2 here)"
    )
    parser.add_argument(
        "--cache-dir", default="out/bench_campaigns",
        help="folder caching the drives ('' for none)",
    )  # fmt: skip
    parser.add_argument(
        "--emulator-dir", default=None,
        help="score the emulators in this folder (train_emulator.py --emulator-dir) instead of "
        "the shipped ones",
    )  # fmt: skip
    parser.add_argument(
        "--cases", nargs="+", default=["A", "B"], choices=["A", "B"], help="cases to score"
    )
    parser.add_argument(
        "--features", nargs="+", default=["band", "window"], choices=["band", "window"],
        help="emulators to score",
    )  # fmt: skip
    args = parser.parse_args(argv)
    if args.emulator_dir is not None and not args.emulator_dir.strip():
        parser.error("argument --emulator-dir: an empty path: give a folder name")
    roads = 1 if args.quick else args.roads
    min_keep_s = 2 * BATCH * 125 / RATE_HZ
    if roads < 1:
        parser.error(f"--roads must be >= 1, got {roads}")
    if not min_keep_s <= args.keep_s < np.inf:  # NaN fails too
        parser.error(
            f"--keep-s must be >= {min_keep_s:.2f} s (two batches of 8 blocks) and finite, got "
            f"{args.keep_s}"
        )
    for option, value in (("--seed", args.seed), ("--boot-seed", args.boot_seed)):
        if value < 0:
            parser.error(f"{option} must be >= 0, got {value}")
    if args.seed >= MAX_SEED:
        parser.error(f"--seed must be < 2**128 (the seeds' range), got {args.seed}")
    n_drives = N_SPEEDS * N_GDS * roads
    try:  # the campaign's design and traces (its own check, made before the design is built)
        vehicle.checks.memory(
            (64.0 + 16.0 * round(args.keep_s * RATE_HZ)) * n_drives,
            f"--roads {roads} and --keep-s {args.keep_s:g}: the traces of {n_drives} drives",
        )  # fmt: skip
    except vehicle.VehicleError as exc:
        parser.error(str(exc))
    if args.cache_dir:
        try:  # a file of that name: refused now, not by the campaign
            Path(args.cache_dir).mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            parser.error(f"--cache-dir {args.cache_dir!r}: cannot make that folder: "
                         f"{exc.strerror or exc}")  # fmt: skip
    if args.workers < 1:
        parser.error(f"--workers must be >= 1, got {args.workers}")

    tic = time.perf_counter()
    emus, model, noise_std, grid = emulators_to_score(args)
    c = drive(grid, roads, args.keep_s, args.seed, args.workers, args.cache_dir or None, model,
              noise_std)  # fmt: skip
    train = training_seeds(next(iter(emus.values())))
    overlap = np.intersect1d(c.seed, train)
    if overlap.size:
        raise SystemExit(f"road seeds {overlap} were in the training campaign: use another --seed")
    print(
        f"{c.v.size} drives ({len(grid.speeds)} x {len(grid.gds)} cells x {roads} roads x "
        f"{args.keep_s:g} s, campaign seed {args.seed}; none of the {train.size} training road "
        f"seeds) in {time.perf_counter() - tic:.0f} s; {int(np.sum(~c.ok))} failed; {load()}"
    )
    if not c.ok.all():
        for v, gd, s in zip(c.v[~c.ok], c.gd[~c.ok], c.status[~c.ok], strict=True):
            print(f"  failed: v={v:g} GD={gd:g}: {s}")
    rng = np.random.default_rng(args.boot_seed)
    for case in args.cases:
        noise = "noise-free" if case == "A" else f"N(0, {noise_std:g}^2) noise"
        if "band" in args.features:
            outputs = control.emulator_feature(emus[(case, "band")])
            print_cells(
                f"band emulator, case {case} ({noise}): per cell, z per output "
                f"({', '.join(outputs.names())})",
                band_cells(case, emus[(case, "band")], c, grid, rng),
                grid,
                band=True,
            )
        if "window" in args.features:
            print_cells(
                f"window emulator (paper's log f of 1,000 samples), case {case} ({noise})",
                window_cells(case, emus[(case, "window")], c, grid, rng),
                grid,
                band=False,
            )
    print(f"\ntotal {time.perf_counter() - tic:.0f} s; {load()}")


if __name__ == "__main__":
    main()
