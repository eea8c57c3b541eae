"""Continuing a fit (``fit(..., init=emu)``) with another unit domain or output scale than the
fit's (``SimData(x_range=, t_range=, y_scale=)``, session 71): the same runs then sit at other
unit values, so the chains cannot continue; the refusal names the input or the scale that
differs (it read "fitted to other simulation runs", which they were not)."""

import numpy as np
import pytest

import gpmsa

RNG = np.random.default_rng(5)
X, T = RNG.uniform(size=(25, 1)), RNG.uniform(200.0, 600.0, size=(25, 1))
Y = np.column_stack([np.sin(3 * X[:, 0]) + T[:, 0] / 300.0, 100.0 * X[:, 0] * T[:, 0] / 600.0])


def _sim(**kw) -> gpmsa.SimData:
    return gpmsa.SimData(x=X, t=T, y=Y, x_names=["v"], t_names=["GD"], **kw)


@pytest.fixture(scope="module")
def ranged_fit():
    return gpmsa.fit(_sim(t_range={"GD": (200.0, 600.0)}), n_iter=20, n_chains=1, seed=0,
                     tune=False)  # fmt: skip


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({}, r"GD: \[200, 600\] in init=emulator's fit, \[2\d\d.*, 5\d\d.*\] here"),
        ({"t_range": {"GD": (100.0, 700.0)}}, r"GD: \[200, 600\] .*, \[100, 700\] here"),
        ({"t_range": {"GD": (200.0, 600.0)}, "y_scale": "columnwise"},
         r"y_scale: 'scalar' in init=emulator's fit, 'columnwise' here"),
    ],
)  # fmt: skip
def test_a_continuation_with_another_domain_or_scale_names_it(ranged_fit, kw, match):
    with pytest.raises(gpmsa.GPMSAError, match=match):
        gpmsa.fit(_sim(**kw), n_iter=10, n_chains=1, seed=1, init=ranged_fit)


def test_the_same_domain_and_scale_continue(ranged_fit):
    emu = gpmsa.fit(_sim(t_range={"GD": (200.0, 600.0)}), n_iter=10, n_chains=1, seed=1,
                    init=ranged_fit)  # fmt: skip
    assert emu.domain["GD"] == (200.0, 600.0)


def test_other_runs_still_read_as_other_runs(ranged_fit):
    other = gpmsa.SimData(x=X, t=T, y=Y * 1.5, x_names=["v"], t_names=["GD"],
                          t_range={"GD": (100.0, 700.0)})  # fmt: skip
    with pytest.raises(gpmsa.GPMSAError, match="fitted to other simulation runs"):
        gpmsa.fit(other, n_iter=10, n_chains=1, seed=1, init=ranged_fit)
