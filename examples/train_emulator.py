"""Train the emulators the closed loop uses (paper Test Cases A and B).

    python examples/train_emulator.py                  # campaign + fits -> out/emulators/
    python examples/train_emulator.py --ship           # ... and replace the package's shipped files
    python examples/train_emulator.py --n-iter 5000 --out out_quick   # a quicker try
    python examples/train_emulator.py --cases B --noise-std 0.3 \
        --vehicle mass_kg=21.5 tyre_stiffness_n_per_m=26000            # your robot (docs/robot.md)

Steps (docs/closed-loop.md):

1. a 198-point Latin hypercube over v in [0.5, 2.0] m/s (``--speed-range``) and GD in [200, 600]
   (``--gd-range``; paper eqs. 3-4, Fig. 5), stretched so that its extreme points lie on the
   bounds (the emulator's domain is the design's range, and the robot drives at exactly 2.0 m/s;
   a robot with another top speed trains to it, and drives with ``Simplex(v_max=...)`` inside
   the range: `control.check_emulator` refuses a Simplex whose speeds lie outside);
   ``--speed-spacing arcsine`` places the speeds denser towards both ends of the range; the band
   emulators' design adds ``--anchor-runs`` (198 // 6 = 33) runs, GD stratified, at each of
   ``--anchor-speeds`` (default 1.0 and 2.0 m/s, the default Simplex's two speeds: where the
   loop reads the emulator; for another ``--speed-range``, 1.0 m/s if it lies inside and the
   range's top);
2. one fresh road and one Jackal drive per point (``vehicle.run_campaign``), keeping the last
   ``--keep-s`` (120) seconds of front-axle accelerations, noise-free and with N(0, 1) noise;
3. the block-feature emulators ``jackal_{A,B}.gpmsa`` (the change-point BCR's): per run, the
   mean feature of its 125-sample blocks (``--block-samples``; `control.training`): 8 log band
   powers and the blocks' 90% and 98% quantiles less their mean (``--quantiles``), fitted by
   ``gpmsa.fit`` through its PCA basis (8 components, ``--n-pc``); the block-to-block
   covariance Sigma(v) and the Student-t dof, stored in the file's metadata (``block_scatter``)
   as the known observation noise of one block;
4. the paper-feature emulators ``jackal_{A,B}_window.gpmsa`` (the paper's estimator and the
   window filters): y = log f of the last 1,000 samples of each drive of the Latin hypercube
   (the paper's design, without the anchor runs), with the GP nugget
   describing the window scatter (its lamWs prior relaxed from GPM/SA's lower bound of 60 to 1).

The files go to ``--emulator-dir`` (default ``OUT/emulators``); ``--ship`` writes them into the
package (control/emulators/) instead, replacing the shipped ones; it refuses, before the
campaign, speed or GD ranges that would not cover the default Simplex's speeds (1-2 m/s) and the
paper's track (GD 300-500), which the README's main command needs. A fit may warn
(``gpmsa.ConvergenceWarning``: one chain is judged by its split R-hat and bulk ESS, and the
shipped band emulators' chains would be flagged for a few speed coefficients; docs/closed-loop.md);
the file records the verdict, and ``--n-iter`` runs longer chains. Each file's metadata records the
vehicle, the noise level, the feature, the road settings, the design, the fit settings and the
versions of Python, numpy, scipy, exudyn and BLAS that made the training data (`gpmsa info`
shows them, with those of the fit). OUT also gets ``campaign.npz`` (the drives' features and
traces) and ``lhs_design.png``; each finished drive is kept in ``OUT/campaign_cache`` (keyed by
its settings and those versions), so a run stopped during the campaign (Ctrl-C) starts again
where it stopped; delete the folder (~60 MB for the default campaign) once the emulators exist.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import time
from typing import Any

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
from _cli import (  # noqa: E402
    check_option_memory,
    check_seed,
    output_folder,
    path_option,
    run,
    save_figure,
)
from closed_loop import GD_MAX, PAPER_SEGMENTS  # noqa: E402

import control  # noqa: E402
import gpmsa  # noqa: E402
import vehicle  # noqa: E402
from control import PAPER_WINDOW, FeatureSpec  # noqa: E402
from control.feature import feature_of_variance  # noqa: E402
from control.plotting import plot_design  # noqa: E402
from control.shipped import EMULATOR_DIR, emulator_file_name  # noqa: E402
from control.training import (  # noqa: E402
    GD_MIN_HI,  # the smallest --gd-range HI: a range below it is one given in m^3
    SINGULAR_WEIGHT,
    WINDOW_PRIORS_LAMWS,
    covariance_rank,
    fit_band_emulator,
    weight_beyond_rank,
)
from gpmsa.fitting.fit import simulation_fit_nbytes  # noqa: E402
from roadgen.checks import home_path  # noqa: E402

V_RANGE = (0.5, 2.0)
GD_RANGE = (200.0, 600.0)
RATE_HZ = 120.0
LEAD_IN_M = 1.0
NOISE_STD = {"A": 0.0, "B": 1.0}
BAND_FEATURE = FeatureSpec()
BAND_PCS = 8
"""Basis size of the band emulators (``--n-pc``): 8 of the feature's 10 outputs (8 band powers,
2 quantiles), 99.98% of the variance of the runs' mean features. What the quantiles add lies
in directions of little variance between runs: the 99.9% rule would keep 6, and held out (198
runs of 60 s, 8 blocks pooled, 1-2 m/s) the quantiles raise the information per second by
17% / 16% (A / B) with 6 components and 18% / 16% with 8. For the band vector alone 5 kept 99.9%
(GPM/SA's default 99.5% kept 3-4 and dropped GD-dependent shape: held-out RMSE of log GD over
8.3 s of driving 0.116 with 3, 0.110 with 5, 0.109 with all 8; docs/closed-loop.md)."""
WINDOW_PRIORS = gpmsa.Priors(lamWs=gpmsa.GammaPrior(*WINDOW_PRIORS_LAMWS))
MIN_RUNS = 4
"""Fewest design points (``--n-runs``): gpmsa.SimData needs p + q + 2 = 4 runs for v and GD
(and the band emulators at least ``--n-pc``)."""
BATCH = 8
"""Blocks per batch of the band emulators' block scatter (`control.training.block_statistics`,
which needs two batches per run: ``--keep-s`` >= 2 * BATCH * ``--block-samples`` / RATE_HZ)."""
SCATTER_NODES = 16
"""Speed nodes of the band emulators' block scatter, evenly over ``--speed-range``."""
ANCHOR_SHARE = 6
"""Default ``--anchor-runs``: ``--n-runs`` // this at each anchor speed (33 for the paper's 198)."""
SPEED_SPACINGS = ("uniform", "arcsine")
"""Spacing of the design's speeds (``--speed-spacing``). A GP is least sure at the ends of its
domain, and the loop drives at its top speed: with the same runs, arcsine spacing lowered the
band emulators' RMS GD bias on held-aside roads from 4.8% to 3.1% (slow edge 9.4% -> 3.5%), but
it moved the closed loop along the GD-300 / GD-500 trade-off rather than forward. With the anchor
runs (the default) it gives the most even emulator over the whole range (RMS GD bias over GD
250-550 2.5% / 2.8% for A / B against 3.6% / 4.5%), but reads 1-4% low at 1.0 m/s in case B and
leaves the closed loop where it was, so the shipped emulators keep uniform spacing; a user who
calibrates at any speed of the range may prefer it (docs/closed-loop.md, "The emulators")."""
BOOLEANS = {"1": True, "true": True, "yes": True, "on": True,
            "0": False, "false": False, "no": False, "off": False}  # fmt: skip


def default_anchor_speeds(speed_range: tuple[float, float]) -> list[float]:
    """Default ``--anchor-speeds``, m/s: the default Simplex's safe speed (1.0 m/s) where it lies
    in ``speed_range``, and the range's top, the speed the robot drives at in performance mode
    (the default Simplex's v_max, 2.0 m/s, for the default range): where the loop reads the
    emulator. On held-aside roads (12 a cell, 6,000-sweep fits, docs/closed-loop.md "The
    emulators") runs on these lines took the band emulators' linearised RMS GD bias at 1.0 m/s
    from 2.4% / 3.6% (A / B) to 1.3% / 2.0%, at 2.0 m/s from 2.4% / 2.2% to 1.7% / 1.9%, and
    their own sd at 2.0 m/s from 6.5% / 5.0% to 3.3% / 2.7%."""
    lo, hi = speed_range
    v_safe = control.Simplex.v_safe
    return ([float(v_safe)] if lo <= v_safe < hi else []) + [float(hi)]


def stretched_design(
    n: int,
    seed: int,
    gd_range: tuple[float, float] = GD_RANGE,
    v_range: tuple[float, float] = V_RANGE,
    speed_spacing: str = "uniform",
) -> np.ndarray:
    """An LHS (vehicle.lhs_design) mapped so each column spans its range exactly (speed in m/s,
    GD in 1e-6 m^3): affinely, or for the speeds with ``speed_spacing="arcsine"`` through
    u -> (1 - cos(pi u)) / 2 of the affine map's unit value u, which keeps the order and places
    the speeds with the arcsine (Chebyshev) density, denser towards both ends of the range."""
    if speed_spacing not in SPEED_SPACINGS:
        raise ValueError(f"speed_spacing must be one of {SPEED_SPACINGS}, got {speed_spacing!r}")
    design = vehicle.lhs_design(n, v_range, gd_range, seed=seed)
    lo, hi = design.min(axis=0), design.max(axis=0)
    unit = (design - lo) / (hi - lo)
    if speed_spacing == "arcsine":
        unit[:, 0] = 0.5 * (1.0 - np.cos(np.pi * unit[:, 0]))
    target_lo, target_hi = np.array([v_range[0], gd_range[0]]), np.array([v_range[1], gd_range[1]])
    return target_lo + unit * (target_hi - target_lo)


def anchor_design(
    speeds: tuple[float, ...], n_per_speed: int, seed: int, gd_range: tuple[float, float]
) -> np.ndarray:
    """``n_per_speed`` runs at each of ``speeds`` (m/s), GD stratified over ``gd_range``
    (1e-6 m^3: one GD drawn uniformly in each of n_per_speed equal strata, a one-dimensional
    Latin hypercube per speed), as rows [v, GD]. A GP is least sure along the edge of its domain,
    and the Simplex drives at exactly its two speeds, so runs on those lines pin the emulator
    where the loop reads it (docs/closed-loop.md, "The emulators")."""
    rng = np.random.default_rng(np.random.SeedSequence([seed, 1]))  # apart from the LHS's
    lo, hi = gd_range
    rows = []
    for v in speeds:
        strata = (rng.permutation(n_per_speed) + rng.uniform(size=n_per_speed)) / n_per_speed
        rows.append(np.column_stack([np.full(n_per_speed, v), lo + strata * (hi - lo)]))
    return np.concatenate(rows) if rows else np.empty((0, 2))


def noise_std(case: str, args) -> float:
    """Accelerometer noise sd of a case, m/s^2: none for A, ``--noise-std`` for B."""
    return NOISE_STD["A"] if case == "A" else float(args.noise_std)


def vehicle_model(overrides: list[str]) -> vehicle.Jackal:
    """A Jackal with the ``NAME=VALUE`` overrides of ``--vehicle`` (its attributes, SI units).

    Raises ValueError, its message starting ``--vehicle``, naming the item that is not
    ``NAME=VALUE`` with a known NAME and a value of its type (lift_off: true/false, yes/no,
    on/off or 1/0; wheels_per_axle: an integer; the others: a number), or the value the Jackal
    refuses (`vehicle.VehicleError`: out of its range).
    """
    fields = {f.name for f in dataclasses.fields(vehicle.Jackal)}
    kw: dict[str, Any] = {}
    for item in overrides:
        name, sep, value = item.partition("=")
        if not sep or name not in fields:
            raise ValueError(
                f"--vehicle {item!r}: expected NAME=VALUE with NAME one of {sorted(fields)}"
            )
        if name in kw:  # the later one would silently win
            raise ValueError(f"--vehicle {name} is given twice; give each name once")
        try:
            if name == "lift_off":
                kw[name] = BOOLEANS[value.lower()]
            elif name == "wheels_per_axle":
                kw[name] = int(value)
            else:
                kw[name] = float(value)
        except (KeyError, ValueError):
            kind = {"lift_off": f"one of {sorted(BOOLEANS)}", "wheels_per_axle": "an integer"}
            raise ValueError(
                f"--vehicle {item!r}: {name} must be {kind.get(name, 'a number')}"
            ) from None
    try:
        return vehicle.Jackal(**kw)
    except vehicle.VehicleError as exc:
        raise ValueError(f"--vehicle: {exc}") from None


def metadata(
    case: str, feature: FeatureSpec, model, campaign, args, extra: dict, anchored: bool = True
) -> dict:
    """What the loop checks and what a reader of the file wants to know (``anchored``: the fit
    used the anchor runs as well as the Latin hypercube's)."""
    speeds = list(args.anchor_speeds) if anchored else []
    return {
        "case": case,
        "vehicle": model.describe(),
        "noise_std": noise_std(case, args),
        "feature": feature.to_dict(),
        "road": {
            "generator": "roadgen.iso8608_profile",
            "lead_in_m": LEAD_IN_M,
            "dx_m": 0.006,
            "band": None,
            "wheel_envelope": True,
            "drive_s": args.keep_s,
        },
        "design": {
            "n": int(campaign.v.size) if anchored else args.n_runs,
            "seed": args.seed,
            "speed_spacing": args.speed_spacing,
            "anchor_speeds": speeds,
            "anchor_runs": args.anchor_runs if speeds else 0,
            "v_range": list(args.speed_range),
            "gd_range": list(args.gd_range),
        },
        "versions": campaign.settings.get("versions", {}),  # what made the training data
        "made_by": "examples/train_emulator.py",
        **extra,
    }


def check_shippable(parser: argparse.ArgumentParser, args) -> None:
    """Refuse --ship with ranges that the main command (closed_loop.py with the shipped files,
    the paper's track and the default Simplex) would refuse, before the campaign runs."""
    need_v = (control.Simplex.v_safe, control.Simplex.v_max)
    need_gd = (min(gd for _, gd in PAPER_SEGMENTS), max(gd for _, gd in PAPER_SEGMENTS))
    for flag, (lo, hi), (need_lo, need_hi), unit in (
        ("--speed-range", args.speed_range, need_v, "m/s (the default Simplex's speeds)"),
        ("--gd-range", args.gd_range, need_gd, "(the paper's track)"),
    ):
        if not lo <= need_lo <= need_hi <= hi:
            parser.error(
                f"--ship with {flag} {lo:g} {hi:g}: the shipped files must cover "
                f"[{need_lo:g}, {need_hi:g}] {unit}, or `python examples/closed_loop.py` would "
                "refuse them; write these emulators elsewhere with --emulator-dir DIR and run "
                "closed_loop.py --emulator-dir DIR"
            )


BAND_OPTIONS = {
    "anchor_speeds": None,
    "anchor_runs": None,
    "block_samples": BAND_FEATURE.block_samples,
    "quantiles": list(BAND_FEATURE.quantiles),
    "n_pc": BAND_PCS,
}
"""The options that shape the band emulators alone, with their defaults (None: filled later)."""


def check_applies(parser: argparse.ArgumentParser, args) -> None:
    """Usage error for an option given where it has no effect (the files would not say that
    it was dropped): a band emulators' option without ``--features band``, ``--noise-std``
    without case B (case A is noise-free); then fill the defaults of those left out."""
    if "band" not in args.features:
        for name in BAND_OPTIONS:
            if getattr(args, name) is not None:
                option = "--" + name.replace("_", "-")
                parser.error(
                    f"{option} shapes the band emulators only, which --features "
                    f"{' '.join(args.features)} does not fit: add band to --features, or "
                    f"leave {option} out"
                )
    if args.noise_std is not None and "B" not in args.cases:
        parser.error(
            f"--noise-std {args.noise_std:g} is case B's noise (case A is trained noise-free), "
            "but --cases leaves B out: for an emulator of your IMU's noise give --cases B"
        )
    for name, default in (*BAND_OPTIONS.items(), ("noise_std", NOISE_STD["B"])):
        if getattr(args, name) is None:
            setattr(args, name, default)


def check_anchors(parser: argparse.ArgumentParser, args) -> None:
    """Refuse anchor speeds outside ``--speed-range`` and fewer than one run a speed; fill the
    default ``--anchor-runs``; no anchors where no band emulator is fitted."""
    v_lo, v_hi = args.speed_range
    if "band" not in args.features:
        args.anchor_speeds = []
    elif args.anchor_speeds is None:
        args.anchor_speeds = default_anchor_speeds((v_lo, v_hi))
    for v in args.anchor_speeds:
        if not (np.isfinite(v) and v_lo <= v <= v_hi):
            parser.error(
                f"--anchor-speeds {v:g}: must lie in --speed-range [{v_lo:g}, {v_hi:g}] m/s"
            )
    if args.anchor_runs is None:
        args.anchor_runs = max(1, args.n_runs // ANCHOR_SHARE)
    if args.anchor_speeds and not 1 <= args.anchor_runs <= args.n_runs:
        parser.error(
            f"--anchor-runs must be in [1, --n-runs = {args.n_runs}] (runs at each anchor "
            f"speed), got {args.anchor_runs}"
        )


def design_title(args) -> str:
    """Title of the design figure: the Latin hypercube's runs and the anchor runs apart (the
    window emulators fit the former only)."""
    title = f"Latin hypercube design, {args.n_runs} runs"
    if args.anchor_speeds:
        speeds = ", ".join(f"{v:g}" for v in args.anchor_speeds)
        title += f"\n+ {args.anchor_runs} anchor runs at each of {speeds} m/s"
    return title


def design_figure(design: np.ndarray, args):
    """The design (paper Fig. 5): the Latin hypercube's runs (rows up to ``--n-runs``), and the
    anchor runs after them marked apart."""
    lhs, anchors = design[: args.n_runs], design[args.n_runs :]
    fig = plot_design(lhs[:, 0], lhs[:, 1], title=design_title(args))
    if anchors.size:
        ax = fig.axes[0]
        ax.collections[0].set_label("Latin hypercube")
        ax.scatter(anchors[:, 0], anchors[:, 1], s=14, marker="x", color="C1",
                   label="anchor runs (band emulators)")  # fmt: skip
        fig.legend(loc="outside lower center", ncols=2, fontsize=8, frameon=False)
    return fig


def fit_memory(m: int, n_pc: int, n_iter: int) -> float:
    """Bytes `gpmsa.fit` needs (its own estimate, which it refuses beyond the limit) for ``m``
    runs of v and GD, ``n_pc`` components and ``n_iter`` sweeps."""
    return simulation_fit_nbytes(m, p=1, q=1, p_u=n_pc, n_iter=n_iter)


def check_fit_memory(parser: argparse.ArgumentParser, args) -> None:
    """Usage error, before the campaign, where a fit would refuse its runs' covariances: the
    band emulators fit --n-runs and the anchor runs (``n_pc`` components), the window
    emulators --n-runs (one)."""
    runs = {
        "band": (args.n_runs + len(args.anchor_speeds) * args.anchor_runs, args.n_pc),
        "window": (args.n_runs, 1),
    }
    for kind in args.features:
        m, n_pc = runs[kind]
        check_option_memory(
            parser, fit_memory(m, n_pc, args.n_iter),
            f"--n-runs {args.n_runs} and --n-iter {args.n_iter}: the {kind} emulators' "
            f"covariances of {m} runs and gpmsa.fit's draws",
        )  # fmt: skip


def check_scatter_rank(parser: argparse.ArgumentParser, design: np.ndarray, args) -> None:
    """Usage error, before the campaign, where the band emulators' block covariance would be
    singular at a speed node whatever the roads (`control.training.weight_beyond_rank`): each
    run's batches give it a rank of at most their number, and too few runs lie near the node."""
    K = band_feature(args).dim
    n_blocks = int(round(args.keep_s * RATE_HZ)) // args.block_samples  # as run_campaign keeps
    rank = covariance_rank(n_blocks, BATCH)
    nodes = np.linspace(*args.speed_range, SCATTER_NODES)
    share = weight_beyond_rank(design[:, 0], rank, K, nodes)
    if np.all(share > SINGULAR_WEIGHT):
        return
    m, need = design.shape[0], -(-K // rank)
    anchors = m > args.n_runs
    runs = f"--n-runs {args.n_runs}" + (f" and {m - args.n_runs} anchor runs" if anchors else "")
    bands, quantiles = len(BAND_FEATURE.bands_hz) - 1, len(args.quantiles)
    where = (
        f"{m} runs x {rank} < {K} at every speed"
        if m * rank < K
        else f"at {nodes[int(np.argmin(share))]:g} m/s all but {share.min():.1g} of the kernel "
        f"weight lies on the {need - 1} nearest runs"
    )
    parser.error(
        f"{runs} with --keep-s {args.keep_s:g}: the band emulators' {K} x {K} block covariance "
        f"(K = {bands} band powers + {quantiles} quantiles) would be singular whatever the "
        f"roads: each run's {n_blocks // BATCH} batches of {BATCH} blocks give it rank {rank}, "
        f"so it needs {need} runs near each speed, and {where}: raise --n-runs"
        f"{', --anchor-runs' if anchors else ''} or --keep-s"
    )


def band_feature(args) -> FeatureSpec:
    """The band emulators' feature: `BAND_FEATURE` with ``--block-samples`` and ``--quantiles``."""
    return dataclasses.replace(
        BAND_FEATURE, block_samples=args.block_samples, quantiles=tuple(args.quantiles)
    )


def fit_runs(kind: str, case: str, campaign, args) -> np.ndarray:
    """The runs an emulator of ``kind`` and ``case`` fits (mask over the campaign's runs):
    finished with finite data; for the window emulators, of the Latin hypercube only."""
    if kind == "band":
        accel = campaign.accel if case == "A" else campaign.accel_measured
        return campaign.ok & np.all(np.isfinite(accel), axis=1)
    f = campaign.f_window if case == "A" else campaign.f_window_noisy
    return campaign.ok & np.isfinite(f) & (f > 0) & (np.arange(f.size) < args.n_runs)


def check_finished_runs(parser: argparse.ArgumentParser, campaign, args) -> None:
    """Usage error, before any fit, where an emulator would have fewer finished runs than its
    fit needs (the window emulators fit the Latin hypercube's runs alone, not the anchors)."""
    for kind in args.features:
        need = max(MIN_RUNS, args.n_pc) if kind == "band" else MIN_RUNS
        runs = campaign.v.size if kind == "band" else args.n_runs
        for case in args.cases:
            n_ok = int(np.count_nonzero(fit_runs(kind, case, campaign, args)))
            if n_ok < need:
                parser.error(
                    f"only {n_ok} of the {kind} emulators' {runs} runs finished (the vehicle "
                    f"left the road in the others), fewer than the {need} a fit needs: lower "
                    "--gd-range HI or --speed-range HI, or raise --n-runs"
                )


def fit_band(case: str, campaign, model, args):
    """The block-feature emulator of one case, with its block scatter in the metadata
    (`control.training.fit_band_emulator`, as a robot's own drives are fitted)."""
    feature = band_feature(args)
    accel = campaign.accel if case == "A" else campaign.accel_measured
    ok = fit_runs("band", case, campaign, args)
    extra = {
        "fit": {"n_iter": args.n_iter, "priors": "GPM/SA defaults", "n_pc": args.n_pc},
        "training_target": "mean feature of the run's blocks (expected feature)",
    }
    return fit_band_emulator(
        campaign.v[ok], campaign.gd[ok], accel[ok], noise_std=noise_std(case, args),
        feature=feature, vehicle=model, n_pc=args.n_pc, batch=BATCH,
        nodes=np.linspace(*args.speed_range, SCATTER_NODES),
        metadata=metadata(case, feature, model, campaign, args, extra),
        n_iter=args.n_iter, seed=args.seed, progress=True,
    )  # fmt: skip


def fit_window(case: str, campaign, model, args):
    """The paper-feature emulator of one case: log f of the last 1,000 samples of each drive of
    the Latin hypercube (the paper's design: the anchor runs are the band emulators')."""
    f = campaign.f_window if case == "A" else campaign.f_window_noisy
    ok = fit_runs("window", case, campaign, args)
    data = gpmsa.SimData(
        x=campaign.v[ok, None], t=campaign.gd[ok, None],
        y=feature_of_variance(f[ok], "log_var")[:, None],
        x_names=["v"], t_names=["GD"], y_names=["log_f"],
        x_units=["m/s"], t_units=["1e-6 m^3"], y_units=["log((m/s^2)^2)"],
    )  # fmt: skip
    extra = {"fit": {"n_iter": args.n_iter, "lamWs_prior": list(WINDOW_PRIORS_LAMWS)}}
    return gpmsa.fit(
        data, n_iter=args.n_iter, seed=args.seed, progress=True, priors=WINDOW_PRIORS,
        metadata=metadata(case, PAPER_WINDOW, model, campaign, args, extra, anchored=False),
    )  # fmt: skip


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--out", type=path_option, default="out",
        help="folder for the campaign and the figure (default ./out)",
    )  # fmt: skip
    parser.add_argument(
        "--n-runs", type=int, default=198, help="design points (default 198, the paper's)"
    )
    parser.add_argument(
        "--keep-s", type=float, default=120.0, help="seconds of driving per run (default 120)"
    )
    parser.add_argument(
        "--n-iter", type=int, default=30_000,
        help="MCMC sweeps per fit (default 30000, the paper's)",
    )  # fmt: skip
    parser.add_argument(
        "--seed", type=int, default=0, help="seed of design, roads and fits (default 0)"
    )
    parser.add_argument(
        "--emulator-dir", type=path_option, default=None,
        help="default: OUT/emulators",
    )  # fmt: skip
    parser.add_argument(
        "--ship", action="store_true", help=f"write the emulators into {EMULATOR_DIR}"
    )
    parser.add_argument(
        "--gd-range", nargs=2, type=float, default=GD_RANGE, metavar=("LO", "HI"),
        help="GD range of the design (the emulators' domain and the BCR's prior)",
    )  # fmt: skip
    parser.add_argument(
        "--speed-range", nargs=2, type=float, default=V_RANGE, metavar=("LO", "HI"),
        help="speed range of the design, m/s (the emulators' domain: the Simplex's v_safe and "
        "v_max must lie in it; HI at most the vehicle's top speed)",
    )  # fmt: skip
    parser.add_argument(
        "--speed-spacing", default="uniform", choices=SPEED_SPACINGS,
        help="spacing of the design's speeds: uniform (the paper's LHS) or arcsine (denser "
        "towards both ends of --speed-range)",
    )  # fmt: skip
    parser.add_argument(
        "--anchor-speeds", nargs="*", type=float, default=None, metavar="V",
        help="speeds, m/s, at which --anchor-runs runs are added to the band emulators' design, "
        "GD stratified: your Simplex's v_safe and v_max, where the loop reads the emulator "
        "(default: the default Simplex's v_safe, 1.0, if in --speed-range, and the range's top; "
        "the option alone: none)",
    )  # fmt: skip
    parser.add_argument(
        "--anchor-runs", type=int, default=None,
        help=f"runs added at each of --anchor-speeds (default: --n-runs // {ANCHOR_SHARE})",
    )  # fmt: skip
    parser.add_argument(
        "--cases", nargs="+", default=["A", "B"], choices=["A", "B"],
        help="test cases: A (noise-free), B (with --noise-std) (default A B)",
    )  # fmt: skip
    parser.add_argument(
        "--noise-std", type=float, default=None,
        help="accelerometer noise sd of case B, m/s^2 (your IMU's; default 1.0, the paper's)",
    )  # fmt: skip
    parser.add_argument(
        "--vehicle", nargs="+", action="extend", default=[], metavar="NAME=VALUE",
        help="Jackal parameters to change, e.g. mass_kg=21.5 tyre_stiffness_n_per_m=26000 "
        "(vehicle.Jackal's attributes, SI units; the option may be repeated)",
    )  # fmt: skip
    parser.add_argument(
        "--features", nargs="+", default=["band", "window"], choices=["band", "window"],
        help="band: the change-point BCR's block-feature emulators; window: the paper's log f "
        "of 1,000 samples (default band window)",
    )  # fmt: skip
    parser.add_argument(
        "--block-samples", type=int, default=None,
        help="samples per block of the band emulators (the change-point BCR takes the length "
        "from the emulator file and updates three times a block; the default 125 is the length the "
        "BCR's settings and sensor checks were chosen for: docs/closed-loop.md)",
    )  # fmt: skip
    parser.add_argument(
        "--quantiles", nargs="*", type=float, default=None, metavar="LEVEL",
        help="levels in (0, 1) of the block quantiles (minus the block mean) appended to the "
        f"band powers (control.FeatureSpec.quantiles; default: {list(BAND_FEATURE.quantiles)}; "
        "the option alone: none, the band powers only)",
    )  # fmt: skip
    parser.add_argument(
        "--n-pc", type=int, default=None,
        help="principal components of the band emulators (1 to the feature's outputs: its "
        f"{len(BAND_FEATURE.bands_hz) - 1} band powers and one per --quantiles level)",
    )  # fmt: skip
    args = parser.parse_args(argv)
    args.cases, args.features = list(dict.fromkeys(args.cases)), list(dict.fromkeys(args.features))
    check_seed(parser, args.seed)
    check_applies(parser, args)
    for option, fields in (
        ("--quantiles", {"quantiles": tuple(args.quantiles)}),
        ("--block-samples", {"block_samples": args.block_samples}),
    ):
        try:
            dataclasses.replace(BAND_FEATURE, **fields)
        except ValueError as exc:  # ControlError: bad levels, or too short for the bands
            parser.error(f"{option}: {exc}")
    dim = band_feature(args).dim
    if not 1 <= args.n_pc <= dim:
        parser.error(f"--n-pc must be in [1, {dim}] (the feature's outputs), got {args.n_pc}")
    band = "band" in args.features
    min_runs = max(MIN_RUNS, args.n_pc) if band else MIN_RUNS
    if args.n_runs < min_runs:
        why = "gpmsa.SimData's minimum and --n-pc" if band else "gpmsa.SimData's minimum"
        parser.error(f"--n-runs must be >= {min_runs} ({why}), got {args.n_runs}")
    needs = (
        [
            (
                2 * BATCH * args.block_samples / RATE_HZ,
                f"band emulators: two batches of {BATCH} blocks of --block-samples",
            )
        ]
        if band
        else []
    )
    if "window" in args.features:
        needs.append((PAPER_WINDOW.block_samples / RATE_HZ, "the window emulators' window"))
    min_keep_s, why = max(needs)
    if not (np.isfinite(args.keep_s) and args.keep_s >= min_keep_s):
        parser.error(f"--keep-s must be >= {min_keep_s:.4g} s ({why}), got {args.keep_s}")
    if args.n_iter < 2:
        parser.error(f"--n-iter must be >= 2 (gpmsa.fit), got {args.n_iter}")
    lo, hi = args.gd_range
    if not (np.isfinite(lo) and np.isfinite(hi) and 0 < lo < hi <= GD_MAX):
        parser.error(
            f"--gd-range must be finite with 0 < LO < HI <= {GD_MAX:g} (beyond ISO 8608's "
            f"roughest class, H, from 131072), got {lo} {hi}"
        )
    if hi < GD_MIN_HI:  # every ISO 8608 road in m^3 lies below 1: a unit slip, not a floor
        parser.error(
            f"--gd-range {lo:g} {hi:g}: GD is Gd(n0) in units of 1e-6 m^3 (ISO 8608's smoothest "
            f"class, A, spans 0-32), so HI must be >= {GD_MIN_HI:g}; a range given in m^3 is "
            f"--gd-range {lo * 1e6:g} {hi * 1e6:g}"
        )
    v_lo, v_hi = args.speed_range
    if not (np.isfinite(v_lo) and np.isfinite(v_hi) and 0 < v_lo < v_hi):
        parser.error(f"--speed-range must be finite with 0 < LO < HI, m/s, got {v_lo} {v_hi}")
    if args.ship and args.emulator_dir is not None:
        parser.error("--ship and --emulator-dir exclude each other")
    shipped_dir = EMULATOR_DIR.resolve()
    given = None if args.emulator_dir is None else home_path(args.emulator_dir)
    if given is not None and given.resolve() == shipped_dir:
        parser.error(f"--emulator-dir {args.emulator_dir!r} is the shipped emulators' folder: "
                     "use --ship, which checks the settings first")  # fmt: skip
    if not (np.isfinite(args.noise_std) and args.noise_std >= 0):
        parser.error(f"--noise-std must be >= 0, got {args.noise_std}")
    try:
        model = vehicle_model(args.vehicle)
    except ValueError as exc:
        parser.error(str(exc))
    if v_hi > model.max_speed_mps:
        parser.error(
            f"--speed-range HI = {v_hi:.10g} m/s exceeds the vehicle's top speed "
            f"{model.max_speed_mps:.10g} m/s (a faster robot: --vehicle max_speed_mps=...)"
        )
    if args.ship:
        check_shippable(parser, args)
    check_anchors(parser, args)
    check_fit_memory(parser, args)
    design = np.concatenate([
        stretched_design(
            args.n_runs, args.seed, tuple(args.gd_range), tuple(args.speed_range),
            args.speed_spacing,
        ),
        anchor_design(tuple(args.anchor_speeds), args.anchor_runs, args.seed, tuple(args.gd_range)),
    ])  # fmt: skip
    if "band" in args.features:
        check_scatter_rank(parser, design, args)
    out = output_folder(parser, "--out", args.out)
    if args.ship:
        emu_dir = output_folder(parser, "--ship", EMULATOR_DIR)
    elif args.emulator_dir:
        emu_dir = output_folder(parser, "--emulator-dir", args.emulator_dir)
    else:
        emu_dir = output_folder(parser, "--out", out / "emulators")

    tic = time.perf_counter()
    try:  # its memory and settings are checked before the first run
        campaign = vehicle.run_campaign(
            design, model, lead_in_m=LEAD_IN_M, rate_hz=RATE_HZ, noise_std=args.noise_std,
            window=PAPER_WINDOW.block_samples, cache_dir=out / "campaign_cache", progress=True,
            seed=args.seed, keep_s=args.keep_s,
        )  # fmt: skip
    except vehicle.VehicleError as exc:
        parser.error(f"the campaign (--n-runs, --anchor-runs, --keep-s, --speed-range): {exc}")
    save_figure(design_figure(design, args), out / "lhs_design.png", dpi=150)
    print(f"campaign: {campaign.v.size} runs in {time.perf_counter() - tic:.0f} s")
    if not campaign.ok.all():
        print(f"  {np.count_nonzero(~campaign.ok)} failed runs are left out")
    check_finished_runs(parser, campaign, args)
    campaign.save(out / "campaign.npz")

    fitters = {"band": fit_band, "window": fit_window}
    for case in args.cases:
        for kind in args.features:
            tic = time.perf_counter()
            try:
                emu = fitters[kind](case, campaign, model, args)
            except control.ControlError as exc:  # the block scatter: too few batches near a speed
                failed = int(np.count_nonzero(~fit_runs(kind, case, campaign, args)))
                why = (
                    f"; {failed} of the {campaign.v.size} runs failed (the vehicle left the road: "
                    "campaign.npz's status), which leaves speeds without runs: lower --gd-range "
                    "HI or --speed-range HI"
                    if failed
                    else ""
                )
                parser.error(
                    f"case {case}, {kind} emulator: {exc}; too few runs or blocks for its "
                    f"covariance: raise --n-runs or --keep-s{why}"
                )
            path = emu_dir / emulator_file_name(case, kind)
            emu.save(path)
            params = {k: np.round(np.ravel(v), 3).tolist() for k, v in emu.params.items()}
            print(f"case {case}, {kind}: fitted in {time.perf_counter() - tic:.0f} s -> {path}")
            print(f"  point estimate: {json.dumps(params)}")
    print(f"design figure: {out / 'lhs_design.png'}")


if __name__ == "__main__":
    run(main)
