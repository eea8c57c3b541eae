"""The example scripts' ``--help`` states each option's default where the run's cost or output
depends on it: train_emulator.py's defaults make a ~25 min run (198 runs of 120 s, 30,000 MCMC
sweeps a fit), which a user deciding on a smaller try must be able to read there."""

import re

import pytest

from tests._script_runs import script_helps

# (script, option, what its help must say)
EXPECTED = [
    ("examples/train_emulator.py", "--out", "default ./out"),
    ("examples/train_emulator.py", "--n-runs", "default 198"),
    ("examples/train_emulator.py", "--keep-s", "default 120"),
    ("examples/train_emulator.py", "--n-iter", "default 30000"),
    ("examples/train_emulator.py", "--seed", "default 0"),
    ("examples/train_emulator.py", "--cases", "default A B"),
    ("examples/train_emulator.py", "--features", "default band window"),
    ("examples/closed_loop.py", "--out", "default ./out"),
    ("examples/closed_loop.py", "--runs", "default 3"),
    ("examples/closed_loop.py", "--first-seed", "default 1"),
    ("examples/closed_loop.py", "--risk", "default: the posterior mean"),
    ("examples/closed_loop.py", "--cases", "default A B"),
]


@pytest.fixture(scope="module")
def helps() -> dict:
    done = script_helps()  # every script's, in one interpreter
    return {s: done[s]["stdout"] for s in sorted({script for script, _, _ in EXPECTED})}


def _option_help(text: str, option: str) -> str:
    """The help text of ``option`` (its lines joined), from argparse's --help output."""
    lines = text.splitlines()
    start = next(i for i, line in enumerate(lines) if re.match(rf"\s+{option}\b", line))
    block = [lines[start]]
    for line in lines[start + 1 :]:
        if re.match(r"\s+-", line) or not line.strip():
            break
        block.append(line)
    return " ".join(" ".join(block).split())


@pytest.mark.parametrize(("script", "option", "says"), EXPECTED)
def test_help_states_the_default(helps, script, option, says) -> None:
    assert says in _option_help(helps[script], option)
