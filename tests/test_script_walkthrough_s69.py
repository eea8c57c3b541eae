"""A new user's walk through the scripts of README's tables: ``--help`` states what a script does
in whole sentences; ``posterior_check.py``'s first table (road 1 of each cell) does not depend on
``--roads``; ``discrepancy_groups.py`` refuses a count of seeds or a ``--out`` file it cannot
use before its minutes of work, and writes that file in one step."""

import json
import time
from pathlib import Path

import numpy as np
import pytest

from tests._examples import load_benchmark, load_example
from tests._script_runs import run_scripts, script_helps

ROOT = Path(__file__).resolve().parents[1]
CUT_SHORT = [  # their docstring's first sentence runs over its first line
    "benchmarks/closed_loop_accuracy.py",
    "benchmarks/hierarchical_coverage.py",
    "benchmarks/oracle_bounds.py",
    "benchmarks/second_channel_loop.py",
]


def _description(help_text: str) -> str:
    """The parser's description in ``--help``'s output: the paragraph after the usage lines."""
    return " ".join(help_text.split("\n\n")[1].split())


def test_help_describes_the_script_in_whole_sentences() -> None:
    helps = script_helps()  # every script's, in one interpreter
    for script, done in ((s, helps[s]) for s in CUT_SHORT):
        assert done["returncode"] == 0, done["stderr"][-2000:]
        assert _description(done["stdout"]).endswith((".", "?")), (script, done["stdout"][:400])


def test_posterior_check_road_one_of_each_cell_does_not_depend_on_roads() -> None:
    script = load_example("posterior_check")
    one, five, ten = (script.road_seeds(2025, roads) for roads in (1, 5, 10))
    assert one.shape == (len(script.GDS), len(script.SPEEDS), 1) and ten.shape[2] == 10
    assert np.array_equal(five[:, :, 0], one[:, :, 0])
    assert np.array_equal(ten[:, :, :5], five)
    assert np.unique(ten).size == ten.size  # a fresh road and drive in every cell
    assert not np.array_equal(script.road_seeds(2026, 1), one)


REFUSED = [
    (["--seeds", "0"], "--seeds must be >= 1, got 0"),
    (["--seeds", "-2"], "--seeds must be >= 1, got -2"),
    (["--out", "{tmp}/missing/res.json"], "/missing/res.json': its folder does not exist"),
    (["--out", "{tmp}"], "': a folder, not a file"),
    (["--out", ""], "argument --out: an empty path"),
]


def test_discrepancy_groups_refuses_what_it_cannot_use_at_once(tmp_path) -> None:
    runs = [
        ("benchmarks/discrepancy_groups.py", [arg.replace("{tmp}", str(tmp_path)) for arg in argv])
        for argv, _ in REFUSED
    ]
    for (argv, message), done in zip(REFUSED, run_scripts(runs, timeout_s=60), strict=True):
        assert done["returncode"] == 2, (argv, done["stderr"][-2000:])
        assert "Traceback" not in done["stderr"]
        (error,) = [line for line in done["stderr"].splitlines() if ": error: " in line]
        assert message in error and not done["stdout"], (argv, error)


def test_discrepancy_groups_writes_its_file_in_one_step(monkeypatch, tmp_path, capsys) -> None:
    bench = load_benchmark("discrepancy_groups")
    row = {"mean": 0.4, "sd": 0.01, "covered": True, "lamVz": [1.0]}
    res = {truth: {name: [row] for name in bench.GROUPINGS} for truth in ("offset", "shape")}
    bad = {**res, "shape": {name: [{**row, "mean": np.float32(0.4)}] for name in bench.GROUPINGS}}
    monkeypatch.setattr(bench, "run", lambda seeds: bad)
    out = tmp_path / "res.json"
    out.write_text("kept")
    with pytest.raises(TypeError, match="not JSON serializable"):  # half written: refused
        bench.main(["--seeds", "1", "--out", str(out)])
    assert out.read_text() == "kept"  # the previous file, not a part of the new one
    monkeypatch.setattr(bench, "run", lambda seeds: res)
    bench.main(["--seeds", "1", "--out", str(out)])
    assert json.loads(out.read_text()) == res


def test_roadgen_speed_times_warm_calls_only() -> None:
    """``--repeats 1`` timed the first call of estimate_gd's fit (579 ms, its set-up, against
    4 ms warm): the median leaves out a first, warm-up call."""
    bench = load_benchmark("roadgen_speed")
    calls = []

    def cold_once() -> None:
        calls.append(1)
        if len(calls) == 1:
            time.sleep(0.3)

    assert bench.median_seconds(cold_once, 1) < 0.1 and len(calls) == 2
