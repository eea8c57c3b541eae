"""A track synthesised on another grid or band than the emulator's training roads (session 69).

Found in a walkthrough on tracks outside the repository: ``roadgen.track(..., dx_m=0.02)`` on
the paper's layout, seed 101, Test Case B, read GD 500 as 358 on average with every estimate
"ok", and the robot drove 20.6 m faster than v_safe on the GD-500 part (2.4 m with the
training roads' 6 mm grid), without a word: a coarser grid (or a band that stops short of the
training roads' Nyquist limit) drops the short waves that the tyre modes respond to, so the
emulator reads the road smoother than its GD. The noise level has a warning for this; the
road's grid and band now have one too (`control.check_emulator` with a track).
"""

from __future__ import annotations

import warnings

import pytest

import control
import roadgen
from control.errors import ControlWarning

SEGMENTS = [(3.0, 300.0), (3.0, 500.0)]


def test_track_on_a_coarser_grid_warns(emulator_a):
    track = roadgen.track(SEGMENTS, seed=101, dx_m=0.02)
    with pytest.warns(ControlWarning, match=r"dx_m = 0\.02 m .* 0\.006 m.*biased"):
        control.check_emulator(emulator_a, track=track)


def test_track_with_a_narrower_band_warns(emulator_a):
    track = roadgen.track(SEGMENTS, seed=101, band=(0.5, 20.0))
    with pytest.warns(ControlWarning, match=r"band up to 20 cycles/m .* 83\.3"):
        control.check_emulator(emulator_a, track=track)


def test_track_like_the_training_roads_does_not_warn(emulator_a, emulator_b):
    track = roadgen.track(SEGMENTS, seed=101)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        control.check_emulator(emulator_a, track=track)
        control.check_emulator(emulator_b, track=track)


@pytest.mark.parametrize(
    "road",
    [None, "0.006", {"band": None}, {"dx_m": "0.006"}, {"dx_m": True}, {"dx_m": -1.0},
     {"dx_m": "0.006", "band": "wide"}, {"dx_m": float("nan"), "band": [0.1, float("nan")]}],
)  # fmt: skip
def test_road_metadata_that_says_nothing_is_not_questioned(emulator_a, road):
    """A file records what it likes (files are shared between users who do not trust each
    other): a road record that is missing or malformed gives no warning and no crash."""
    track = roadgen.track(SEGMENTS, seed=101, dx_m=0.02, band=(0.5, 20.0))
    meta = {k: v for k, v in emulator_a.metadata.items() if k != "road"}
    if road is not None:
        meta["road"] = road
    bare = type("Bare", (), {})()
    for name in ("domain", "t_names", "x_names"):
        setattr(bare, name, getattr(emulator_a, name))
    bare.metadata = meta
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        control.check_emulator(bare, track=track)


def test_a_track_like_object_without_a_band_is_judged_by_its_grid_alone(emulator_a):
    """A track-like object whose settings say ``band=None`` (or have no settings): only its
    grid step is compared (this raised TypeError, indexing None)."""
    from types import SimpleNamespace

    from control.compat import _track_road_mismatch

    for settings in (SimpleNamespace(band=None), None):
        coarse = SimpleNamespace(dx_m=0.02, settings=settings)
        assert _track_road_mismatch(emulator_a.metadata, coarse) == "dx_m = 0.02 m against 0.006 m"
        same = SimpleNamespace(dx_m=0.006, settings=settings)
        assert _track_road_mismatch(emulator_a.metadata, same) == ""
