"""A range given to SimData(x_range=, t_range=) far wider than its design column (a unit
mistake: 1e12 for a design in [0, 1]) was accepted silently, the runs then filling a sliver of
the unit interval, where the fit ignores the input: a DomainWarning names the column."""

import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.model.data import RANGE_COVER_MIN

RNG = np.random.default_rng(3)
X, T = RNG.uniform(size=(20, 1)), RNG.uniform(200.0, 600.0, size=(20, 1))
Y = np.sin(3 * X[:, 0]) + T[:, 0] / 300.0


def _sim(**kw) -> gpmsa.SimData:
    return gpmsa.SimData(x=X, t=T, y=Y, x_names=["v"], t_names=["GD"], **kw)


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"x_range": {"v": (0.0, 1e12)}}, r"design column v spans \[0.0\d+, 0.9\d+\], [89].\d+e-13 "
                                          r"of its x_range \[0, 1e\+12\]"),
        ({"t_range": [[0.0, 600e3]]}, r"design column GD spans .* of its t_range \[0, 600000\]"),
    ],
)  # fmt: skip
def test_a_range_far_wider_than_the_design_warns_naming_the_column(kw, match):
    with pytest.warns(gpmsa.DomainWarning, match=match) as caught:
        sim = _sim(**kw)
    assert caught[0].filename == __file__  # attributed to the user's SimData call
    assert sim.x_range or sim.t_range  # still accepted: a warning, not a refusal


def test_a_design_on_part_of_its_range_is_silent():
    lo, hi = float(T.min()), float(T.max())
    wide = lo + (hi - lo) / (2 * RANGE_COVER_MIN)  # the design covers 2 x the threshold
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        _sim(t_range={"GD": (200.0, 600.0)}, x_range=[[0.0, 1.0]])
        _sim(t_range={"GD": (lo, wide)})
    with pytest.warns(gpmsa.DomainWarning, match="GD"):
        _sim(t_range={"GD": (lo, lo + (hi - lo) / (0.9 * RANGE_COVER_MIN))})
