"""Benchmarks and examples as a new user meets them (session 81): every option's ``--help`` says
what it sets, no figure prints as NaN, and a timed row does not carry a process's one-off cost
(the first ``gpmsa.calibrate`` imports ArviZ, ~0.5 s, which fell on a baseline's first run)."""

import re
import sys
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

import roadgen
from tests._examples import load_benchmark, load_example
from tests._script_runs import script_helps

ROOT = Path(__file__).resolve().parents[1]
SCRIPTS = [
    str(path.relative_to(ROOT))
    for folder in ("benchmarks", "examples")
    for path in sorted((ROOT / folder).glob("*.py"))
    if not path.name.startswith("_")
]


@pytest.fixture(scope="module")
def helps() -> dict:
    """Each script's ``--help`` output (`script_helps`: all in one interpreter)."""
    done = script_helps()
    return {s: done[s]["stdout"] for s in SCRIPTS}


def _undocumented(text: str) -> list[str]:
    """The options and positional arguments of a ``--help`` text that have no help of their own
    (argparse prints such an entry alone on its line, with nothing on the line below it)."""
    lines = text.splitlines()
    bare = []
    in_args = False
    for i, line in enumerate(lines):
        if line.endswith(":") and not line.startswith(" "):
            in_args = line in ("options:", "optional arguments:", "positional arguments:")
            continue
        entry = re.match(r"^  (\S.*?)\s*$", line)
        if not in_args or not entry or "  " in entry.group(1):
            continue  # not an entry, or its help follows on the same line
        below = lines[i + 1] if i + 1 < len(lines) else ""
        if not re.match(r"^ {10,}\S", below):  # the help would be indented on the next line
            bare.append(entry.group(1))
    return bare


@pytest.mark.parametrize("script", SCRIPTS)
def test_every_option_of_a_script_has_its_help(helps, script: str) -> None:
    # e.g. vehicle_speed.py's --repeats, --runs and --skip-campaign, kronecker_fit.py's n_sweeps
    # printed their names alone: what they set and their defaults were in the code only
    assert "usage:" in helps[script]
    assert [e for e in _undocumented(helps[script]) if not e.startswith("-h, --help")] == []


def test_speed_change_blocks_names_the_option_and_its_value(monkeypatch, capsys) -> None:
    # "--roads and --runs must be >= 2, --workers >= 1, --first-seed >= 0" for --runs 1
    bench = load_benchmark("speed_change_blocks")
    argv = ["benchmarks/speed_change_blocks.py", "--part", "loop", "--runs", "1"]
    monkeypatch.setattr(sys, "argv", argv)
    with pytest.raises(SystemExit) as done:
        bench.main()
    assert done.value.code == 2
    assert "error: --runs must be >= 2, got 1" in capsys.readouterr().err


def test_backends_one_chain_r_hat_prints_a_dash_not_nan() -> None:
    bench = load_benchmark("backends")
    assert bench.rhat_text(float("nan")) == "     -"
    assert bench.rhat_text(1.0123) == " 1.012"


def test_backends_only_runs_its_pair_and_the_task_baseline() -> None:
    # --only fit:pyro printed the pyro row with "vs numpy -": no baseline in the run
    bench = load_benchmark("backends")
    configs = [("numpy", 1, 10, True), ("numpy", 1, 10, False), ("torch", 8, 10, False)]
    assert bench.selected(configs, "calibrate", None) == configs
    assert bench.selected(configs, "calibrate", "calibrate:torch") == [configs[0], configs[2]]
    assert bench.selected(configs, "calibrate", "calibrate:numpy") == configs[:2]
    assert bench.selected(configs, "fit", "calibrate:torch") == []


def test_calibrate_speed_times_the_calls_after_the_first() -> None:
    # the process's first gpmsa.calibrate (~0.5 s importing ArviZ) was one of the --runs timed
    # calls: the p90 of the default 10 (and, with --runs 2, the median) carried it
    bench = load_benchmark("calibrate_speed")
    seeds = []
    first, times = bench.calibrate_times(seeds.append, 3)
    assert seeds == [3, 0, 1, 2]  # the untimed-in-the-row first call, then the seeds as before
    assert len(times) == 3 and first >= 0.0


def _outcome(bench, kind: str, crash: str = ""):
    sc = bench.Scenario("#0", "A", ((50.0, 300.0),), 1, 1, kind, 1.0, 1.0)
    return bench.Outcome(sc, crash=crash, fast_clean=1.0, fast_fault=1.0, during_clean=0.0,
                         during_fault=0.0, fast_null=1.0, during_null=0.0,
                         statuses=Counter())  # fmt: skip


def test_fault_soak_tables_print_no_nan(capsys) -> None:
    # a kind whose faulted, clean and null runs all drove alike printed p "nan"; a kind whose
    # runs all crashed printed "nan" percentiles (fault_soak.py --scenarios 2 --no-examples)
    bench = load_benchmark("fault_soak")
    bench.summarise([_outcome(bench, "nan"), _outcome(bench, "spike", crash="boom")])
    out = capsys.readouterr().out
    figures = [tok for line in out.splitlines() for tok in line.split()[1:]]  # (a kind: "nan")
    assert "nan" not in figures, out
    spike = next(line for line in out.splitlines() if line.startswith("spike"))
    assert spike.split()[:3] == ["spike", "1", "1"] and spike.count(" -") >= 5
    null_all = [line for line in out.splitlines() if line.startswith("all")][-1]
    assert " - |" in null_all


def test_roadgen_psd_check_prints_a_dash_where_welch_does_not_apply(tmp_path, monkeypatch, capsys):
    # the 21 m roads' welch column printed "nan" (the Welch fit runs on 150 m roads only)
    module = load_example("roadgen_psd_check")
    monkeypatch.setattr(roadgen, "plot_profile_psd", lambda road, title: title)  # fast
    monkeypatch.setattr(module, "save_figure", lambda fig, path: None)
    module.main(["--out", str(tmp_path)])
    out = capsys.readouterr().out
    assert "nan" not in out
    rows = [line.split() for line in out.splitlines() if line.startswith(("deterministic", " "))]
    short = [r for r in rows if len(r) == 8 and r[1] == "21"]
    assert len(short) == 24 and {r[6] for r in short} == {"-"}
    assert all(np.isfinite(float(r[6])) for r in rows if len(r) == 8 and r[1] == "150")


@pytest.mark.slow  # ~5 s: 21 drives and calibrations
def test_posterior_check_case_b_says_the_papers_table_is_noise_free(tmp_path, capsys) -> None:
    # --case B printed the paper's (noise-free, case A) Table 2 as "paper" beside case B's errors
    load_example("posterior_check").main(["--case", "B", "--roads", "1", "--out", str(tmp_path)])
    out = capsys.readouterr().out
    assert "(paper (noise-free: its Table 2 is case A) | ours)" in out
    assert "percent error: paper (noise-free: its Table 2 is case A) 78.2 / 17.9" in out
