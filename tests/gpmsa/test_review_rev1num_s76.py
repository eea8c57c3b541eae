"""Review of session 75's numbers_text (helper, session 76): a continuation's refusal that names
a unit domain or output scale differing from the fit's prints them so that they read apart
(the ranges [200, 600 + 1e-9] and [200, 600] both read "[200, 600]")."""

import math

import numpy as np
import pytest

import gpmsa
from gpmsa.errors import numbers_text

RNG = np.random.default_rng(5)
X, T = RNG.uniform(size=(25, 1)), RNG.uniform(200.0, 600.0, size=(25, 1))
Y = np.column_stack([np.sin(3 * X[:, 0]) + T[:, 0] / 300.0, 100.0 * X[:, 0] * T[:, 0] / 600.0])


def _sim(**kw) -> gpmsa.SimData:
    return gpmsa.SimData(x=X, t=T, y=Y, x_names=["v"], t_names=["GD"], **kw)


@pytest.fixture(scope="module")
def ranged_fit():
    return gpmsa.fit(_sim(t_range={"GD": (200.0, 600.0)},
                          y_sd=[1.5, 30.0]), n_iter=20, n_chains=1, seed=0, tune=False)  # fmt: skip


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"t_range": {"GD": (200.0, 600.000000001)}, "y_sd": [1.5, 30.0]},
         r"GD: \[200, 600\] in init=emulator's fit, \[200, 600.000000001\] here"),
        ({"t_range": {"GD": (200.0, 600.0)}, "y_sd": [1.5, 30.0 + 3e-8]},
         r"y_sd: \[1.5, 30\] \(given\) in init=emulator's fit, \[1.5, 30.00000003\] \(given\)"),
    ],
)  # fmt: skip
def test_a_continuation_names_values_that_differ_past_six_digits_apart(ranged_fit, kw, match):
    with pytest.raises(gpmsa.GPMSAError, match=match):
        gpmsa.fit(_sim(**kw), n_iter=10, n_chains=1, seed=1,
                  init=ranged_fit)  # fmt: skip


def test_numbers_text_edge_values():
    assert numbers_text(math.nan, -0.0, math.inf, 1.0) == ("nan", "-0", "inf", "1")
    assert numbers_text(np.float32(2.5), 3) == ("2.5", "3")
    one_up = math.nextafter(1.0, 2.0)
    assert numbers_text(1.0, one_up) == ("1", "1.0000000000000002")
    assert numbers_text(-1e6 - 0.5, -1e6) == ("-1000000.5", "-1000000")
    assert numbers_text(1e-320, 1e-320 + 5e-324)[0] != numbers_text(1e-320, 1e-320 + 5e-324)[1]
    assert numbers_text(0.0856, 0.956, 0.0, 1e12) == ("0.0856", "0.956", "0", "1e+12")
    assert numbers_text(1e6 + 1.5, 1e6 + 0.003, 1e6 + 0.935) == (
        "1000001.5", "1000000.003", "1000000.935")  # fmt: skip


def test_the_digits_follow_the_values_that_read_alike_not_the_largest():
    # a sliver of a design column in a wide range: the digits that tell 0.1 from 0.1000001
    # (it read "0.10000000000000001, 0.10000009999999999": the largest value's 17 digits)
    assert numbers_text(0.1, 0.1000001, 0.0, 1e12) == ("0.1", "0.1000001", "0", "1e+12")
    rng = np.random.default_rng(0)
    for _ in range(2000):  # distinct values read apart, at any size and sign
        base = 10 ** rng.uniform(-300, 300) * rng.choice([-1.0, 1.0])
        rel = rng.choice([1e-15, 1e-10, 1e-7, 1e-3], size=3) * rng.integers(-5, 6, size=3)
        values = [*(base * (1 + rel)), rng.normal() * 10 ** rng.uniform(-5, 5)]
        assert len(set(numbers_text(*values))) == len(set(values))
