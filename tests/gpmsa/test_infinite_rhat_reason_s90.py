"""A file's convergence record (s90): `read_back` and `gpmsa info` read "R-hat infinite" from
a flagged element's reason by one rule, `INFINITE_RHAT` before any ", ..." (read_back took any
reason starting with that text, so a hand-edited "R-hat info" read inf there and NaN in info)."""

import math

import pytest

from gpmsa.mcmc import diagnostics as dg


@pytest.mark.parametrize(
    ("why", "infinite"),
    [
        ("R-hat inf", True),
        ("R-hat inf, ESS 3", True),
        ("R-hat inf,", True),
        ("R-hat info", False),
        ("R-hat inf5, ESS 3", False),
        (" R-hat inf", False),
        ("R-hat 1.2", False),
        (None, False),
        (3, False),
        (["R-hat inf"], False),
    ],
)
def test_one_rule_reads_an_infinite_rhat(why, infinite):
    assert dg.says_infinite_rhat(why) is infinite
    out = dg.read_back({"a": {"rhat": [None]}}, {"a": ()}, {"a": why})["a"]["rhat"][0]
    assert out == math.inf if infinite else math.isnan(out)
