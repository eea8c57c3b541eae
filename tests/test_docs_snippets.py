"""Every ```python block of README.md and docs/*.md runs as written, or says why it cannot.

A block not meant to run on its own carries, on the nearest non-blank line above its fence,
``<!-- snippet: fragment -->`` (it uses names defined elsewhere, or a file the reader brings) or
``<!-- snippet: slow -->`` (it runs, but takes longer than this suite allows). Every other block
runs here, each in a fresh Python process, in the order a reader meets them (README.md, then
docs/ by file name, top to bottom), all in one scratch folder that links the project's top-level
folders: relative paths such as tests/data/case.npz resolve, what a block writes stays in the
scratch folder, and a file one block makes is there for a later one (docs/calibration.md loads
the README's road.gpmsa).
"""

import os
import re
import subprocess
import sys
import textwrap
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
MARKERS = ("fragment", "slow")
MARKER_RE = re.compile(r"<!--\s*snippet:\s*(?P<kind>[\w-]+)\s*-->")
TIMEOUT_S = 120  # one block; those of the suite take 1-15 s on a 2-core machine


@dataclass(frozen=True)
class Block:
    """One ```python block: its file (relative to the root), the line of its first code line
    (1-based), its code, and its marker ("" for none)."""

    path: str
    line: int
    code: str
    marker: str

    @property
    def id(self) -> str:
        return f"{self.path}:{self.line}"


def _doc_files() -> list[Path]:
    return [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def _blocks(path: Path) -> list[Block]:
    """The ```python blocks of one Markdown file; an unclosed one is an error."""
    lines = path.read_text(encoding="utf-8").splitlines()
    rel = path.relative_to(ROOT).as_posix()
    blocks = []
    i = 0
    while i < len(lines):
        if lines[i].strip() == "```python":
            above = next((s.strip() for s in reversed(lines[:i]) if s.strip()), "")
            marker = MARKER_RE.fullmatch(above)
            end = next((j for j in range(i + 1, len(lines)) if lines[j].strip() == "```"), None)
            if end is None:
                raise ValueError(f"{rel}:{i + 1}: a ```python block is never closed")
            code = textwrap.dedent("\n".join(lines[i + 1 : end])) + "\n"
            blocks.append(Block(rel, i + 2, code, marker["kind"] if marker else ""))
            i = end
        i += 1
    return blocks


BLOCKS = [b for path in _doc_files() for b in _blocks(path)]
RUNNABLE = [b for b in BLOCKS if not b.marker]


def _run(block: Block, folder: Path, scripts: Path) -> subprocess.CompletedProcess:
    script = scripts / (re.sub(r"\W", "_", block.id) + ".py")
    script.write_text(block.code, encoding="utf-8")
    env = {**os.environ, "MPLBACKEND": "Agg", "PYTHONPATH": str(ROOT)}
    return subprocess.run(
        [sys.executable, str(script)], cwd=folder, env=env, capture_output=True, text=True,
        timeout=TIMEOUT_S, check=False,
    )  # fmt: skip


@pytest.fixture(scope="module")
def reader(tmp_path_factory):
    """Runs the runnable blocks in reading order, each once, up to the one asked for; returns
    that one's finished process."""
    folder = tmp_path_factory.mktemp("reader")
    scripts = tmp_path_factory.mktemp("snippets")
    for entry in ROOT.iterdir():  # folders only: a block that writes a file writes it here
        if entry.is_dir() and not entry.name.startswith("."):
            (folder / entry.name).symlink_to(entry, target_is_directory=True)
    done: dict[str, subprocess.CompletedProcess] = {}

    def run_through(block: Block) -> subprocess.CompletedProcess:
        for earlier in RUNNABLE[: RUNNABLE.index(block) + 1]:
            if earlier.id not in done:
                done[earlier.id] = _run(earlier, folder, scripts)
        return done[block.id]

    return run_through


@pytest.mark.parametrize("block", RUNNABLE, ids=[b.id for b in RUNNABLE])
def test_an_unmarked_block_runs_as_written(block, reader):
    result = reader(block)
    code = result.returncode
    assert code == 0, (
        f"{block.id}: the block fails (exit {code}); fix it, or mark it "
        f"<!-- snippet: fragment --> or <!-- snippet: slow --> on the line above its fence:\n"
        f"{result.stderr[-3000:]}"
    )


def test_every_marker_is_known_and_sits_above_a_python_block():
    wrong = []
    for path in _doc_files():
        lines = path.read_text(encoding="utf-8").splitlines()
        for i, line in enumerate(lines):
            if "snippet:" not in line or not line.lstrip().startswith("<!--"):
                continue
            where = f"{path.relative_to(ROOT).as_posix()}:{i + 1}"
            marker = MARKER_RE.fullmatch(line.strip())
            below = next((s.strip() for s in lines[i + 1 :] if s.strip()), "")
            if marker is None or marker["kind"] not in MARKERS:
                wrong.append(f"{where}: {line.strip()!r} is not one of {MARKERS}")
            elif below != "```python":
                wrong.append(f"{where}: the marker is not above a ```python fence")
    assert not wrong, "\n".join(wrong)


def test_the_blocks_are_found():
    """The parser sees every ```python fence, and the README's quick start is one that runs."""
    fences = sum(
        line.strip() == "```python"
        for path in _doc_files()
        for line in path.read_text(encoding="utf-8").splitlines()
    )
    assert len(BLOCKS) == fences > 0
    assert any(b.path == "README.md" for b in RUNNABLE)
