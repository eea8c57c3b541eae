"""The paper's Test Cases A and B in closed loop: BCR + Simplex on the 150 m track, three runs each.

    python examples/closed_loop.py                # writes ./out/metrics.json and the figures
    python examples/closed_loop.py --out DIR --runs 3 --method changepoint --law linear
    python examples/closed_loop.py --record runs/   # also one MCAP per run, for Foxglove
    python examples/closed_loop.py --track 40:250,30:450,60:350 --first-seed 21   # another track
    python examples/closed_loop.py --emulator-dir mine/emulators   # your emulators (and robot)
    python examples/closed_loop.py --emulator-dir mine/emulators --v-max 1.5   # a slower robot

Track: 50 m at GD 300, 50 m at GD 500, 50 m at GD 300 (roadgen.track), or ``--track`` (segments
``LENGTH_M:GD``, GD within the emulators' domain, 200-600). Test Case A: noise-free
accelerations and the noise-free emulators; Test Case B: N(0, 1) accelerometer noise and the
emulators trained with it. Run k drives a track synthesised with seed k (and noise seed k), for
k = FIRST_SEED .. FIRST_SEED + RUNS - 1. ``--emulator-dir DIR`` takes the four emulators that
``examples/train_emulator.py --emulator-dir DIR`` writes instead of the shipped ones; the loop then
drives the vehicle they were trained for, with their noise level. The Simplex's speeds
(``--v-safe``, ``--v-max``; the paper's 1.0 and 2.0 m/s) must lie in the emulators' speed range,
and its GD band (``--gd-min``, ``--gd-max``; the paper's 250 and 350) fit their GD range: its
``--gd-max`` above the lowest GD and below the highest. A run whose Simplex a fault latched in
safety mode (v_safe for the rest of the run) is named below the tables, with the estimate that
latched it.

Each case is run twice: with our estimator (default: the change-point BCR on log band powers of
1 s blocks, `control.bcr`) and with the paper's method run here (one 1,000-sample window, its
log variance, the paper's uniform prior: ``method="window"``). The RMSE is that of the
posterior-mean GD at each estimate's position against the GD prescribed there, pooled over the
runs, for each prescribed GD of the track; the table prints the paper's figures (on the paper's
track), the paper's method run here, and ours. A "-" in the tables (null in metrics.json): no
estimate on that part (shorter than the first block), or a change the estimate never crossed.
"""

from __future__ import annotations

import argparse
import inspect
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
from _cli import check_seed, output_folder, path_option, run, save_figure, write_text  # noqa: E402

import control  # noqa: E402
import gpmsa  # noqa: E402
import roadgen  # noqa: E402
import vehicle  # noqa: E402
from control.bcr import emulator_domain  # noqa: E402
from control.closed_loop import gd_key  # noqa: E402
from control.metrics import strict_json  # noqa: E402
from control.plotting import plot_gd_trace, plot_speed  # noqa: E402
from control.shipped import EMULATOR_DIR, emulator_file_name  # noqa: E402
from control.validation import within  # noqa: E402
from gpmsa.model.data import repr_name  # noqa: E402

PAPER_SEGMENTS = ((50.0, 300.0), (50.0, 500.0), (50.0, 300.0))
PAPER_RMSE = {"A": {"300": 42.58, "500": 94.42}, "B": {"300": 50.19, "500": 96.23}}


TRACK_DEFAULTS = inspect.signature(roadgen.track).parameters
LEAD_IN_M = TRACK_DEFAULTS["lead_in_m"].default
"""roadgen.track's lead-in from flat ground at the start of the first segment, m."""
BLEND_M = TRACK_DEFAULTS["blend_m"].default
"""roadgen.track's cross-fade between neighbouring segments, m."""

GD_MAX = 1e6
"""Largest GD (1e-6 m^3) the scripts take: beyond ISO 8608's roughest class (H, from 131072),
far beyond what a small robot survives (its drive ends with `vehicle.SimulationDivergedError`)."""


def parse_segments(text: str) -> tuple[tuple[float, float], ...]:
    """``"50:300,50:500,50:300"`` -> ((50.0, 300.0), (50.0, 500.0), (50.0, 300.0)): length in m, GD.

    Raises ValueError naming the segment that is not ``LENGTH:GD`` with two finite positive
    numbers, GD at most `GD_MAX`, length at least roadgen.track's (`_check_lengths`), and
    naming two GDs that differ but print alike to six digits (``f"{gd:g}"``), which a reader
    of the tables would take for one.
    """
    segments = []
    labels: dict[str, float] = {}
    for part in text.split(","):
        fields = part.strip().split(":")
        try:
            length, gd = (float(f) for f in fields)
        except ValueError:
            raise ValueError(f"segment {part.strip()!r} is not LENGTH_M:GD (e.g. 50:300)") from None
        if not (np.isfinite(length) and np.isfinite(gd) and length > 0 and gd > 0):
            raise ValueError(f"segment {part.strip()!r}: length and GD must be finite and > 0")
        if gd > GD_MAX:
            raise ValueError(f"segment {part.strip()!r}: GD must be at most {GD_MAX:g}")
        if labels.setdefault(f"{gd:g}", gd) != gd:
            raise ValueError(
                f"segment {part.strip()!r}: GD {gd!r} differs from GD {labels[f'{gd:g}']!r} but "
                f"both print as {gd:g} to six digits, one GD to a reader of the tables: give "
                "both parts one GD, or GDs that differ within six digits"
            )
        segments.append((length, gd))
    _check_lengths(segments, [part.strip() for part in text.split(",")])
    return tuple(segments)


def _check_lengths(segments: list[tuple[float, float]], parts: list[str]) -> None:
    """ValueError naming the first segment shorter than roadgen.track allows with its default
    lead-in (`LEAD_IN_M`) and blend (`BLEND_M`): the first segment holds the lead-in and half a
    blend, every other segment a blend."""
    several = len(segments) > 1
    for k, ((length, _), part) in enumerate(zip(segments, parts, strict=True)):
        shortest = BLEND_M if k else LEAD_IN_M + (0.5 * BLEND_M if several else 0.0)
        if length < shortest:
            if k:
                why = f"the {BLEND_M:g} m blend between segments"
            else:
                why = f"the {LEAD_IN_M:g} m lead-in from flat ground" + (
                    f" and half the {BLEND_M:g} m blend into the next segment" if several else ""
                )
            raise ValueError(
                f"segment {part!r} is {length:g} m long: it must be at least {shortest:g} m "
                f"({why}); lengthen it or merge it with a neighbour"
            )


def figure(value: float | None, spec: str) -> str:
    """`value` formatted with `spec`, or "-" when it is NaN or None (no estimate, a change never
    seen: `LoopMetrics.as_dict` gives None)."""
    return "-" if value is None or np.isnan(value) else format(value, spec)


def run_case(
    case: str,
    emu,
    seeds: range,
    method: str,
    simplex: control.Simplex,
    segments=PAPER_SEGMENTS,
    record: Path | None = None,
    checked: bool = True,
) -> list:
    """The closed-loop results of one test case and estimator on emulator ``emu``, one per seed
    (track and noise), on the vehicle and at the noise level the emulator was trained for; with
    ``record``, each run is also written there as ``case{A,B}_{method}_run{k}.mcap``
    (control.record_run). ``checked=False``: the emulator is not checked against the run (the
    caller has checked all but the track's GD)."""
    bcr = control.bcr_settings_for(emu, method=method)
    likelihood = control.BCR.from_emulator(emu, bcr).model  # prepared once for all runs
    return [
        control.run_closed_loop(
            roadgen.track(segments, seed=k),
            emu,
            model=control.emulator_vehicle(emu),
            noise_std=control.emulator_noise_std(emu) or 0.0,
            seed=k,
            bcr=bcr,
            simplex=simplex,
            likelihood=likelihood,
            record=record / f"case{case}_{method}_run{k}.mcap" if record else None,
            check=checked,
        )  # fmt: skip
        for k in seeds
    ]


def check_same_robot(band, window) -> None:
    """EmulatorMismatchError unless the band and window emulators of one case record one
    vehicle and one noise level: each run drives the robot its emulator records
    (`run_case`), so emulators of two robots would compare the methods on different ones."""
    robots = [control.emulator_vehicle(emu).describe() for emu in (band, window)]
    differ = [
        f"{k}: band {robots[0].get(k)!r} vs window {robots[1].get(k)!r}"
        for k in sorted(set(robots[0]) | set(robots[1]))
        if robots[0].get(k) != robots[1].get(k)
    ]
    noise = (control.emulator_noise_std(band) or 0.0, control.emulator_noise_std(window) or 0.0)
    if not np.isclose(*noise):
        differ.append(f"noise sd: band {noise[0]:g} vs window {noise[1]:g} m/s^2")
    if differ:
        raise control.EmulatorMismatchError(", ".join(differ))


def latched_by(result) -> str | None:
    """``"STATUS: REASON"`` of the estimate that latched the run's Simplex in safety mode (the
    rest of the run at v_safe), None where none did."""
    when = result.metrics.latched_at_s
    if not np.isfinite(when):
        return None
    k = int(np.argmin(np.abs(result.time - when)))
    return f"{result.status[k]}: {result.reason[k]}"


def summarise(results, gds: list[float]) -> dict:
    """Pooled RMSE per prescribed GD (keys `gd_key`'s, as the per-run metrics'), pooled
    interval coverage and the per-run metrics (with ``domain_edge``: how many estimates named
    each edge of the emulator's GD domain; ``latched_by``: the estimate that latched safety
    mode, `latched_by`); NaN where a part has no estimate."""
    errors = [r.metrics.gd_errors for r in results]
    ok = np.concatenate([np.isfinite(r.gd_mean) for r in results])
    lo, hi, true = (
        np.concatenate([getattr(r, k) for r in results]) for k in ("gd_lo", "gd_hi", "gd_true")
    )
    covered = (lo[ok] <= true[ok]) & (true[ok] <= hi[ok])
    return {
        "rmse": {gd_key(gd): control.pooled_rmse(errors, gd) for gd in gds},
        "coverage": float(np.mean(covered)) if covered.size else float("nan"),
        "runs": [
            {
                **r.metrics.as_dict(),
                "domain_edge": control.edge_counts(r.domain_edge),
                "latched_by": latched_by(r),
            }
            for r in results
        ],
    }


def main(argv: list[str] | None = None) -> dict:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--out", type=path_option, default="out",
        help="folder for metrics.json and the figures (default ./out)",
    )  # fmt: skip
    parser.add_argument("--runs", type=int, default=3, help="runs per test case (default 3)")
    parser.add_argument(
        "--first-seed", type=int, default=1,
        help="run k drives track and noise seed k, k = FIRST_SEED .. FIRST_SEED + RUNS - 1 "
        "(default 1)",
    )  # fmt: skip
    parser.add_argument(
        "--track", default=None, metavar="L:GD,...",
        help="segments LENGTH_M:GD, e.g. 50:300,50:500,50:300 (the paper's track, the default)",
    )  # fmt: skip
    parser.add_argument(
        "--beyond-domain", action="store_true",
        help="allow a --track GD outside the emulators' GD domain, to see the estimate name the "
        "domain's edge (docs/closed-loop.md, Guards); its RMSE there is no fair score",
    )  # fmt: skip
    parser.add_argument(
        "--method", default="changepoint", choices=list(control.METHODS),
        help="our estimator: changepoint (default), or the window methods for comparison",
    )  # fmt: skip
    parser.add_argument(
        "--risk", type=float, default=None,
        help="risk posture alpha: drive on the (1 - alpha) posterior quantile of GD (default: the "
        "posterior mean, the paper's)",
    )  # fmt: skip
    parser.add_argument(
        "--law", default="linear", choices=list(control.simplex.LAWS),
        help="Simplex performance law: linear (default), paper (eq. 8 literally), switch",
    )  # fmt: skip
    parser.add_argument(
        "--record", type=path_option, default=None, metavar="DIR",
        help="write each run as an MCAP file in DIR, to watch in Foxglove with "
        "examples/foxglove_layout.json (needs the robot extra)",
    )  # fmt: skip
    parser.add_argument(
        "--speed-step", type=float, default=control.Simplex.speed_step_mps, metavar="M_PER_S",
        help="the Simplex rounds its speed down to this grid, m/s (0: the continuous law; "
        "docs/closed-loop.md)",
    )  # fmt: skip
    parser.add_argument(
        "--release-m", type=float, default=control.Simplex.release_m, metavar="M",
        help="the Simplex's release dwell, m: after safety mode, performance mode again only "
        "once the law has read it over this much travel (default 0: none; docs/closed-loop.md)",
    )  # fmt: skip
    parser.add_argument(
        "--v-max", type=float, default=control.Simplex.v_max, metavar="M_PER_S",
        help="the Simplex's top speed, m/s (default 2.0, the paper's; within the emulators' "
        "speed range and the vehicle's top speed)",
    )  # fmt: skip
    parser.add_argument(
        "--v-safe", type=float, default=control.Simplex.v_safe, metavar="M_PER_S",
        help="the Simplex's safety-mode speed, m/s (default 1.0, the paper's)",
    )  # fmt: skip
    parser.add_argument(
        "--gd-min", type=float, default=control.Simplex.gd_min, metavar="GD",
        help="the Simplex's GD band, 1e-6 m^3: v_max at and below --gd-min (default 250, the "
        "paper's) ...",
    )  # fmt: skip
    parser.add_argument(
        "--gd-max", type=float, default=control.Simplex.gd_max, metavar="GD",
        help="... v_safe at --gd-max and safety mode above it (default 350, the paper's); "
        "within the emulators' GD range",
    )  # fmt: skip
    parser.add_argument(
        "--cases", nargs="+", choices=["A", "B"], default=["A", "B"],
        help="test cases: A (noise-free), B (with the noise the case-B emulators were trained on) "
        "(default A B)",
    )  # fmt: skip
    parser.add_argument(
        "--emulator-dir", type=path_option, default=None, metavar="DIR",
        help="the emulators DIR/jackal_{A,B}[_window].gpmsa made by examples/train_emulator.py "
        "--emulator-dir DIR, instead of the shipped ones",
    )  # fmt: skip
    args = parser.parse_args(argv)
    args.cases = list(dict.fromkeys(args.cases))  # each case once
    if args.runs < 1:
        parser.error(f"--runs must be >= 1, got {args.runs}")
    check_seed(parser, args.first_seed, args.runs - 1, "--first-seed")  # each run's seed
    try:
        segments = PAPER_SEGMENTS if args.track is None else parse_segments(args.track)
        track = roadgen.track(segments, seed=args.first_seed)
    except ValueError as err:  # RoadgenError is a ValueError
        parser.error(f"--track: {err}")
    seeds = range(args.first_seed, args.first_seed + args.runs)
    gds = sorted({gd for _, gd in segments})
    paper_track = tuple(segments) == PAPER_SEGMENTS
    try:
        control.Simplex(risk=args.risk)
    except control.ControlError as err:
        parser.error(f"--risk: {err}")
    try:
        control.Simplex(gd_min=args.gd_min, gd_max=args.gd_max)
    except control.ControlError as err:
        parser.error(f"--gd-min / --gd-max: {err}")
    try:
        control.Simplex(release_m=args.release_m)
    except control.ControlError as err:
        parser.error(f"--release-m: {err}")
    try:  # the speeds are checked together (v_safe <= v_max, the step <= v_max); --law: choices
        simplex = control.Simplex(
            risk=args.risk, law=args.law, speed_step_mps=args.speed_step,
            v_max=args.v_max, v_safe=args.v_safe, gd_min=args.gd_min, gd_max=args.gd_max,
            release_m=args.release_m,
        )  # fmt: skip
    except control.ControlError as err:
        parser.error(f"--v-safe, --v-max, --speed-step: {err}")
    emulator_dir = Path(args.emulator_dir) if args.emulator_dir else None
    try:  # every file before the first run
        emulators = {
            (case, kind): control.shipped_emulator(case, kind, emulator_dir)
            for case in args.cases
            for kind in ("band", "window")
        }
    except (control.ControlError, gpmsa.EmulatorFileError) as err:
        parser.error(f"--emulator-dir: {err} (or leave that case out: --cases)")
    for emu in emulators.values():  # the runs' checks of the files, before the first run
        try:
            bcr = control.bcr_settings_for(emu)
            control.check_emulator(emu, model=control.emulator_vehicle(emu), bcr=bcr)
        except control.ControlError as err:  # a user's file without or with garbled records
            parser.error(f"--emulator-dir: {err}")
        try:
            control.check_emulator(emu, track=track)
        except control.EmulatorMismatchError as err:  # a GD outside the emulator's domain
            if not args.beyond_domain:
                parser.error(f"--track: {err} (--beyond-domain drives it anyway)")
        try:
            control.check_emulator(emu, simplex=simplex)
        except control.EmulatorMismatchError as err:  # speeds, or GD band, outside the domain
            (v_lo, v_hi), _ = emulator_domain(emu)
            speeds = all(within(v, v_lo, v_hi) for v in (simplex.v_safe, simplex.v_max))
            parser.error(f"{'--gd-min / --gd-max' if speeds else '--v-safe / --v-max'}: {err}")
    for case in args.cases:  # the two methods of a case are compared on one robot
        try:
            check_same_robot(emulators[case, "band"], emulators[case, "window"])
        except control.EmulatorMismatchError as err:
            where = emulator_dir if emulator_dir else EMULATOR_DIR
            parser.error(
                f"--emulator-dir: case {case}'s {emulator_file_name(case, 'band')} and "
                f"{emulator_file_name(case, 'window')} were trained for different robots "
                f"({err}), so its table would compare the two methods on different robots (one "
                f"left from an earlier training?): train both for one robot (examples/"
                f"train_emulator.py --features band window --emulator-dir {where})"
            )
    if args.record:
        from control.robot.record import check_can_record

        try:
            check_can_record()
        except control.ControlError as err:  # MissingExtraError: the robot extra
            parser.error(f"--record: {err}")
    out = output_folder(parser, "--out", args.out)
    record = output_folder(parser, "--record", args.record) if args.record else None

    metrics: dict = {"ours": {}, "paper_method": {}}
    figures = {}  # written once every run has finished: a failed run leaves no partial set
    for case in args.cases:
        noise = control.emulator_noise_std(emulators[case, "band"])
        title = f"Test Case {case} ({f'N(0, {noise**2:g}) noise' if noise else 'noise-free'})"
        for key, method in (("ours", args.method), ("paper_method", "window")):
            emu = emulators[case, "band" if method == "changepoint" else "window"]
            try:
                results = run_case(case, emu, seeds, method, simplex, segments, record,
                                   checked=not args.beyond_domain)  # fmt: skip
            except vehicle.SimulationDivergedError as err:  # a road far rougher than any known
                parser.error(f"--track: the vehicle left the road ({err}); lower the track's GD")
            metrics[key][case] = summarise(results, gds)
            label = "ours" if key == "ours" else "paper's method"
            figures[f"gd_trace_{case}_{key}.png"] = plot_gd_trace(
                results, track, title=f"{title}, {label}: GD", gd_max=simplex.gd_max
            )
            figures[f"speed_{case}_{key}.png"] = plot_speed(
                results, track, title=f"{title}, {label}: speed", gd_max=simplex.gd_max,
                v_safe=simplex.v_safe,
            )  # fmt: skip
    for name, fig in figures.items():
        save_figure(fig, out / name, dpi=150)
    if paper_track:
        metrics["paper"] = PAPER_RMSE
    metrics["settings"] = {**vars(args), "segments": segments, "seeds": list(seeds)}
    # written before the tables: a reader that stops reading (`... | head`) ends it at a print
    write_text(out / "metrics.json", json.dumps(strict_json(metrics), indent=2, allow_nan=False))

    source = "paper: Lewis et al. 2025" if paper_track else "no paper figures for this track"
    which = f"seed {seeds.start}" if len(seeds) == 1 else f"seeds {seeds.start}-{seeds[-1]} pooled"
    # GD's unit in brackets, as `gpmsa info` prints it, where the emulators record one alike
    units = {str(emu.t_units[0]) if emu.t_units else "" for emu in emulators.values()}
    named = units.pop() if len(units) == 1 else ""  # (two cases with different units: none)
    unit = f" [{repr_name(named)}]" if named else ""
    print(f"RMSE of the GD estimate{unit}, {which} ({source})")
    print(f"{'case':<6}{'part':<9}{'paper':>8}{'paper method':>14}{'ours':>8}   ours per run")
    for case in args.cases:
        ours = metrics["ours"][case]
        for gd in ours["rmse"]:
            per_run = " ".join(f"{figure(r['rmse'][gd], '.1f'):>6}" for r in ours["runs"])
            paper = PAPER_RMSE[case].get(gd, np.nan) if paper_track else np.nan
            print(
                f"{case:<6}{'GD ' + gd:<9}{figure(paper, '.1f'):>8}"
                f"{figure(metrics['paper_method'][case]['rmse'][gd], '.1f'):>14}"
                f"{figure(ours['rmse'][gd], '.1f'):>8}   {per_run}"
            )
    print()
    head = (f"fast on GD>{simplex.gd_max:g}", "90% cover", "time (s)", "x real time")
    print(f"{'case':<6}{'seed':<6}" + "".join(f"{h:>{len(h) + 2}}" for h in head)
          + "   delay at each change (m)")  # fmt: skip
    for case in args.cases:
        for k, r in zip(seeds, metrics["ours"][case]["runs"], strict=True):
            delays = " ".join(figure(d, ".1f") for d in r["detection_delay_m"])
            print(
                f"{case:<6}{k:<6}{r['fast_on_rough_m']:{len(head[0])}.1f} m"
                f"{figure(r['coverage'], '.2f'):>11}{r['traversal_time_s']:10.1f}"
                f"{r['real_time_factor']:13.0f}   {delays}"
            )
    latched = [
        f"{case} seed {k} ({label}): at {r['latched_at_s']:.2f} s, {r['latched_by']}"
        for case in args.cases
        for key, label in (("ours", "ours"), ("paper_method", "paper's method"))
        for k, r in zip(seeds, metrics[key][case]["runs"], strict=True)
        if r["latched_by"] is not None
    ]
    if latched:
        print("\nruns latched in safety mode by a fault (v_safe for the rest of the run):")
        print("\n".join(f"  {line}" for line in latched))
    edges = [
        f"{case} seed {k}: " + ", ".join(f"{n} {e}" for e, n in r["domain_edge"].items() if n)
        for case in args.cases
        for k, r in zip(seeds, metrics["ours"][case]["runs"], strict=True)
        if any(r["domain_edge"].values())
    ]
    if edges:
        print("\nestimates naming an edge of the emulator's GD domain (the road may lie beyond):")
        print("\n".join(f"  {line}" for line in edges))
    print(f"\nwrote {out / 'metrics.json'} and the figures gd_trace_*.png, speed_*.png")
    if args.record:
        print(f"wrote one MCAP per run in {args.record} (open in Foxglove with "
              "examples/foxglove_layout.json)")  # fmt: skip
    return metrics


if __name__ == "__main__":
    run(main)
