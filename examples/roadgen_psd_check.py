"""Repeat the paper's PSD check: a road generated with GD 450 gives back ~450 at 0.1 cycles/m.

Prints prescribed against recovered GD for a few GDs and seeds (150 m and 21 m roads, 6 mm grid)
and saves the profile/PSD figures of the GD 450 road (paper Figs 3-4) and of the paper's track
(GD 300 / 500 / 300, 50 m each).

    python examples/roadgen_psd_check.py [--out DIR]     # default ./out/; ~2 s
"""

from __future__ import annotations

import argparse

import matplotlib

matplotlib.use("Agg")

from _cli import output_folder, path_option, run, save_figure  # noqa: E402

import roadgen  # noqa: E402

GDS = (200.0, 300.0, 450.0, 600.0)
SEEDS = (0, 1, 2)
LENGTHS = (150.0, 21.0)
KEY = f"""recovered GD of each road (prescribed: GD):
  at n0: the paper's check, the one periodogram ordinate at 0.1 cycles/m: exact for
         deterministic amplitudes; for rayleigh ones (a random road's) it scatters as one
         chi^2_2 ordinate, an exponential variable
  fit:   fixed-slope fit over {roadgen.psd.FIT_BAND[0]:g}-{roadgen.psd.FIT_BAND[1]:g} cycles/m
         (roadgen.estimate_gd's default); welch: the same fit to the Welch PSD (150 m roads
         only; "-" on the 21 m ones)
  slope: the fitted slope of log Gd on log n (ISO 8608: -2)
"""


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--out", type=path_option, default="out", help="folder for the figures (default ./out)"
    )
    args = parser.parse_args(argv)
    out = output_folder(parser, "--out", args.out)

    road = roadgen.iso8608_profile(150.0, 450.0, seed=0)
    # the figures first: a reader that stops reading (`... | head`) ends the script at a print
    fig = roadgen.plot_profile_psd(road, title="ISO 8608 profile, prescribed GD 450")
    path = out / "roadgen_psd_gd450.png"
    save_figure(fig, path)
    track = roadgen.track([(50, 300), (50, 500), (50, 300)], seed=0)
    track_path = out / "roadgen_track.png"
    save_figure(
        roadgen.plot_profile_psd(track, title="the paper's track: GD 300 / 500 / 300"), track_path
    )
    print(
        f"paper check: GD 450, 150 m, 6 mm -> periodogram at 0.1 cycles/m gives "
        f"{roadgen.estimate_gd(road, method='periodogram'):.1f}, fit "
        f"{roadgen.estimate_gd(road):.1f}, class {roadgen.road_class(450.0)}"
    )
    print()
    print(KEY)
    header = f"{'amplitudes':>13} {'length m':>8} {'GD':>6} {'seed':>4} {'at n0':>8} {'fit':>8}"
    print(header + f" {'welch':>8} {'slope':>6}")
    for amplitudes in ("deterministic", "rayleigh"):
        for length in LENGTHS:
            for gd in GDS:
                for seed in SEEDS:
                    p = roadgen.iso8608_profile(length, gd, seed=seed, amplitudes=amplitudes)
                    welch = f"{roadgen.estimate_gd(p, 'welch'):8.1f}" if length >= 100 else "-"
                    print(
                        f"{amplitudes:>13} {length:8.0f} {gd:6.0f} {seed:4d} "
                        f"{roadgen.estimate_gd(p, 'periodogram'):8.1f} "
                        f"{roadgen.estimate_gd(p):8.1f} {welch:>8} {roadgen.psd_slope(p):6.2f}"
                    )
    print(f"\nsaved {path} and {track_path}")


if __name__ == "__main__":
    run(main)
