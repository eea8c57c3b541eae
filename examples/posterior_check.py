"""The paper's Table 2 and Appendix A: percent error of the posterior-mean GD on fresh roads.

    python examples/posterior_check.py                 # case A, 5 roads per cell, ./out
    python examples/posterior_check.py --case B --roads 10 --out DIR

For v in {0.75, 1.25, 1.75} m/s and GD in {250, 300, ..., 550}: a fresh 21 m road per cell, made
as the training roads are (roadgen.iso8608_profile with a 1 m lead-in, wheel-enveloped), one drive
at constant v of the vehicle, with the noise, that the emulator records (the Jackal for the shipped
files), one observation from the last 1,000 samples (the emulator's window), and the posterior of
GD from ``gpmsa.Calibrator.update`` (uniform prior on the emulator's GD domain: [200, 600], the
paper's eq. 3, for the shipped files; a file whose domain misses a cell is refused).
The table's first block is road 1 of each cell (one window per cell, as the paper); the second is
the mean absolute percent error over ``--roads`` roads per cell, a steadier figure. The paper's
Table 2 is of its noise-free case (A): with ``--case B`` its column says so. About 10-15 s at the
defaults (README.md's figures: the defaults, case A), ~5 s with ``--roads 1``. The histograms
(Appendix A) are of road 1's posterior draws.
"""

from __future__ import annotations

import argparse
import json

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
from _cli import check_seed, output_folder, path_option, run, save_figure, write_text  # noqa: E402

import control  # noqa: E402
import gpmsa  # noqa: E402
import roadgen  # noqa: E402
import vehicle  # noqa: E402
from control.feature import window_feature  # noqa: E402
from control.plotting import plot_posterior_grid  # noqa: E402

SPEEDS = (0.75, 1.25, 1.75)
GDS = (250, 300, 350, 400, 450, 500, 550)
PAPER_TABLE2 = {  # percent error, rows GD, columns v (Lewis et al. 2025, Table 2)
    250: (78.2, 12.3, 46.8),
    300: (33.6, 23.6, 7.2),
    350: (24.2, 0.2, 14.2),
    400: (2.2, 4.0, 30.9),
    450: (4.9, 16.1, 1.5),
    500: (18.5, 3.1, 5.7),
    550: (22.1, 7.4, 19.2),
}


ROAD_M = 21.0
"""Length of each fresh road, m (the paper's): long enough for a 1,000-sample window at 1.75 m/s."""


def cell_posterior(calibrator, model, v: float, gd: float, seed: int, noise_std: float, emu):
    """Posterior of GD from one window on one fresh road driven at v (the window emulator's
    feature, roads made as its training roads were)."""
    feature = control.emulator_feature(emu)
    road = roadgen.iso8608_profile(
        ROAD_M, gd, seed=seed, lead_in_m=emu.metadata["road"]["lead_in_m"]
    )
    trace = vehicle.simulate(
        model, road, v, rate_hz=feature.rate_hz, noise_std=noise_std, seed=seed
    )
    y = window_feature(trace.accel_front_measured[-feature.block_samples :], feature.name)
    return calibrator.update([[v]], [[y]])


def check_domain(emu) -> None:
    """ValueError unless the emulator's domain holds every cell of the table (speeds in m/s, GD
    in 1e-6 m^3): shipped files retrained with ``train_emulator.py --ship`` may cover less, and
    the calibration would refuse a speed outside it, or bound GD's prior short of the cell's."""
    (v_lo, v_hi), (gd_lo, gd_hi) = emu.domain[emu.x_names[0]], emu.domain[emu.t_names[0]]
    if not (v_lo <= min(SPEEDS) <= max(SPEEDS) <= v_hi and gd_lo <= min(GDS) <= max(GDS) <= gd_hi):
        raise ValueError(
            f"the shipped window emulator covers v [{v_lo:g}, {v_hi:g}] m/s and GD "
            f"[{gd_lo:g}, {gd_hi:g}]; Table 2's cells need v [{min(SPEEDS):g}, {max(SPEEDS):g}] "
            f"m/s and GD [{min(GDS):g}, {max(GDS):g}] (the paper's: v [0.5, 2], GD [200, 600]): "
            "retrain it with examples/train_emulator.py --ship over those ranges"
        )


MAX_ROADS = 10_000
"""Most fresh roads per cell (``--roads``): each is a drive of its own."""


def road_seeds(seed: int, roads: int) -> np.ndarray:
    """Seeds (GD, v, road) of each cell's roads and drives: road k's of every cell are the
    same whatever ``roads``, so that the table's first block (road 1) does not change with
    --roads. The first 5 roads of a cell are those the script has always drawn with its default
    5 (the figures README quotes); more come after them in the same stream."""
    cells = len(GDS) * len(SPEEDS)
    state = np.random.SeedSequence(seed).generate_state(cells * max(roads, 5))
    first = state[: cells * 5].reshape(len(GDS), len(SPEEDS), 5)
    more = state[cells * 5 :].reshape(-1, len(GDS), len(SPEEDS)).transpose(1, 2, 0)
    return np.concatenate([first, more], axis=2)[:, :, :roads]


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--case", default="A", choices=["A", "B"],
        help="the shipped window emulator of test case A (noise-free, the default) or B",
    )  # fmt: skip
    parser.add_argument("--roads", type=int, default=5, help="fresh roads per cell (default 5)")
    parser.add_argument(
        "--seed", type=int, default=2025, help="seed of the roads and drives (default 2025)"
    )
    parser.add_argument(
        "--out", type=path_option, default="out",
        help="folder for table2_CASE.json and posterior_grid_CASE.png (default ./out)",
    )  # fmt: skip
    args = parser.parse_args(argv)
    if not 1 <= args.roads <= MAX_ROADS:
        parser.error(f"--roads must be in [1, {MAX_ROADS}] (a drive each), got {args.roads}")
    check_seed(parser, args.seed)
    emu = control.shipped_emulator(args.case, "window")  # the paper's feature
    try:
        check_domain(emu)
    except ValueError as exc:
        parser.error(f"--case {args.case}: {exc}")
    out = output_folder(parser, "--out", args.out)
    calibrator = gpmsa.Calibrator(emu, seed=args.seed)
    model = control.emulator_vehicle(emu)  # `train_emulator.py --ship --vehicle` replaces it
    noise = control.emulator_noise_std(emu) or 0.0

    errors = np.zeros((len(GDS), len(SPEEDS), args.roads))
    cells = []
    seeds = road_seeds(args.seed, args.roads)
    for i, gd in enumerate(GDS):
        for j, v in enumerate(SPEEDS):
            for k in range(args.roads):
                post = cell_posterior(calibrator, model, v, gd, int(seeds[i, j, k]), noise, emu)
                errors[i, j, k] = 100 * abs(post.mean("GD") - gd) / gd
                if k == 0:
                    cells.append((v, gd, post.samples["GD"]))

    paper = np.array(list(PAPER_TABLE2.values()))
    summary = {
        "paper": {"max": float(paper.max()), "mean": float(paper.mean())},
        "one_road": {"max": float(errors[:, :, 0].max()), "mean": float(errors[:, :, 0].mean())},
        "all_roads": {
            "max_cell_mean": float(errors.mean(axis=2).max()),
            "mean": float(errors.mean()),
            "roads_per_cell": args.roads,
        },
    }
    # the files first: a reader that stops reading (`... | head`) ends the script at a print
    title = f"Posterior GD, case {args.case}, one window per cell (line: the road's GD)"
    fig = plot_posterior_grid(cells, title=title, gd_range=emu.domain[emu.t_names[0]])
    figure_path, table_path = (
        out / f"posterior_grid_{args.case}.png",
        out / f"table2_{args.case}.json",
    )
    save_figure(fig, figure_path)
    write_text(
        table_path, json.dumps({"summary": summary, "percent_error": errors.tolist()}, indent=1)
    )

    # the paper's Table 2 is its noise-free case: case B's rows set ours beside that
    paper_label = "paper" if args.case == "A" else "paper (noise-free: its Table 2 is case A)"
    print(
        f"Table 2, case {args.case}: percent error of the posterior-mean GD ({paper_label} | ours)"
    )
    print(
        f"{'GD':>5} " + "".join(f"{'v=' + str(v):>18}" for v in SPEEDS) + f"{'mean of roads':>30}"
    )
    for i, gd in enumerate(GDS):
        row = "".join(f"{PAPER_TABLE2[gd][j]:9.1f}{errors[i, j, 0]:8.1f} " for j in range(3))
        avg = "".join(f"{errors[i, j].mean():9.1f}" for j in range(3))
        print(f"{gd:>5} {row}  {avg}")
    print(
        f"max / mean percent error: {paper_label} {summary['paper']['max']:.1f} / "
        f"{summary['paper']['mean']:.1f}; ours, one road per cell "
        f"{summary['one_road']['max']:.1f} / {summary['one_road']['mean']:.1f}; "
        f"ours, mean over {args.roads} road{'s' if args.roads != 1 else ''}: worst cell "
        f"{summary['all_roads']['max_cell_mean']:.1f} / {summary['all_roads']['mean']:.1f}"
    )
    print(f"wrote {table_path} and {figure_path}")
    return summary


if __name__ == "__main__":
    run(main)
