"""Bad command-line arguments of the benchmark and example scripts are usage errors: exit status
2 and a one-line message naming the option and the value, before any long work (no traceback
from deep inside a library). Also: the accuracy benchmark drives the robot that its emulators
record."""

from pathlib import Path

import numpy as np
import pytest

import control
import vehicle
from tests._examples import load_benchmark
from tests._script_runs import run_scripts

ROOT = Path(__file__).resolve().parents[1]
FILE = "{file}"
"""In argv: an existing regular file where the script wants a folder; in the message: its path
as the script prints it (repr)."""
NOT_A_FOLDER = FILE + ": cannot make that folder"
BIG_SEED = str(2**128)
"""A seed just beyond the libraries' range [0, 2**128)."""
LAST_SEED = str(2**128 - 1)
"""The last seed in range: a script that derives more seeds from it goes beyond."""
FOLDER = "{folder}"
"""In argv: a fresh folder (for a script's output)."""

CASES = [
    ("benchmarks/backends.py", ["--repeats", "0"], "--repeats must be >= 1, got 0"),
    ("benchmarks/calibrate_speed.py", ["--updates", "10"], "--updates must be >= 1000"),
    ("benchmarks/chains.py", ["--numpy-iter", "4"], "--numpy-iter must be >= 5"),
    ("benchmarks/closed_loop_accuracy.py", ["--sets", ""], "--sets names no set, got ''"),
    ("benchmarks/closed_loop_accuracy.py", ["--cases", "X"], "--cases must be among"),
    (
        "benchmarks/closed_loop_accuracy.py",
        ["--mean-segment", "-1"],
        "--mean-segment: mean_segment_m must be finite and > 0, got -1",
    ),
    (
        "benchmarks/closed_loop_accuracy.py",
        ["--steady-roads", "1"],
        "--steady-roads must be >= 2 (a standard error needs two), got 1",
    ),
    (
        "benchmarks/closed_loop_accuracy.py",
        ["--steady-first-seed", "-1"],
        "--steady-first-seed must be >= 0, got -1",
    ),
    ("benchmarks/closed_loop_speed.py", ["--repeats", "0"], "--repeats must be >= 1, got 0"),
    ("benchmarks/closed_loop_speed.py", ["--long-m", "-1"], "--long-m must be a length >= 0"),
    ("benchmarks/closed_loop_speed.py", ["--replays", "0"], "--replays must be >= 1, got 0"),
    (
        "benchmarks/emulator_bias.py",
        ["--keep-s", "nan"],
        "--keep-s must be >= 16.67 s (two batches",
    ),
    ("benchmarks/emulator_bias.py", ["--workers", "0"], "--workers must be >= 1, got 0"),
    ("benchmarks/fault_soak.py", ["--scenarios", "0"], "--scenarios must be >= 1, got 0"),
    ("benchmarks/fault_soak.py", ["--example-seeds", "1", "-2"], "--example-seeds must be >= 0"),
    ("benchmarks/fault_soak.py", ["--speed-step", "-1"], "--speed-step: "),
    (
        "benchmarks/feature_information.py",
        ["--n-runs", "0"],
        "--n-runs must be >= 10 (a cubic mean per output), got 0",
    ),
    ("benchmarks/feature_information.py", ["--gd-band", "500", "300"], "--gd-band must lie in"),
    ("benchmarks/hierarchical_coverage.py", ["--sets", "0"], "--sets must be >= 1, got 0"),
    ("benchmarks/oracle_bounds.py", ["--seeds", "3-1"], "--seeds: '3-1' must name seeds >= 0"),
    ("benchmarks/oracle_bounds.py", ["--seeds", "1-x"], "--seeds: '1-x' is not a seed or a"),
    ("benchmarks/oracle_bounds.py", ["--cases", "C"], "--cases must be among"),
    ("benchmarks/oracle_bounds.py", ["--workers", "0"], "--workers must be >= 1, got 0"),
    ("benchmarks/replay_speed.py", ["--repeats", "0"], "--repeats must be >= 1, got 0"),
    ("benchmarks/reproducibility.py", ["--runs", "199"], "--runs must be in [1, 198]"),
    ("benchmarks/roadgen_speed.py", ["--repeats", "0"], "--repeats must be >= 1, got 0"),
    ("benchmarks/second_channel.py", ["--roads", "5"], "--roads must be an even integer >= 4"),
    ("benchmarks/second_channel.py", ["--duration-s", "10"], "--duration-s must be >= 30"),
    ("benchmarks/second_channel_loop.py", ["--sets", "x"], "--sets must name sets among"),
    ("benchmarks/second_channel_loop.py", ["--channels", "gyro"], "--channels must be among"),
    ("benchmarks/second_channel_loop.py", ["--out", FILE], "--out " + NOT_A_FOLDER),
    ("benchmarks/sensor_checks.py", ["--keep-s", "0.5"], "--keep-s must be >= 1.04 s"),
    ("benchmarks/sensor_checks.py", ["--seed", "-3"], "--seed must be >= 0, got -3"),
    ("benchmarks/sensor_checks.py", ["--drives", "0"], "--drives must be >= 1, got 0"),
    ("benchmarks/steady_hedge.py", ["--roads", "1"], "--roads must be >= 2 (a standard error"),
    (
        "benchmarks/steady_hedge.py",
        ["--gd", "700"],
        "--gd 700: outside emulator A's GDs [200, 600]",
    ),
    (
        "benchmarks/steady_hedge.py",
        ["--speeds", "3"],
        "--speeds 3: outside A's speeds [0.5, 2] m/s",
    ),
    ("benchmarks/steady_hedge.py", ["--cases", "C"], "--cases must be among"),
    ("benchmarks/vehicle_speed.py", ["--runs", "0"], "--runs must be >= 1, got 0"),
    ("examples/ball_drop.py", ["--runs", "11"], "--runs must be >= 12"),
    ("examples/ball_drop.py", ["--out", FILE], "--out " + NOT_A_FOLDER),
    ("examples/closed_loop.py", ["--risk", "1.5"], "--risk: risk must be None or lie in (0, 1)"),
    ("examples/closed_loop.py", ["--out", FILE], "--out " + NOT_A_FOLDER),
    (
        "examples/closed_loop.py",
        ["--v-max", "2.5"],
        "--v-safe / --v-max: the Simplex's v_max = 2.5 m/s lies outside the emulator's speed",
    ),
    (
        "examples/closed_loop.py",
        ["--speed-step", "-0.1"],
        "--v-safe, --v-max, --speed-step: speed_step_mps must lie in [0, v_max] = [0, 2]",
    ),
    (
        "examples/closed_loop.py",
        ["--v-safe", "1.5", "--v-max", "1.2"],
        "--v-safe, --v-max, --speed-step: v_safe must be <= v_max, got 1.5 and 1.2",
    ),
    ("examples/posterior_check.py", ["--seed", "-1"], "--seed must be >= 0, got -1"),
    ("examples/posterior_check.py", ["--out", FILE], "--out " + NOT_A_FOLDER),
    ("examples/roadgen_psd_check.py", ["--out", FILE], "--out " + NOT_A_FOLDER),
    ("examples/shared_theta.py", ["--n-iter", "1"], "--n-iter must be >= 2"),
    ("examples/shared_theta.py", ["--out", FILE], "--out " + NOT_A_FOLDER),
    (
        "examples/train_emulator.py",
        ["--vehicle", "mass_kg=abc"],
        "--vehicle 'mass_kg=abc': mass_kg must be a number",
    ),
    ("examples/train_emulator.py", ["--gd-range", "5", "1"], "--gd-range must be finite"),
    ("examples/train_emulator.py", ["--gd-range", "200", "1e300"], "HI <= 1e+06"),
    (
        "examples/train_emulator.py",
        ["--keep-s", "1", "--features", "window"],
        "--keep-s must be >= 8.333 s (the window emulators' window), got 1.0",
    ),
    ("examples/train_emulator.py", ["--n-iter", "10" * 10], "gpmsa.fit's draws needs about"),
    (
        "examples/train_emulator.py",
        ["--vehicle", "mass_kg=20", "mass_kg=30"],
        "--vehicle mass_kg is given twice",
    ),
    ("examples/train_emulator.py", ["--out", ""], "argument --out: an empty path"),
    (
        "examples/train_emulator.py",
        ["--emulator-dir", "control/emulators"],
        "is the shipped emulators' folder: use --ship",
    ),
    ("examples/closed_loop.py", ["--out", ""], "argument --out: an empty path"),
    ("examples/closed_loop.py", ["--record", " "], "argument --record: an empty path"),
    ("examples/closed_loop.py", ["--track", "50:1e7"], "GD must be at most 1e+06"),
    ("examples/closed_loop.py", ["--emulator-dir", FILE], "is not a folder"),
    (
        "examples/closed_loop.py",
        ["--runs", "1", "--cases", "A", "--beyond-domain", "--track", "5:300,10:200000"],
        "--track: the vehicle left the road",
    ),
    ("examples/ball_drop.py", ["--runs", "100000000"], "--runs 100000000: the GP's covariances"),
    ("examples/shared_theta.py", ["--n-iter", "10" * 10], "the draws needs about"),
    ("examples/posterior_check.py", ["--roads", "10" * 6], "--roads must be in [1, 10000]"),
    ("benchmarks/closed_loop_accuracy.py", ["--emulator-dir", ""], "an empty path"),
    ("examples/train_emulator.py", ["--keep-s", "0"], "--keep-s must be >= 16.67 s"),
    (
        "examples/train_emulator.py",
        ["--speed-range", "1.5", "0.5"],
        "--speed-range must be finite with 0 < LO < HI, m/s, got 1.5 0.5",
    ),
    (
        "examples/train_emulator.py",
        ["--speed-range", "0.5", "2.0000001"],  # was "HI = 2 m/s exceeds ... top speed 2 m/s"
        "--speed-range HI = 2.0000001 m/s exceeds the vehicle's top speed 2 m/s",
    ),
    (
        "examples/train_emulator.py",
        ["--speed-range", "0.5", "2.5"],
        "--speed-range HI = 2.5 m/s exceeds the vehicle's top speed 2 m/s",
    ),
    ("examples/train_emulator.py", ["--out", FILE], "--out " + NOT_A_FOLDER),
    (
        "examples/train_emulator.py",
        ["--anchor-speeds", "1.0", "2.5"],
        "--anchor-speeds 2.5: must lie in --speed-range [0.5, 2] m/s",
    ),
    (
        "examples/train_emulator.py",
        ["--anchor-speeds", "1.0", "--anchor-runs", "0"],
        "--anchor-runs must be in [1, --n-runs = 198] (runs at each anchor speed), got 0",
    ),
    (
        "examples/train_emulator.py",
        ["--ship", "--speed-range", "0.5", "1.5"],
        "--ship with --speed-range 0.5 1.5: the shipped files must cover [1, 2] m/s",
    ),
    (
        "examples/train_emulator.py",
        ["--ship", "--gd-range", "350", "600"],
        "--ship with --gd-range 350 600: the shipped files must cover [300, 500]",
    ),
    # odd values: a drive too short for its road, infinite lengths, folders that are files, and
    # seeds beyond the seeds' range [0, 2**128) (the first seed, or the last one derived from it)
    (
        "benchmarks/closed_loop_speed.py",
        ["--long-m", "1"],
        "--long-m 1 (three segments of a third): blend_m=1 is out of range",
    ),
    ("benchmarks/emulator_bias.py", ["--keep-s", "inf"], "(two batches of 8 blocks) and finite"),
    ("benchmarks/emulator_bias.py", ["--cache-dir", FILE], "--cache-dir " + NOT_A_FOLDER),
    ("benchmarks/emulator_bias.py", ["--seed", BIG_SEED], "--seed must be < 2**128"),
    ("benchmarks/feature_information.py", ["--keep-s", "inf"], "pooled) and finite, got inf"),
    ("benchmarks/feature_information.py", ["--cache-dir", FILE], "--cache-dir " + NOT_A_FOLDER),
    (
        "benchmarks/feature_information.py",
        ["--test-seed", BIG_SEED],
        "--test-seed must be in [0, 2**128), got " + BIG_SEED,
    ),
    ("benchmarks/sensor_checks.py", ["--keep-s", "inf"], "(one block) and finite, got inf"),
    ("benchmarks/sensor_checks.py", ["--seed", BIG_SEED], "--seed must be < 2**128"),
    ("benchmarks/second_channel.py", ["--duration-s", "inf"], "road) and finite, got inf"),
    ("benchmarks/speed_change_blocks.py", ["--first-seed", LAST_SEED], "beyond the seeds' range"),
    ("benchmarks/steady_hedge.py", ["--first-seed", LAST_SEED], "its 8 seeds run beyond"),
    (
        "benchmarks/closed_loop_accuracy.py",
        ["--random-first-seed", LAST_SEED],
        "--random-first-seed " + LAST_SEED + ": its 40 seeds run beyond",
    ),
    ("benchmarks/oracle_bounds.py", ["--seeds", "1-" + BIG_SEED], "beyond the seeds' range"),
    ("benchmarks/fault_soak.py", ["--example-seeds", "1", BIG_SEED], "--example-seeds must be <"),
    # counts whose memory the libraries would refuse only after (or while) building the work
    (
        "benchmarks/emulator_bias.py",
        ["--roads", "10" * 5],
        "the traces of 63636363630 drives needs",
    ),
    ("benchmarks/feature_information.py", ["--n-runs", "10" * 5], "a campaign's traces needs"),
    (
        "benchmarks/sensor_checks.py",
        ["--drives", "10" * 5],
        "--drives 1010101010 and --keep-s 120: a campaign's traces needs",
    ),
    (
        "benchmarks/second_channel_loop.py",
        ["--n-iter", "10" * 6, "--out", FOLDER],
        "--n-iter 101010101010: gpmsa.fit's draws needs about",
    ),
]


@pytest.fixture(scope="module")
def usage_runs(tmp_path_factory) -> list[tuple[dict, Path]]:
    """Each case's run, all in one interpreter (`run_scripts`), and the file it was given (one
    a case, written "kept")."""
    folder = tmp_path_factory.mktemp("usage")
    files, runs = [], []
    for k, (script, argv, _) in enumerate(CASES):
        a_file = folder / f"a_file_{k}"
        a_file.write_text("kept")
        files.append(a_file)
        args = [str(a_file) if arg == FILE else arg for arg in argv]
        runs.append((script, [str(folder / f"out_{k}") if arg == FOLDER else arg for arg in args]))
    return list(zip(run_scripts(runs), files, strict=True))


@pytest.mark.parametrize(
    "case", range(len(CASES)), ids=[f"{Path(s).name} {' '.join(a)}" for s, a, _ in CASES]
)
def test_bad_argument_is_a_usage_error_naming_it(usage_runs, case) -> None:
    done, a_file = usage_runs[case]
    message = CASES[case][2]
    assert done["returncode"] == 2, done["stderr"][-2000:]
    assert "Traceback" not in done["stderr"], done["stderr"][-2000:]
    (error,) = [line for line in done["stderr"].splitlines() if ": error: " in line]
    assert message.replace(FILE, repr(str(a_file))) in error
    assert a_file.read_text() == "kept"


def _emulators_for_another_robot(folder: Path, noise_std: float) -> Path:
    """The shipped band emulator of case A, its record changed to a 21.5 kg Jackal and the
    given training noise, saved in ``folder``."""
    emu = control.shipped_emulator("A", "band")
    emu.metadata["vehicle"] = vehicle.Jackal(mass_kg=21.5).describe()
    emu.metadata["noise_std"] = noise_std
    folder.mkdir()
    emu.save(folder / "jackal_A.gpmsa")
    return folder


def test_accuracy_benchmark_drives_the_robot_its_emulators_record(tmp_path) -> None:
    bench = load_benchmark("closed_loop_accuracy")
    for case in ("A", "B"):  # the shipped emulators: the default Jackal and the cases' noise
        emu = bench.emulator_for(case, "changepoint", None)
        assert bench.driven(emu) == (vehicle.Jackal(), bench.NOISE_STD[case])
    folder = str(_emulators_for_another_robot(tmp_path / "mine", noise_std=0.3))
    model, noise = bench.driven(bench.emulator_for("A", "changepoint", folder))
    assert (model, noise) == (vehicle.Jackal(mass_kg=21.5), 0.3)
    assert bench.vehicle_changes(model) == "mass_kg=21.5"
    assert bench.vehicle_changes(vehicle.Jackal()) == "the default Jackal"
    # no window emulator in the folder: the paper's method reads the shipped one
    window = bench.emulator_for("A", "window", folder)
    assert window.metadata == control.shipped_emulator("A", "window").metadata


def _accuracy_usage_errors(*argvs: list[str]) -> list[str]:
    """The one-line usage error of ``closed_loop_accuracy.py argv`` (exit status 2, no
    traceback) for each argv, all in one interpreter (`run_scripts`)."""
    errors = []
    runs = [("benchmarks/closed_loop_accuracy.py", argv) for argv in argvs]
    for done in run_scripts(runs, timeout_s=120 * len(runs)):
        assert done["returncode"] == 2, done["stderr"][-2000:]
        assert "Traceback" not in done["stderr"]
        (error,) = [line for line in done["stderr"].splitlines() if ": error: " in line]
        errors.append(error)
    return errors


def test_accuracy_benchmark_refuses_a_paper_method_for_another_robot(tmp_path) -> None:
    folder = _emulators_for_another_robot(tmp_path / "mine", noise_std=0.0)
    argv = ["--sets", "paper", "--cases", "A", "--emulator-dir", str(folder)]
    (error,) = _accuracy_usage_errors(argv)
    assert "the shipped window emulator of case A, which does not fit" in error
    assert "mass_kg: model 21.5 vs emulator" in error
    assert "--features band window" in error


def test_accuracy_benchmark_refuses_emulators_it_cannot_drive(tmp_path) -> None:
    """A band emulator without a vehicle record, or a damaged file, is a usage error naming it."""
    unrecorded = tmp_path / "unrecorded"
    unrecorded.mkdir()
    emu = control.shipped_emulator("A", "band")
    del emu.metadata["vehicle"]
    emu.save(unrecorded / "jackal_A.gpmsa")
    damaged = tmp_path / "damaged"
    damaged.mkdir()
    (damaged / "jackal_A.gpmsa").write_bytes(b"not a zip")
    cases = (
        (unrecorded, "the emulator's metadata has no 'vehicle'"),
        (damaged, "jackal_A.gpmsa: not a gpmsa emulator file"),
    )
    argv = ["--sets", "random", "--cases", "A", "--emulator-dir"]
    errors = _accuracy_usage_errors(*([*argv, str(folder)] for folder, _ in cases))
    for (_, message), error in zip(cases, errors, strict=True):
        assert "--emulator-dir: " in error and message in error


def test_oracle_replay_is_the_loops_estimator_and_the_oracles_know_more() -> None:
    """The oracle benchmark's replay without an oracle follows the loop's own estimates (it
    lacks only the sensor guards, which a clean simulated drive rarely calls); knowing the
    change points lowers the error of both parts."""
    bench = load_benchmark("oracle_bounds")
    out = bench._run(("A", 1))
    loop, replayed = (
        [control.pooled_rmse([out[name]], gd) for gd in (300.0, 500.0)]
        for name in ("loop", "filters")
    )  # fmt: skip
    assert np.allclose(replayed, loop, atol=1.0)
    for name in ("reset", "no change"):
        oracle = [control.pooled_rmse([out[name]], gd) for gd in (300.0, 500.0)]
        assert oracle[0] < loop[0] - 5 and oracle[1] < loop[1] - 5, (name, oracle, loop)
