"""Which observation of a block of accelerations carries the most information about GD per second.

    PYTHONPATH=. python benchmarks/feature_information.py             # 2 x 198 runs x 60 s
    PYTHONPATH=. python benchmarks/feature_information.py --quick     # 2 x 60 runs x 30 s
    PYTHONPATH=. python benchmarks/feature_information.py --help

Features of one block of B samples of front-axle vertical acceleration (120 Hz), B in
{125, 250, 500, 1000}, with and without N(0, 1) sensor noise:

- ``log_var``: log f, f = var of the block (the paper's feature, eq. 5; B = 1000 is the paper's);
- ``log_pgram``: the mean log periodogram (Hann window) over the bins in [1.5, 60] Hz;
- ``whittle``: log c_hat, c_hat = mean_j I(f_j) / S_ref(f_j; v), the maximum-likelihood (Whittle)
  scale of a reference spectrum S_ref: the average periodogram of the training runs near speed v,
  each rescaled to GD_ref = 400 (Gaussian kernel weights in speed, bandwidth 0.15 m/s, and in
  log GD about GD_ref, bandwidth 0.3; a training run's own blocks are left out of its reference);
- ``bands``: the log band-power vector of `control.block_features` with
  ``FeatureSpec(block_samples=B, quantiles=())`` (8 bands 1.5-60 Hz, DPSS NW = 2, 3 tapers),
  multivariate (the shipped feature adds two quantiles: section 4).

Method (held out): two independent campaigns (`vehicle.run_campaign`, Latin hypercube over v in
[0.5, 2] m/s and GD in [200, 600], other seeds), one for training and one for testing. On the
training campaign, per feature and B, the mean of each output is a cubic polynomial in
(log v, log GD) fitted by least squares to the runs' mean features, and the block-to-block
covariance Sigma(v) is the long-run covariance (batch means over 1,000 samples, as
`control.training`) averaged with Gaussian kernel weights in speed (bandwidth 0.15 m/s). On each
test run with GD in [250, 550] (the prior truncates estimates near the domain's edges; the
tables use only runs away from them) the blocks of T seconds of driving (T = 500, 1,000 and 2,000
samples: 4.2, 8.3, 16.7 s; disjoint stretches, as many as the run holds) are pooled into a
Gaussian likelihood on a grid of log GD with a flat prior on [log 200, log 600].

Printed (with the load average): per noise case, feature and B, for each T the information per
second J = 1 / (RMSE^2 T) of the posterior-mean log GD (with its bootstrap standard error over
test runs), the RMSE in log GD and the coverage of the central 90% interval; J_fit, the
information per second the fitted model itself claims (Fisher information of the cubic mean under
Sigma(v), averaged over the test runs as 1 / mean(1 / I)); the ratio of each J to that of log f at
B = 1000 (the paper's); lack of fit (mean over training runs of the squared standardised
residual of the run mean about the cubic, per output; 1 when the cubic and Sigma explain the run
means); per speed band (v < 1, 1-1.5, > 1.5 m/s) J at T = 8.3 s. The prior alone (posterior mean
= prior mean) has the RMSE printed as ``prior-only``: a J near 1 / (that^2 T) is the prior's, not
the feature's. Last, variants of the band vector (`BAND_VARIANTS`: the block's quantiles, of
which the shipped feature adds the 90% and 98%; narrower bands, a lower first band, other
tapers, shorter blocks; the vector plus the block's skewness, log kurtosis or flight time),
J and J_lin at T ~ 8.3 s: is there information the band vector leaves out?

Campaign runs are cached under ``--cache-dir`` (keyed by their settings), so a second call only
recomputes the features (a few seconds).
"""

from __future__ import annotations

import argparse
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from _host import load_average
from scipy.linalg import cho_factor, cho_solve
from scipy.signal.windows import hann

import vehicle
from control import FeatureSpec, block_features
from control.feature import STANDARD_GRAVITY
from gpmsa.model.data import MAX_SEED

RATE_HZ = 120.0
V_RANGE = (0.5, 2.0)
GD_RANGE = (200.0, 600.0)
BLOCKS = (125, 250, 500, 1000)
FEATURES = ("log_var", "log_pgram", "whittle", "bands")
SPANS = (500, 1000, 2000)  # samples of driving pooled per estimate
PAPER = ("log_var", 1000)
BAND_HZ = (1.5, 60.0)
GD_REF = 400.0
SPEED_BW = 0.15  # m/s, kernel bandwidth of Sigma(v) and S_ref
LOG_GD_BW = 0.3  # kernel bandwidth of S_ref in log GD
BATCH_SAMPLES = 1000  # samples per batch of the long-run covariance
SPEED_BANDS = ((0.0, 1.0, "v<1"), (1.0, 1.5, "1-1.5"), (1.5, 9.9, "v>1.5"))
N_GRID = 401
NARROW_BANDS_HZ = (1.5, 3, 4.5, 6, 7, 8.5, 10, 12, 14, 17, 20, 25, 30, 37, 45, 52, 60)
BANDS_ONLY = {"quantiles": ()}
BAND_VARIANTS: dict[str, tuple[int, dict, str | None]] = {  # name: (block samples, FeatureSpec
    # fields, extra moment or None)
    "8 bands": (125, BANDS_ONLY, None),
    "+ quantiles 0.9, 0.98 (shipped)": (125, {}, None),
    "+ quantiles 0.02, 0.1, 0.9, 0.98": (125, {"quantiles": (0.02, 0.1, 0.9, 0.98)}, None),
    "+ quantiles 0.02, 0.1": (125, {"quantiles": (0.02, 0.1)}, None),
    "+ quantile 0.5 (median)": (125, {"quantiles": (0.5,)}, None),
    "16 narrower bands": (125, {**BANDS_ONLY, "bands_hz": NARROW_BANDS_HZ}, None),
    "first band from 0.9 Hz": (
        125,
        {**BANDS_ONLY, "bands_hz": (0.9, 2.5, 4.5, 7, 10, 14, 20, 30, 45, 60)},
        None,
    ),
    "NW 3, 5 tapers": (125, {**BANDS_ONLY, "taper_nw": 3.0, "n_tapers": 5}, None),
    "NW 1.5, 2 tapers": (125, {**BANDS_ONLY, "taper_nw": 1.5, "n_tapers": 2}, None),
    "+ skewness": (125, BANDS_ONLY, "skewness"),
    "+ log kurtosis": (125, BANDS_ONLY, "log_kurtosis"),
    "+ flight time": (125, BANDS_ONLY, "flight_time"),
    "100-sample blocks": (100, BANDS_ONLY, None),
    "80-sample blocks": (80, BANDS_ONLY, None),
    "64-sample blocks": (64, BANDS_ONLY, None),
}

FIRST_VARIANT = next(iter(BAND_VARIANTS))
"""The 8-band vector: the variants' J is given as a ratio to its J."""


def singular(what: str, n_runs: int, keep_s: float) -> str:
    """Why a feature's block covariance Sigma(v) cannot be factorised (``what``: the
    feature, or "" in a table row): the runs near a speed hold fewer batch means than it has
    outputs."""
    return (
        (f"{what}: " if what else "")
        + f"Sigma(v) singular: {n_runs} runs x {keep_s:g} s hold too few batches of "
        f"{BATCH_SAMPLES} samples for its outputs (raise --n-runs or --keep-s)"
    )


def lhs(n: int, seed: int) -> np.ndarray:
    """(n, 2) Latin-hypercube design [v, GD] over the paper's domain."""
    return vehicle.lhs_design(n, V_RANGE, GD_RANGE, seed=seed)


def campaign(n: int, keep_s: float, seed: int, workers: int, cache_dir: str | None):
    """A campaign of n runs keeping keep_s seconds of accelerations (failed runs left out)."""
    with ProcessPoolExecutor(max_workers=workers) as pool:
        c = vehicle.run_campaign(
            lhs(n, seed), seed=seed, keep_s=keep_s, executor=pool, progress=False,
            cache_dir=cache_dir,
        )  # fmt: skip
    assert c.accel is not None and c.accel_measured is not None, "keep_s > 0 keeps them"
    ok = c.ok & np.all(np.isfinite(c.accel_measured), axis=1)
    return c.v[ok], c.gd[ok], {"A": c.accel[ok], "B": c.accel_measured[ok]}


# --- features ------------------------------------------------------------------------------------


def blocks_of(accel: np.ndarray, B: int) -> np.ndarray:
    """(runs, n_blocks, B) disjoint blocks of each run."""
    n = accel.shape[1] // B
    return accel[:, : n * B].reshape(accel.shape[0], n, B)


def periodogram(blocks: np.ndarray) -> np.ndarray:
    """Hann-windowed one-sided periodogram (.., bins in BAND_HZ), (m/s^2)^2/Hz."""
    B = blocks.shape[-1]
    w = hann(B, sym=False)
    x = (blocks - blocks.mean(axis=-1, keepdims=True)) * w
    f = np.fft.rfftfreq(B, 1.0 / RATE_HZ)
    sel = (f >= BAND_HZ[0]) & (f <= BAND_HZ[1])
    return 2.0 * np.abs(np.fft.rfft(x, axis=-1)[..., sel]) ** 2 / (RATE_HZ * np.sum(w**2))


def kernel(v_eval: np.ndarray, v_runs: np.ndarray) -> np.ndarray:
    """(n_eval, n_runs) Gaussian weights in speed (rows unnormalised)."""
    return np.exp(-0.5 * ((v_eval[:, None] - v_runs[None, :]) / SPEED_BW) ** 2)


def reference_spectrum(v_eval, v_train, gd_train, mean_pgram, leave_out: bool) -> np.ndarray:
    """S_ref(f; v) (n_eval, bins): training runs' mean periodograms rescaled to GD_REF, kernel
    weighted in speed and in log GD about GD_REF (the evaluated run itself left out)."""
    w = kernel(v_eval, v_train) * np.exp(-0.5 * (np.log(gd_train / GD_REF) / LOG_GD_BW) ** 2)
    if leave_out:
        np.fill_diagonal(w, 0.0)
    scaled = mean_pgram * (GD_REF / gd_train)[:, None]
    return (w @ scaled) / w.sum(axis=1, keepdims=True)


def features(blocks: np.ndarray, B: int, pgram: np.ndarray, s_ref: np.ndarray | None):
    """{name: (runs, n_blocks, K)} of every feature."""
    out = {
        "log_var": np.log(np.var(blocks, axis=-1))[..., None],
        "log_pgram": np.mean(np.log(pgram), axis=-1)[..., None],
        "bands": band_vector(blocks, FeatureSpec(block_samples=B, quantiles=())),
    }
    if s_ref is not None:
        out["whittle"] = np.log(np.mean(pgram / s_ref[:, None, :], axis=-1))[..., None]
    return out


def moment(blocks: np.ndarray, name: str) -> np.ndarray:
    """(runs, n_blocks, 1) skewness, log kurtosis or flight time of each block (lift-off makes
    the acceleration non-Gaussian: what a spectrum cannot see). The flight time is log(1 + the
    samples below -0.9 g): a wheel in the air reads -g."""
    if name == "flight_time":
        return np.log1p(np.sum(blocks < -0.9 * STANDARD_GRAVITY, axis=-1))[..., None]
    d = blocks - blocks.mean(axis=-1, keepdims=True)
    var = np.mean(d**2, axis=-1)
    if name == "skewness":
        return (np.mean(d**3, axis=-1) / var**1.5)[..., None]
    return np.log(np.mean(d**4, axis=-1) / var**2)[..., None]


def band_vector(blocks: np.ndarray, spec: FeatureSpec) -> np.ndarray:
    """(runs, n_blocks, K) `control.block_features` of every block."""
    return block_features(blocks.reshape(-1, blocks.shape[-1]), spec).reshape(*blocks.shape[:2], -1)


def band_variant(accel: np.ndarray, B: int, fields: dict, extra: str | None) -> np.ndarray:
    """(runs, n_blocks, K) a variant of the band vector: other bands, tapers or block length,
    or the band vector plus quantiles or one moment."""
    blocks = blocks_of(accel, B)
    out = band_vector(blocks, FeatureSpec(block_samples=B, **fields))
    return out if extra is None else np.concatenate([out, moment(blocks, extra)], axis=-1)


# --- the model: cubic mean, kernel-weighted long-run covariance -----------------------------------


def poly(log_v: np.ndarray, log_gd: np.ndarray) -> np.ndarray:
    """(n, 10) cubic monomials of (log v, log GD), centred and scaled to [-1, 1]."""
    a = (log_v - np.log(1.0)) / np.log(2.0)
    b = (log_gd - np.log(346.4)) / np.log(3.0) * 2
    return np.stack([a**i * b**j for i in range(4) for j in range(4 - i)], axis=-1)


def dpoly_dlog_gd(log_v: np.ndarray, log_gd: np.ndarray) -> np.ndarray:
    """(n, 10) derivative of `poly` with respect to log GD."""
    a = (log_v - np.log(1.0)) / np.log(2.0)
    b = (log_gd - np.log(346.4)) / np.log(3.0) * 2
    s = 2 / np.log(3.0)
    cols = [
        (j * a**i * b ** max(j - 1, 0) * s) if j else np.zeros_like(a)
        for i in range(4)
        for j in range(4 - i)
    ]
    return np.stack(cols, axis=-1)


def long_run_cov(feats: np.ndarray, batch: int) -> np.ndarray:
    """(runs, K, K) long-run covariance per run: batch means of `batch` consecutive blocks."""
    dev = feats - feats.mean(axis=1, keepdims=True)
    n_batch = feats.shape[1] // batch
    means = dev[:, : n_batch * batch].reshape(feats.shape[0], n_batch, batch, -1).mean(axis=2)
    return np.einsum("rbi,rbj->rij", means, means) / (n_batch - 1) * batch


@dataclass
class Model:
    """Fitted mean (cubic coefficients (10, K)) and per-run covariances for Sigma(v)."""

    coef: np.ndarray
    v_train: np.ndarray
    cov_train: np.ndarray
    lack_of_fit: float

    def sigma(self, v: np.ndarray) -> np.ndarray:
        """(n, K, K) kernel-weighted long-run covariance at speeds v."""
        w = kernel(np.atleast_1d(v), self.v_train)
        w /= w.sum(axis=1, keepdims=True)
        return np.einsum("sr,rij->sij", w, self.cov_train)

    def mean(self, v: float, log_gd: np.ndarray) -> np.ndarray:
        """(G, K) mean feature at speed v on the log-GD grid."""
        return poly(np.full(log_gd.size, np.log(v)), log_gd) @ self.coef


def fit(v: np.ndarray, gd: np.ndarray, feats: np.ndarray, batch: int) -> Model:
    """Least-squares cubic mean of the runs' mean features; per-run long-run covariances."""
    X = poly(np.log(v), np.log(gd))
    run_mean = feats.mean(axis=1)
    coef, *_ = np.linalg.lstsq(X, run_mean, rcond=None)
    cov = long_run_cov(feats, batch)
    model = Model(coef, v, cov, np.nan)
    resid = run_mean - X @ coef
    sig = model.sigma(v) / feats.shape[1]
    d2 = [r @ np.linalg.solve(s, r) for r, s in zip(resid, sig, strict=True)]
    dof = 1.0 - X.shape[1] / v.size  # residuals of a least-squares fit are smaller
    # (10 runs: the cubic goes through every run mean, and its lack of fit is unknown)
    model.lack_of_fit = float(np.mean(d2) / feats.shape[2] / dof) if dof > 0 else np.nan
    return model


# --- held-out estimates ---------------------------------------------------------------------------


@dataclass
class Scores:
    """Per estimate (one stretch of T seconds): error of the posterior-mean log GD, interval
    covered, error of the linearised estimate (see `estimates`), run index, speed."""

    err: np.ndarray
    covered: np.ndarray
    err_lin: np.ndarray
    run: np.ndarray
    speed: np.ndarray

    def subset(self, sel: np.ndarray) -> Scores:
        return Scores(*(getattr(self, k)[sel] for k in self.__dataclass_fields__))


def estimates(model: Model, v, gd, feats: np.ndarray, per: int, log_grid) -> Scores:
    """Estimates of log GD from each stretch of ``per`` blocks of each run.

    The posterior (flat prior on ``log_grid``) gives the posterior mean and the 90% interval.
    The linearised estimate is the generalised-least-squares step from the truth,
    g' S^-1 (y_bar - mu(log GD_true)) / (g' S^-1 g), g = d mu / d log GD: no prior and no grid
    bounds, so its error measures the information the feature holds (and the fit's bias), not
    the prior's.
    """
    err, cov, lin, run, spd = [], [], [], [], []
    n_seg = feats.shape[1] // per
    for r in range(v.size):
        mu = model.mean(float(v[r]), log_grid)  # (G, K)
        chol = cho_factor(model.sigma(v[r])[0], lower=True)
        y = feats[r, : n_seg * per]  # (n, K)
        dev = y[:, None, :] - mu[None, :, :]  # (n, G, K)
        white = cho_solve(chol, dev.reshape(-1, dev.shape[2]).T).T.reshape(dev.shape)
        d2 = np.einsum("ngk,ngk->ng", dev, white)
        loglik = -0.5 * d2.reshape(n_seg, per, -1).sum(axis=1)  # (n_seg, G)
        post = np.exp(loglik - loglik.max(axis=1, keepdims=True))
        post /= post.sum(axis=1, keepdims=True)
        mean = post @ log_grid
        cdf = np.cumsum(post, axis=1)
        lo = log_grid[np.argmax(cdf >= 0.05, axis=1)]
        hi = log_grid[np.argmax(cdf >= 0.95, axis=1)]
        truth = np.log(gd[r])
        g = dpoly_dlog_gd(np.log(v[r : r + 1]), np.array([truth]))[0] @ model.coef  # (K,)
        s_g = cho_solve(chol, g)
        ybar = y.reshape(n_seg, per, -1).mean(axis=1)
        mu_true = poly(np.log(v[r : r + 1]), np.array([truth]))[0] @ model.coef
        err.append(mean - truth)
        cov.append((lo <= truth) & (truth <= hi))
        lin.append((ybar - mu_true) @ s_g / (g @ s_g))
        run.append(np.full(n_seg, r))
        spd.append(np.full(n_seg, v[r]))
    return Scores(*(np.concatenate(a) for a in (err, cov, lin, run, spd)))


def fisher_j(model: Model, v, gd, B: int) -> float:
    """Information per second about log GD the fitted model claims, g' Sigma^-1 g / block
    duration, median over the runs (v, GD)."""
    g = dpoly_dlog_gd(np.log(v), np.log(gd)) @ model.coef  # (n, K)
    sig = model.sigma(v)
    info = np.array([d @ np.linalg.solve(s, d) for d, s in zip(g, sig, strict=True)])
    return float(np.median(info * RATE_HZ / B))


MEDIAN_CHI2_1 = 0.4549364  # median of a chi-square(1) variable


def info_per_s(s: Scores, t_s: float, rng: np.random.Generator, n_boot: int = 300) -> dict:
    """J (1/(RMSE^2 T)) with its bootstrap SE over test runs, RMSE, coverage, and J_lin: the
    information per second of the linearised estimate, robust (from the median squared error,
    so that a few runs where a feature's slope vanishes do not dominate), with its SE."""

    def j_of(e):
        return 1.0 / (np.mean(e**2) * t_s)

    def jlin_of(e):
        return MEDIAN_CHI2_1 / (np.median(e**2) * t_s)

    runs = np.unique(s.run)
    idx = [np.flatnonzero(s.run == r) for r in runs]
    boot = []
    for _ in range(n_boot):
        pick = np.concatenate([idx[i] for i in rng.integers(0, runs.size, runs.size)])
        boot.append((j_of(s.err[pick]), jlin_of(s.err_lin[pick])))
    boot_j = np.array(boot)
    return {
        "J": j_of(s.err),
        "se": float(np.std(boot_j[:, 0])),
        "rmse": float(np.sqrt(np.mean(s.err**2))),
        "cov": float(np.mean(s.covered)),
        "Jlin": jlin_of(s.err_lin),
        "se_lin": float(np.std(boot_j[:, 1])),
    }


def paired_j_ratio(
    s: Scores,
    span: int,
    base: Scores,
    base_span: int,
    rng: np.random.Generator,
    n_boot: int = 1000,
) -> tuple[float, float]:
    """J of ``s`` over J of ``base`` (from the posterior-mean errors of their stretches of
    ``span`` and ``base_span`` samples), with its paired bootstrap SE: the same test runs are
    resampled for both."""
    runs = np.unique(base.run)
    mine = [np.flatnonzero(s.run == r) for r in runs]
    theirs = [np.flatnonzero(base.run == r) for r in runs]

    def ratio(picks: np.ndarray) -> float:
        a = np.concatenate([mine[i] for i in picks])
        b = np.concatenate([theirs[i] for i in picks])
        return float(np.mean(base.err[b] ** 2) * base_span / (np.mean(s.err[a] ** 2) * span))

    boot = [ratio(rng.integers(0, runs.size, runs.size)) for _ in range(n_boot)]
    return ratio(np.arange(runs.size)), float(np.std(boot))


def load() -> str:
    return "load average {:.2f} {:.2f} {:.2f}".format(*load_average())


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--quick",
        action="store_true",
        help="small campaigns (60 runs x 30 s each) for a first look",
    )
    parser.add_argument(
        "--n-runs", type=int, default=None, help="runs per campaign (default 198; --quick: 60)"
    )
    parser.add_argument(
        "--keep-s",
        type=float,
        default=None,
        help="seconds of driving kept per run (default 60; --quick: 30)",
    )
    parser.add_argument(
        "--train-seed",
        type=int,
        default=101,
        help="seed of the training campaign's design, roads and noise",
    )
    parser.add_argument(
        "--test-seed",
        type=int,
        default=202,
        help="seed of the test campaign (must differ from --train-seed)",
    )
    parser.add_argument(
        "--gd-band",
        type=float,
        nargs=2,
        default=(250.0, 550.0),
        help="test runs scored: GD in this range (away from the prior's edges)",
    )
    parser.add_argument(
        "--workers",
        type=int,
        default=2,
        help="worker processes of the campaigns (at most 2 on a shared machine)",
    )
    parser.add_argument(
        "--cache-dir",
        default="out/bench_campaigns",
        help="folder caching the campaign runs ('' for none)",
    )
    parser.add_argument("--seed", type=int, default=0, help="seed of the bootstrap")
    args = parser.parse_args(argv)
    if args.train_seed == args.test_seed:
        parser.error("--train-seed and --test-seed must differ (held-out test)")
    n_runs = (60 if args.quick else 198) if args.n_runs is None else args.n_runs
    keep_s = (30.0 if args.quick else 60.0) if args.keep_s is None else args.keep_s
    min_keep_s = max(SPANS) / RATE_HZ
    if n_runs < 10:
        parser.error(f"--n-runs must be >= 10 (a cubic mean per output), got {n_runs}")
    if not min_keep_s <= keep_s < np.inf:  # NaN fails too
        parser.error(
            f"--keep-s must be >= {min_keep_s:.2f} s (the longest stretch pooled) and finite, "
            f"got {keep_s}"
        )
    for option, value in (
        ("--train-seed", args.train_seed), ("--test-seed", args.test_seed), ("--seed", args.seed)
    ):  # fmt: skip
        if not 0 <= value < MAX_SEED:
            parser.error(f"{option} must be in [0, 2**128), got {value}")
    lo, hi = args.gd_band
    if not GD_RANGE[0] <= lo < hi <= GD_RANGE[1]:
        parser.error(f"--gd-band must lie in {list(GD_RANGE)} with low < high, got {lo:g} {hi:g}")
    if args.workers < 1:
        parser.error(f"--workers must be >= 1, got {args.workers}")
    try:  # each campaign's design and traces (its own check, before the campaigns)
        vehicle.checks.memory(
            (64.0 + 16.0 * round(keep_s * RATE_HZ)) * n_runs,
            f"--n-runs {n_runs} and --keep-s {keep_s:g}: a campaign's traces",
        )  # fmt: skip
    except vehicle.VehicleError as exc:
        parser.error(str(exc))
    cache = args.cache_dir or None
    if cache:
        try:  # a file of that name: refused now, not by the first campaign
            Path(cache).mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            parser.error(f"--cache-dir {cache!r}: cannot make that folder: {exc.strerror or exc}")

    tic = time.perf_counter()
    v_tr, gd_tr, acc_tr = campaign(n_runs, keep_s, args.train_seed, args.workers, cache)
    v_te, gd_te, acc_te = campaign(n_runs, keep_s, args.test_seed, args.workers, cache)
    print(f"campaigns: {v_tr.size} training + {v_te.size} test runs of {keep_s:g} s "
          f"(seeds {args.train_seed}, {args.test_seed}) in {time.perf_counter() - tic:.0f} s; "
          f"{load()}")  # fmt: skip
    scored = (gd_te >= args.gd_band[0]) & (gd_te <= args.gd_band[1])
    v_s, gd_s = v_te[scored], gd_te[scored]
    log_grid = np.linspace(np.log(GD_RANGE[0]), np.log(GD_RANGE[1]), N_GRID)
    prior_rmse = float(np.sqrt(np.mean((log_grid.mean() - np.log(gd_s)) ** 2)))
    print(f"scored test runs: {scored.sum()} with GD in [{args.gd_band[0]:g}, "
          f"{args.gd_band[1]:g}]; prior-only RMSE of log GD: {prior_rmse:.3f}")  # fmt: skip
    for B in BLOCKS:
        counts = FeatureSpec(block_samples=B, quantiles=())  # raises if a band has no bin
        f = np.fft.rfftfreq(B, 1 / RATE_HZ)
        e = counts.bands_hz
        n_bins = [int(np.sum((f >= lo) & (f < hi))) for lo, hi in zip(e[:-1], e[1:], strict=True)]
        n_bins[-1] += int(np.sum(f == e[-1]))
        print(f"  B = {B:4d}: frequency bins per band {n_bins}")

    rng = np.random.default_rng(args.seed)
    table: dict = {}
    lack: dict = {}
    jfit: dict = {}
    band_j: dict = {}
    for case in ("A", "B"):
        for B in BLOCKS:
            bl_tr, bl_te = blocks_of(acc_tr[case], B), blocks_of(acc_te[case], B)[scored]
            pg_tr, pg_te = periodogram(bl_tr), periodogram(bl_te)
            mean_pg = pg_tr.mean(axis=1)
            s_tr = reference_spectrum(v_tr, v_tr, gd_tr, mean_pg, leave_out=True)
            s_te = reference_spectrum(v_s, v_tr, gd_tr, mean_pg, leave_out=False)
            f_tr = features(bl_tr, B, pg_tr, s_tr)
            f_te = features(bl_te, B, pg_te, s_te)
            batch = max(1, BATCH_SAMPLES // B)
            for name in FEATURES:
                try:
                    model = fit(v_tr, gd_tr, f_tr[name], batch)
                    jfit[case, name, B] = fisher_j(model, v_s, gd_s, B)
                    for span in SPANS:
                        if span < B:
                            continue
                        sc = estimates(model, v_s, gd_s, f_te[name], span // B, log_grid)
                        table[case, name, B, span] = info_per_s(sc, span / RATE_HZ, rng)
                        if span == 1000:
                            for lo, hi, label in SPEED_BANDS:
                                sel = (sc.speed >= lo) & (sc.speed < hi)
                                sub = sc.subset(sel)
                                band_j[case, name, B, label] = info_per_s(sub, span / RATE_HZ, rng)
                except np.linalg.LinAlgError:
                    raise SystemExit(singular(f"{name}, B = {B}", n_runs, keep_s)) from None
                lack[case, name, B] = model.lack_of_fit

    def reference(case: str, span: int) -> tuple:
        """log f of the paper's 1,000-sample window, or of the longest block within T."""
        return (case, PAPER[0], min(PAPER[1], max(b for b in BLOCKS if b <= span)), span)

    def ratio(d: dict, key: tuple, ref_key: tuple, field: str) -> float:
        return d[key][field] / d[ref_key][field] if ref_key in d else np.nan

    print(f"\n1. Held-out GD estimates from T seconds of driving ({load()})")
    print("J = 1/(RMSE^2 T) [1/s] +- bootstrap SE over test runs; RMSE of the posterior-mean log")
    print("GD (flat prior on [log 200, log 600]); cov: coverage of the 90% interval; ratio: J /")
    print("J(log_var, B=1000) at the same T (at T = 4.2 s: log_var, B=500). Prior-only RMSE")
    print(f"{prior_rmse:.3f}: where RMSE is not far below it, the prior bounds the error and J")
    print("measures the prior as much as the feature (section 2 leaves the prior out).")
    head = "".join(f"| T={s / RATE_HZ:4.1f} s: J +- se    RMSE  cov ratio " for s in SPANS)
    for case in ("A", "B"):
        print(f"\ncase {case} ({'noise-free' if case == 'A' else 'N(0, 1) noise'})")
        print(f"{'feature':<10}{'B':>5} {head}")
        for name in FEATURES:
            for B in BLOCKS:
                row = f"{name:<10}{B:5d} "
                for span in SPANS:
                    key = (case, name, B, span)
                    if key not in table:
                        row += f"| {'(block longer than T)':<38}"
                        continue
                    t = table[key]
                    r = ratio(table, key, reference(case, span), "J")
                    row += f"| {t['J']:6.2f} +- {t['se']:5.2f} {t['rmse']:6.3f} "
                    row += f"{t['cov']:4.2f} {r:5.2f} "
                print(row)

    print(f"\n2. Information per second without the prior ({load()})")
    print(
        "J_lin [1/s] +- bootstrap SE: held out, from the linearised (GLS-from-the-truth) estimate"
    )
    print("of each stretch: 0.455 / (median squared error x T) (a robust 1 / (MSE T)); ratio: to")
    print(
        "log_var B=1000 at T = 8.3 s. J_fit: the fitted model's own Fisher information per second"
    )
    print("(median over test runs). lof: lack of fit of the training runs' means about the cubic")
    print("(mean squared standardised residual per output; 1: the cubic and Sigma explain them).")
    head = "".join(f"| T={s / RATE_HZ:4.1f} s: J_lin +- se " for s in SPANS)
    for case in ("A", "B"):
        print(f"\ncase {case} ({'noise-free' if case == 'A' else 'N(0, 1) noise'})")
        print(f"{'feature':<10}{'B':>5} {'J_fit':>6} {'lof':>5} {head}| ratio@8.3s")
        for name in FEATURES:
            for B in BLOCKS:
                row = f"{name:<10}{B:5d} {jfit[case, name, B]:6.2f} {lack[case, name, B]:5.2f} "
                for span in SPANS:
                    key = (case, name, B, span)
                    if key not in table:
                        row += f"| {'(B > T)':<22}"
                        continue
                    t = table[key]
                    row += f"| {t['Jlin']:12.2f} +- {t['se_lin']:5.2f} "
                r = ratio(table, (case, name, B, 1000), (case, *PAPER, 1000), "Jlin")
                print(row + f"| {r:6.2f}")

    n_band = ", ".join(f"{lab}: {np.sum((v_s >= lo) & (v_s < hi))}" for lo, hi, lab in SPEED_BANDS)
    print(f"\n3. Per speed band at T = 8.3 s (test runs {n_band}); ({load()})")
    print("J from the posterior-mean RMSE and J_lin (no prior), [1/s], ratio to log_var B=1000")
    cols = "".join(f"{lab + ': J (ratio)':>17}{'J_lin (ratio)':>16}" for *_, lab in SPEED_BANDS)
    for case in ("A", "B"):
        print(f"\ncase {case}")
        print(f"{'feature':<10}{'B':>5} {cols}")
        for name in FEATURES:
            for B in BLOCKS:
                row = f"{name:<10}{B:5d} "
                for *_, lab in SPEED_BANDS:
                    t, band_key, ref = (
                        band_j[case, name, B, lab],
                        (case, name, B, lab),
                        (case, *PAPER, lab),
                    )
                    row += f"{t['J']:10.2f} ({ratio(band_j, band_key, ref, 'J'):4.2f})"
                    row += f"{t['Jlin']:9.2f} ({ratio(band_j, band_key, ref, 'Jlin'):4.2f})"
                print(row)

    print(f"\n4. Variants of the band vector at T ~ 8.3 s (1,000 samples; {load()})")
    print("J and J_lin [1/s] +- bootstrap SE as in sections 1 and 2; K: outputs per block;")
    print("J / bands: J over the 8-band vector's J, +- a paired bootstrap SE over test runs")
    print("(same runs, same stretches: block-length variants differ in stretch ends, still paired)")
    for case in ("A", "B"):
        print(f"\ncase {case}")
        print(f"{'variant':<34}{'B':>5}{'K':>4} {'J +- se':>15} {'J_lin +- se':>15} {'cov':>5}"
              f" {'J / bands':>15}")  # fmt: skip
        bands = None
        for name, (B, fields, extra) in BAND_VARIANTS.items():
            f_tr = band_variant(acc_tr[case], B, fields, extra)
            f_te = band_variant(acc_te[case], B, fields, extra)[scored]
            per = 1000 // B
            try:
                model = fit(v_tr, gd_tr, f_tr, max(1, BATCH_SAMPLES // B))
                sc = estimates(model, v_s, gd_s, f_te, per, log_grid)
            except np.linalg.LinAlgError:  # more outputs than the short campaigns resolve
                print(f"{name:<34}{B:5d}{f_tr.shape[2]:4d} {singular('', n_runs, keep_s)}")
                continue
            if name == FIRST_VARIANT:
                bands = sc, per * B
            t = info_per_s(sc, per * B / RATE_HZ, rng)
            r, r_se = paired_j_ratio(sc, per * B, *bands, rng) if bands else (np.nan, np.nan)
            print(f"{name:<34}{B:5d}{f_tr.shape[2]:4d} {t['J']:7.2f} +- {t['se']:4.2f} "
                  f"{t['Jlin']:7.2f} +- {t['se_lin']:4.2f} {t['cov']:5.2f} "
                  f"{r:7.3f} +- {r_se:5.3f}")  # fmt: skip
    print(f"\ntotal {time.perf_counter() - tic:.0f} s; {load()}")


if __name__ == "__main__":
    main()
