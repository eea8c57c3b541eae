"""``SimData``'s repr names the output index's columns where ``index_names`` gives them ("on index
points time [0, 1] x angle [0, 2]"), also for the default index 0..l-1; without names, as
before. ``ObsData``'s says how many columns an index of points has."""

from __future__ import annotations

import numpy as np
import pytest

import gpmsa

TIME, ANGLE = np.linspace(0.0, 1.0, 4), np.linspace(0.0, 2.0, 5)
POINTS = np.column_stack([np.repeat(TIME, 5), np.tile(ANGLE, 4)])  # (20, 2)


def _sim(index, names=None, l_sim: int = 4) -> gpmsa.SimData:
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(12, 1)), rng.uniform(size=(12, 1))
    y = x + t * np.linspace(1.0, 2.0, l_sim)
    return gpmsa.SimData(x=x, t=t, y=y, index=index, index_names=names)


@pytest.mark.parametrize(
    ("index", "names", "l_sim", "end"),
    [
        (POINTS, ("time", "angle"), 20, "on index points time [0, 1] x angle [0, 2])"),
        (POINTS, None, 20, "on index points [0, 1] x [0, 2])"),
        (TIME * 5, "time", 4, "on index time [0, 5])"),
        (TIME * 5, None, 4, "on index [0, 5])"),
        (None, "time", 4, "on index time [0, 3])"),  # the default index 0..l-1, named
    ],
)  # fmt: skip
def test_the_repr_names_the_index_columns(index, names, l_sim, end):
    text = repr(_sim(index, names, l_sim))
    assert text.endswith(end) and len(text) < 200 and "\n" not in text


def test_without_an_index_or_names_the_repr_is_as_before():
    assert " index" not in repr(_sim(None))


def test_a_long_or_odd_index_name_is_cut_and_escaped():
    text = repr(_sim(POINTS, ("t" * 60, "a\nb"), 20))
    assert f"on index points {'t' * 37}... [0, 1] x a\\nb [0, 2])" in text
    assert "\n" not in text


def test_obsdata_repr_counts_the_columns_of_points():
    obs = gpmsa.ObsData([[0.3]], [np.ones(3)], index=[POINTS[:3]])
    assert repr(obs).endswith("; index given (2 columns))")
    grid = gpmsa.ObsData([[0.3]], [np.ones(3)], index=[TIME[:3]])
    assert repr(grid).endswith("; index given)")
