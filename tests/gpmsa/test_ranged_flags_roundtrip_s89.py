"""`Standardizer.x_ranged` / `t_ranged` flag which columns' domains the user gave (empty: none).
A fit given only an x range read ``t_ranged == ()`` in memory and ``(False,)`` after loading (and
``x_range=[None]`` gave ``(False,)`` in memory): no column given now reads ``()`` everywhere."""

import warnings

import numpy as np
import pytest

import gpmsa


def _fit(**ranges) -> gpmsa.Emulator:
    rng = np.random.default_rng(2)
    x, t = rng.uniform(0.2, 0.8, (10, 1)), rng.uniform(0.2, 0.8, (10, 1))
    data = gpmsa.SimData(x=x, t=t, y=np.sin(3 * x) + t, **ranges)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.GPMSAWarning)
        return gpmsa.fit(data, n_iter=10, tune=False, seed=0, progress=False)


@pytest.mark.parametrize(
    ("ranges", "x_flags", "t_flags"),
    [
        ({"x_range": [(0.0, 1.0)]}, (True,), ()),
        ({"t_range": [(0.0, 1.0)]}, (), (True,)),
        ({"x_range": [None]}, (), ()),
        ({"x_range": [(0.0, 1.0)], "t_range": [None]}, (True,), ()),
        ({}, (), ()),
    ],
)
def test_the_ranged_flags_read_alike_in_memory_and_loaded(ranges, x_flags, t_flags, tmp_path):
    emu = _fit(**ranges)
    emu.save(tmp_path / "e.gpmsa")
    loaded = gpmsa.load(tmp_path / "e.gpmsa")
    for e in (emu, loaded):
        assert (e.standardizer.x_ranged, e.standardizer.t_ranged) == (x_flags, t_flags)
    assert loaded.given_ranges == emu.given_ranges
