"""``terrain-replay``: run the BCR and the Simplex over a robot's recording.

    terrain-replay BAG --emulator jackal.gpmsa [--out DIR] [--imu-topic /imu/data]
                   [--odom-topic /odometry/filtered] [--axis z] [--sign 1] ...

BAG: a ROS 2 bag folder (MCAP or sqlite3), a ``*.mcap`` file or a ROS 1 ``*.bag``. Writes
``DIR/estimates.csv``, ``DIR/estimates/`` (a ROS 2 bag with the topic ``/bcr/estimate``) and
``DIR/replay.json`` (settings, what was found in the recording, timing; strict JSON: a number
that is not finite, such as the rate of a topic with one message, is ``null``), and prints a
summary. DIR may not lie inside the recording (its bag folder, for a file given inside one),
as ``replay_bag`` refuses its outputs there: replaying ``.`` from inside a bag folder needs an
``--out`` outside it. DIR is made only once the replay has run, and removed again (with the
parents this made) if writing into it fails, where nothing else was written into it meanwhile;
a folder that was there before is never removed, none of the three outputs may be there
already (nor appear before each is written: another run given the same DIR), and a failed
write removes those it wrote, and only those. A reader that has gone (``| head -1``) ends
nothing: the outputs are written, exit status 0.
Exit status 0 on success, also for a recording too short for one estimate (the summary then
says "no estimate" and why); 2 with a one-line message on a usage error (``--out`` a file or
inside the recording, a setting out of range), an emulator file that is missing or cannot be
loaded, a recording that cannot be replayed (a missing topic, a damaged file, a simulated
recording that records another vehicle than the emulator's, ...) or a missing extra (the
message says which extra to install). ``--ignore-vehicle`` replays such a simulated recording
anyway (`replay_bag`'s ``check_vehicle=False``; a note says so); a robot's recording records
no vehicle and is never refused for one.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import shutil
import sys
from dataclasses import asdict
from pathlib import Path

from control.compat import check_emulator
from control.errors import ControlError, MissingExtraError
from control.estimate import edge_counts
from control.metrics import strict_json
from control.robot.bags import check_bag_path
from control.robot.replay import (
    GRAVITY,
    POSITIONS,
    SHIPPED,
    TIME_BASES,
    ReplayResult,
    ReplaySettings,
    load_emulator,
    overlapped_input,
    replay_bag,
    replay_inputs,
)
from control.simplex import Simplex
from gpmsa._version import __version__
from gpmsa.io.atomic import atomic_write
from roadgen.checks import home_path

DEFAULTS = ReplaySettings()
OUTPUTS = ("estimates.csv", "estimates", "replay.json")
"""What the command writes into --out."""


def _one_line(exc: Exception) -> str:
    """The message of ``exc`` on one line (a library's message may hold line breaks)."""
    return " ".join(str(exc).split())


def _check_out(out: Path) -> None:
    """`ControlError` where ``out``, or its nearest existing parent, is not a folder, or where
    ``out`` holds any of `OUTPUTS` already, a dangling link included (checked before the replay
    runs)."""
    there = next((p for p in (out, *out.parents) if p.exists()), None)
    if there == out and not out.is_dir():
        raise ControlError(f"--out {str(out)!r} exists and is not a folder")
    if there is not None and not there.is_dir():
        raise ControlError(f"--out {str(out)!r}: {str(there)!r} exists and is not a folder")
    there_already = [name for name in OUTPUTS if os.path.lexists(out / name)]  # links too
    if there_already:
        raise ControlError(
            f"{out / there_already[0]} exists already: choose another --out (this command "
            f"writes {', '.join(OUTPUTS)} and overwrites none of them)"
        )


def _check_out_apart(out: Path, bag: Path, default: bool) -> None:
    """`ControlError` where ``out`` is, or lies inside, the recording (the whole bag folder of a
    file given inside one), as `replay_bag` refuses its ``csv`` and ``out_bag`` there (an
    emulator file holds no folder; ``out`` that file: `_check_out`); ``default``: ``out`` is
    the default, BAG's name + _bcr."""
    what = overlapped_input(out, replay_inputs(bag, None))
    if what is not None:
        given = (f"the default --out {str(out)!r} (BAG's name + _bcr, in the current folder)"
                 if default else f"--out {str(out)!r}")  # fmt: skip
        raise ControlError(
            f"{given} lies inside {what}: the outputs would be written into what is read; "
            "give --out a folder outside it"
        )


def _report(
    bag: Path, source: str, settings: ReplaySettings, simplex: Simplex, result: ReplayResult
) -> dict:
    """The content of ``replay.json`` (``simplex``: the settings whose commands the outputs
    hold)."""
    return {
        "bag": str(bag),
        "emulator": source,
        "settings": asdict(settings),
        "simplex": asdict(simplex),
        "imu": asdict(result.imu),
        "odometry": asdict(result.odometry),
        "restamping": asdict(result.restamping),
        "resampling": asdict(result.resampling),
        "notes": list(result.notes),
        "status_counts": result.status_counts(),
        "domain_edge_counts": edge_counts(result.domain_edge),
        "timing_s": {"read": result.read_s, "resample": result.condition_s, "bcr": result.bcr_s},
        "duration_s": result.duration_s,
        "real_time_factor": result.real_time_factor,
    }


def _write(out: Path, result: ReplayResult, report: dict) -> None:
    """Write the estimates (CSV, ROS 2 bag) and the report (strict JSON) into ``out``, made
    here where it is missing. Each output is refused (`ControlError`) where it has appeared
    since `_check_out` (another run given the same ``--out``; an output file's name is taken
    by `_reserve` before it is written, so that two such runs cannot write over each other's
    at the same time); on a failure only what this
    call wrote is removed: its outputs, then the folders it made, where they are empty (another
    run may have written into them)."""
    made, written = [], []
    try:
        for folder in reversed((out, *out.parents)):  # the outermost missing one first
            if folder.exists():
                continue
            try:
                folder.mkdir()
                made.append(folder)
            except FileExistsError:  # made meanwhile by another run: not this one's
                pass
            except OSError as exc:
                raise ControlError(f"--out {str(out)!r}: cannot make it ({exc.strerror})") from exc
        text = json.dumps(strict_json(report), indent=2, allow_nan=False)
        for name, write in (
            ("estimates.csv", lambda path: result.to_csv(path)),
            ("estimates", lambda path: result.write_bag(path)),
            ("replay.json", lambda path: _write_text(path, text)),
        ):
            path = out / name
            if name == "estimates":  # a new folder, moved into place whole (open_bag_writer)
                _refuse_existing(path)
                write(path)
                written.append(path)
                continue
            _reserve(path)  # a file: made empty here, so another run's cannot take its place
            written.append(path)
            write(path)
    except BaseException:
        for path in written:
            if path.is_dir() and not path.is_symlink():
                shutil.rmtree(path, ignore_errors=True)
            else:  # a read-only file system refuses to unlink a missing file too (EROFS)
                with contextlib.suppress(OSError):
                    path.unlink(missing_ok=True)
        for folder in reversed(made):  # the innermost first; one holding another's files stays
            with contextlib.suppress(OSError):
                folder.rmdir()
        raise


def _refuse_existing(path: Path) -> None:
    """`ControlError` where ``path`` has appeared since `_check_out`."""
    if os.path.lexists(path):
        raise _appeared(path)


def _appeared(path: Path) -> ControlError:
    return ControlError(
        f"{path} exists already (written since the check of --out: another run given the same "
        "--out?); choose another --out"
    )


def _reserve(path: Path) -> None:
    """Make ``path`` an empty file, where nothing is there (a link to nowhere too): an output
    file's name taken in one step, so that two runs given one ``--out`` cannot both write it
    (the writers replace an empty file); `ControlError` otherwise."""
    try:
        os.close(os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
    except FileExistsError:
        raise _appeared(path) from None
    except OSError as exc:
        raise ControlError(f"{path}: cannot write ({exc.strerror})") from exc


def _write_text(path: Path, text: str) -> None:
    """``text`` (UTF-8) written to ``path`` in one step."""
    with atomic_write(path, text=True, error=ControlError) as fh:
        fh.write(text)


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="terrain-replay",
        description="Run the terrain-roughness estimator (BCR) and the Simplex speed controller "
        "over a ROS bag's IMU and odometry; write the estimates as CSV and as a ROS 2 bag.",
    )
    p.add_argument("bag", help="ROS 2 bag folder (mcap or sqlite3), *.mcap file or ROS 1 *.bag")
    p.add_argument(
        "--emulator", required=True,
        help="the emulator file (*.gpmsa) trained for this vehicle and IMU; A or B: the shipped "
        "Jackal ones (noise-free / N(0, 1) noise)",
    )  # fmt: skip
    p.add_argument(
        "--out", default=None,
        help="output folder, outside the recording (default: BAG's name + _bcr, in the current "
        "folder)",
    )  # fmt: skip
    p.add_argument("--imu-topic", default=DEFAULTS.imu_topic, help="sensor_msgs/msg/Imu topic")
    p.add_argument("--odom-topic", default=DEFAULTS.odom_topic, help="nav_msgs/msg/Odometry topic")
    p.add_argument(
        "--axis", default=DEFAULTS.imu_axis, choices=["x", "y", "z"],
        help="IMU axis that points up when the robot stands level",
    )  # fmt: skip
    p.add_argument(
        "--sign", type=float, default=1, choices=[1, -1],
        help="-1 if that axis points down (an IMU mounted upside down); 1.0 and -1.0 too",
    )  # fmt: skip
    p.add_argument(
        "--time-base", default=DEFAULTS.time_base, choices=list(TIME_BASES),
        help="header: the messages' stamps (default); log: the recorder's receive times",
    )  # fmt: skip
    p.add_argument(
        "--position", default=DEFAULTS.position, choices=list(POSITIONS),
        help="position along the path from the odometry's poses (path) or its speed (speed)",
    )  # fmt: skip
    p.add_argument(
        "--gravity", default=DEFAULTS.gravity, choices=list(GRAVITY),
        help="keep (each block is demeaned) or highpass (0.5 Hz, zero-phase) the acceleration; "
        "highpass an IMU that reads gravity with an emulator trained without noise (A)",
    )  # fmt: skip
    p.add_argument(
        "--static-mps2", type=float, default=None, metavar="M_PER_S2",
        help="the mean the up axis reads at rest, after --sign: 9.80665 for an IMU that reports "
        "gravity (specific force, REP-145); a block whose raw mean lies more than "
        "SensorLimits.static_tolerance (20%%) off it, or a span of static_span (1000) samples "
        "more than static_span_tolerance (7%%), is a scale fault (sensor_fault), with "
        "--gravity keep or highpass (checked before the filter); default: not checked",
    )  # fmt: skip
    p.add_argument(
        "--resample", default=DEFAULTS.resample, choices=["sample", "lowpass"],
        help="for an IMU faster than the emulator: sample (band-limited, the simulator's "
        "sensor model; default) or lowpass (anti-aliasing at the emulator's Nyquist frequency)",
    )  # fmt: skip
    p.add_argument(
        "--no-restamp", action="store_true",
        help="feed the IMU's stamps as recorded (default: put them on their fitted regular "
        "clock where they jitter by less than 1/6 period; dropped messages stay faults)",
    )  # fmt: skip
    p.add_argument(
        "--reorder-periods", type=float, default=DEFAULTS.reorder_periods, metavar="PERIODS",
        help="put IMU (and odometry) messages received out of header-stamp order by at most "
        "this many of their periods in stamp order (default 3; 0: the order received); "
        "odometry later still where its stamp fills the gap it left",
    )  # fmt: skip
    p.add_argument(
        "--storage", default=DEFAULTS.storage, choices=["mcap", "sqlite3"],
        help="storage of the output bag",
    )  # fmt: skip
    p.add_argument(
        "--v-max", type=float, default=Simplex.v_max, metavar="M_PER_S",
        help="the Simplex's top speed, m/s, for the commands it would have ordered (default "
        "2.0, the paper's; within the emulator's speed range)",
    )  # fmt: skip
    p.add_argument(
        "--v-safe", type=float, default=Simplex.v_safe, metavar="M_PER_S",
        help="the Simplex's safety-mode speed, m/s (default 1.0, the paper's)",
    )  # fmt: skip
    p.add_argument(
        "--release-m", type=float, default=Simplex.release_m, metavar="M",
        help="the Simplex's release dwell, m: after safety mode, performance mode again only "
        "once the law has read it over this much travel (default 0: none; docs/closed-loop.md)",
    )  # fmt: skip
    p.add_argument(
        "--ignore-vehicle", action="store_true",
        help="replay a simulated recording that records another vehicle than the emulator's "
        "(refused by default; a robot's recording records none)",
    )  # fmt: skip
    p.add_argument("--progress", action="store_true", help="show a progress bar")
    p.add_argument("--version", action="version", version=f"terrain-replay {__version__}")
    return p


def main(argv: list[str] | None = None) -> int:
    usage = parser()
    args = usage.parse_args(argv)
    if hasattr(sys.stdout, "reconfigure"):  # a path that the output's encoding (cp1252 in a
        sys.stdout.reconfigure(errors="backslashreplace")  # file on Windows) lacks: \u0141
    try:
        Simplex(release_m=args.release_m)
    except ControlError as err:
        usage.error(f"--release-m: {err}")
    for name, given in (("BAG", args.bag), ("--out", args.out), ("--emulator", args.emulator)):
        if given is not None and not given.strip():  # would mean the current folder
            print(f"terrain-replay: error: {name} is an empty path: give a file or folder name",
                  file=sys.stderr)  # fmt: skip
            return 2
    bag = home_path(args.bag)  # a leading ~ is the home folder, as replay_bag reads it
    default_out = Path(f"{bag.name.removesuffix(bag.suffix)}_bcr")
    out = default_out if args.out is None else home_path(args.out)
    try:
        settings = ReplaySettings(
            imu_topic=args.imu_topic,
            odom_topic=args.odom_topic,
            imu_axis=args.axis,
            imu_sign=float(args.sign),
            time_base=args.time_base,
            position=args.position,
            gravity=args.gravity,
            static_mps2=args.static_mps2,
            resample=args.resample,
            restamp=not args.no_restamp,
            reorder_periods=args.reorder_periods,
            storage=args.storage,
        )
        simplex = Simplex(v_max=args.v_max, v_safe=args.v_safe, release_m=args.release_m)
        _check_out_apart(out, bag, args.out is None)
        _check_out(out)
        check_bag_path(out / "estimates", settings.storage, "--out")
        emulator = load_emulator(args.emulator, "--emulator")
        check_emulator(emulator, simplex=simplex)
        progress = args.progress and sys.stderr is not None  # no bar where stderr is closed
        result = replay_bag(bag, emulator, settings, simplex=simplex, progress=progress,
                            check_vehicle=not args.ignore_vehicle)  # fmt: skip
        source = (
            f"shipped emulator {args.emulator}" if args.emulator in SHIPPED
            else str(home_path(args.emulator)) if args.emulator.startswith("~")  # as the shell
            else args.emulator
        )  # fmt: skip
        _write(out, result, _report(bag, source, settings, simplex, result))
    except MissingExtraError as exc:
        print(f"terrain-replay: {_one_line(exc)}", file=sys.stderr)
        return 2
    except (ControlError, OSError) as exc:  # OSError: e.g. a full disk
        print(f"terrain-replay: error: {_one_line(exc)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:  # Ctrl-C: one line, not a traceback (_write left no part)
        print("terrain-replay: interrupted (Ctrl-C)", file=sys.stderr)
        return 130
    try:
        print(result.describe())
        print(f"wrote {out / 'estimates.csv'}, {out / 'estimates'} (topic "
              f"{settings.estimate_topic}) and {out / 'replay.json'}")  # fmt: skip
        if sys.stdout is not None:  # None: stdout closed (`>&-`), print wrote nothing
            sys.stdout.flush()  # here, not at exit: a reader that has gone is no error
    except BrokenPipeError:  # `terrain-replay ... | head -1`: the outputs are written
        devnull = os.open(os.devnull, os.O_WRONLY)  # closed once stdout holds it
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    return 0


if __name__ == "__main__":
    sys.exit(main())
