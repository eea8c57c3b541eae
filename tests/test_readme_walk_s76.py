"""A new user's reading of README.md and docs/: what the two commands take and print, where the
quick start runs and what it leaves, one figure a results row (the older ones in
docs/performance.md), one Calibrator.update timing, no development-process wording, CI's steps,
no 25-minute retraining in a pasted block, and the examples' expected ConvergenceWarnings
announced where a user meets them."""

import re
import shutil
import subprocess
from pathlib import Path

import pytest

from tests._examples import load_example

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")
DOCS = {p.name: p.read_text(encoding="utf-8") for p in (ROOT / "docs").glob("*.md")}


def _section(text: str, heading: str) -> str:
    start = text.index(heading)
    end = text.find("\n## ", start + len(heading))
    return text[start : end if end >= 0 else None]


def _row(what: str) -> list[str]:
    (line,) = [x for x in README.splitlines() if x.startswith(f"| {what}")]
    return line[2:-2].split(" | ")


def test_the_two_commands_say_how_long_they_take_and_what_they_print():
    two = _section(README, "## The two commands")
    assert "11-20 s" in two and "~8-12 min" in two and "~8,400 tests" in two
    assert "python -m pytest -m slow" in two
    # the printed RMSEs are those of the results table
    for case in ("A", "B"):
        ours = re.match(r"[\d.]+ / [\d.]+", _row(f"Test Case {case}, RMSE")[2]).group(0)
        assert f"{case} {ours}" in two, (case, ours)
    pyproject = (ROOT / "pyproject.toml").read_text()
    assert re.search(r"^addopts = .*-m 'not slow'", pyproject, flags=re.M)
    assert "addopts = \"-m 'not slow'\"" in two


def test_ci_run_line_names_what_ci_does():
    ci = (ROOT / ".ci" / "run").read_text()
    for step in ("robot", "ruff check .", "ruff format --check ."):
        assert step in ci
    line = README[README.index("`bash .ci/run`") :].split("\n\n")[0]
    for step in ("robot", "`ruff check .`", "`ruff format --check .`", "python -m pytest"):
        assert step in line, step


def test_quick_start_says_where_to_run_and_its_files_are_ignored():
    quick = _section(README, "## Quickstart")
    assert "from the repository root" in quick
    written = set()
    for text in (README, *DOCS.values()):
        for block in re.findall(r"```python\n(.*?)```", text, flags=re.S):
            written |= set(re.findall(r"(?:save|to_netcdf|savefig)\(\"([\w.-]+)\"\)", block))
    assert {"road.gpmsa", "post.nc"} <= written
    if shutil.which("git") is None or not (ROOT / ".git").exists():
        pytest.skip("not a git checkout")
    ignored = subprocess.run(
        ["git", "check-ignore", "--no-index", *sorted(written)], cwd=ROOT, capture_output=True,
        text=True, check=False,
    ).stdout.split()  # fmt: skip
    assert sorted(ignored) == sorted(written)


def test_results_rows_hold_one_figure_and_link_the_history():
    rows = [x for x in README.splitlines() if x.startswith("| ") and x.count(" | ") == 2]
    assert len(rows) > 20
    assert max(len(x) for x in rows) < 900, max(rows, key=len)[:200]
    for what in ("closed loop, real-time factor", "replay of a ROS 2 bag", "sensor faults"):
        assert "docs/performance.md#history-of-the-measurements" in _row(what)[2]
    perf = DOCS["performance.md"]
    history = _section(perf, "## History of the measurements")
    assert "(3561ab8, against the commit before;" in history  # the old text, verbatim
    assert "Seed 35 (fresh, 400 scenarios" in history


def test_the_road_case_row_says_which_run():
    cell = _row("GPM/SA road case, joint posterior of GD")
    assert "gpmsa.fit(" in cell[0] + cell[2] and "seed=" in cell[0] + cell[2]
    assert "quick start" in cell[2]


def test_calibrator_update_timing_is_stated_once_as_a_range():
    quick = re.search(r"cal\.update\(.*# exact grid, ([\d.]+-[\d.]+ ms) \(([\w/.]+)\)", README)
    doc = re.search(r"cal\.update\(\[\[1\.25\]\].*# exact, ([\d.]+-[\d.]+ ms) \(([\w/.]+)\)",
                    DOCS["calibration.md"])  # fmt: skip
    assert quick and doc
    assert quick.groups() == doc.groups() == ("0.3-0.9 ms", "benchmarks/calibrate_speed.py")
    assert "0.3-0.9 ms" in _row("`Calibrator.update`")[2]


@pytest.mark.parametrize(
    "pattern",
    [r"the device tool", r"this task", r"steerer", r"other helpers|helpers'", r"walkthrough",
     r"\bissue \d+", r"the issue's", r"can_start_another", r"\blent\b"],
)  # fmt: skip
def test_no_development_process_wording(pattern):
    hits = [f"{name}: {m.group(0)}" for name, text in {"README.md": README, **DOCS}.items()
            for m in re.finditer(pattern, text, flags=re.I)]  # fmt: skip
    assert not hits, hits[:5]


def test_no_pasted_block_starts_the_25_minute_retraining():
    blocks = re.findall(r"```(?:bash|sh|console)?\n(.*?)```", DOCS["closed-loop.md"], flags=re.S)
    lines = [x.strip() for b in blocks for x in b.splitlines()]
    assert not [x for x in lines if x.startswith("python examples/train_emulator.py --ship")]
    assert "**overwrites**" in DOCS["closed-loop.md"]


class _Stop(Exception):
    pass


def _stop(*_, **__):
    raise _Stop


def test_ball_drop_announces_its_convergence_warning(monkeypatch, capsys, tmp_path):
    script = load_example("ball_drop")
    monkeypatch.setattr(script.gpmsa, "fit", _stop)
    with pytest.raises(_Stop):
        script.main(["--out", str(tmp_path)])
    out = capsys.readouterr().out
    assert "ConvergenceWarning" in out and "betaV[0,0]" in out and "R-hat 1.023, ESS 76" in out
    assert "betaV" in DOCS["prediction.md"] and "R-hat\n1.023 and ESS 76" in DOCS["prediction.md"]


def test_shared_theta_announces_its_four_convergence_warnings(monkeypatch, capsys, tmp_path):
    script = load_example("shared_theta")
    monkeypatch.setattr(script.gpmsa, "calibrate", _stop)
    with pytest.raises(_Stop):
        script.main(["--out", str(tmp_path), "--n-iter", "2"])
    out = capsys.readouterr().out
    fits, alone = out.split("calibrating each test alone")
    assert "ConvergenceWarning" in fits and "R-hat 1.013-1.025" in fits
    assert "cannot separate E from rho" in alone and "R-hat ~1.37, ESS 7" in alone
    models = DOCS["models.md"]
    assert "examples/shared_theta.py" in models and "four `gpmsa.ConvergenceWarning`s" in models
