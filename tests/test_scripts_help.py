"""Every benchmark and example script answers ``--help`` (its imports and argument parser work)."""

from pathlib import Path

import pytest

from tests._script_runs import script_helps

ROOT = Path(__file__).resolve().parents[1]
SCRIPTS = [
    path
    for folder in ("benchmarks", "examples")
    for path in sorted((ROOT / folder).glob("*.py"))
    if not path.name.startswith("_")  # a helper the scripts import (examples/_cli.py)
]


@pytest.fixture(scope="module")
def helps() -> dict:
    """Each script's run with ``--help``, all in one interpreter (`script_helps`)."""
    done = script_helps()
    return {path: done[path.relative_to(ROOT).as_posix()] for path in SCRIPTS}


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_script_answers_help(helps, script: Path) -> None:
    done = helps[script]
    assert done["returncode"] == 0, done["stderr"][-2000:]
    assert "usage:" in done["stdout"]
