"""The message of a correlation matrix that does not factor shows betaU as numpy's defaults
(at its own precision 3) whatever print options the user set: sign="+", suppress=True or a
legacy mode changed it (session 86 made the other messages' arrays independent of them)."""

import numpy as np
import pytest

from gpmsa.model.nugget import not_positive_definite

PARAMS = {"betaU": [[1.23456, 2.0], [1e-9, 3.0]], "lamUz": [1.0, 1.0], "lamWs": [1e5, 1e5],
          "lamWOs": [1e5]}  # fmt: skip


def _text() -> str:
    return not_positive_definite(0, PARAMS, np.array([1.0, 1.0]), 12, "at the start")


@pytest.mark.parametrize(
    "options",
    [{"sign": "+"}, {"suppress": True}, {"legacy": "1.13"}, {"precision": 1, "floatmode": "fixed"}],
)
def test_betau_reads_the_same_under_the_users_print_options(options):
    default = _text()
    assert "betaU[:, 0] = [1.235e+00 1.000e-09])" in default
    with np.printoptions(**options):
        assert _text() == default
