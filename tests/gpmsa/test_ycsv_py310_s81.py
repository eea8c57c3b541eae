"""``gpmsa calibrate --y-csv`` skips blank and comment lines with a pattern of possessive
quantifiers, which Python 3.10's re does not read (the ``gpmsa`` command failed at import:
"multiple repeat at position 6"); there it takes greedy quantifiers and a bounded repeat,
matched again where it ends, with the same ends."""

from __future__ import annotations

import re

import numpy as np

from gpmsa.cli import calibrate
from gpmsa.cli.calibrate import _skipped_end, _skipped_pattern

CHARS = np.array([*" \t\n\r#a1,;-.eE+", "\r\n", "\x0b", "\x85", "\u2028", "#N/A", "#VALUE!",
                  "#NAME?", " 1.5", "# c\n"])  # fmt: skip


def test_the_greedy_patterns_skip_to_the_same_ends():
    greedy = re.compile(_skipped_pattern(possessive=False))
    bounded = re.compile(_skipped_pattern(possessive=False, most=3))  # crosses many bounds
    rng = np.random.default_rng(81)
    for _ in range(2000):
        text = "".join(rng.choice(CHARS, size=int(rng.integers(0, 24))))
        for pos in range(len(text) + 1):
            want = _skipped_end(text, pos)
            assert _skipped_end(text, pos, greedy) == want, (text, pos)
            assert _skipped_end(text, pos, bounded) == want, (text, pos)


def test_long_runs_of_comments_cross_the_bound_to_their_end():
    text = "# a comment\n\n  \n" * 5000 + "#N/A,1\n"
    bounded = re.compile(_skipped_pattern(possessive=False, most=calibrate._SKIPPED_MOST))
    assert _skipped_end(text, 0, bounded) == _skipped_end(text, 0) == len(text) - 7


def test_the_python310_pattern_has_no_syntax_of_python_311():
    pattern = _skipped_pattern(possessive=False, most=calibrate._SKIPPED_MOST)
    assert not re.search(r"[*+?}]\+", pattern)  # possessive quantifiers
    assert "(?>" not in pattern  # atomic groups
    assert re.search(r"[*+?}]\+", _skipped_pattern())  # (the check sees them)
