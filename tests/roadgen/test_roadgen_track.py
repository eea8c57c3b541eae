"""Tracks of segments: prescribed GD, continuous joins, lead-in, local roughness, seeds."""

from types import SimpleNamespace

import numpy as np
import pytest

import roadgen

PAPER = [(50, 300), (50, 500), (50, 300)]


def test_paper_track_layout_and_prescribed_gd():
    t = roadgen.track(PAPER, seed=0)
    assert isinstance(t, roadgen.Track)
    assert t.length_m == pytest.approx(150.0)
    assert t.boundaries_m == (0.0, 50.0, 100.0)
    assert t.segments == ((50.0, 300.0), (50.0, 500.0), (50.0, 300.0))
    s = np.array([0.0, 25.0, 49.99, 50.0, 75.0, 99.99, 100.0, 150.0])
    np.testing.assert_array_equal(t.gd_at(s), [300, 300, 300, 500, 500, 500, 300, 300])
    assert t.gd_at(75.0) == 500.0 and isinstance(t.gd_at(75.0), float)
    with pytest.raises(roadgen.RoadgenError, match="allowed positions"):
        t.gd_at(150.5)


def test_track_starts_at_rest_height_with_zero_slope():
    t = roadgen.track(PAPER, seed=1, lead_in_m=1.0)
    assert t.z[0] == 0.0
    assert abs(t.z[1] - t.z[0]) < 0.01 * np.std(np.diff(t.z))
    assert t.height_at(0.0) == 0.0


def _step_ratio(z: np.ndarray, i: int) -> float:
    """Largest |dz| within 10 samples of index i, over the rms |dz| of the whole road."""
    dz = np.diff(z)
    return float(np.max(np.abs(dz[i - 10 : i + 10])) / np.sqrt(np.mean(dz**2)))


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_joins_have_no_step(seed):
    t = roadgen.track(PAPER, seed=seed)
    for b in t.boundaries_m[1:]:
        assert _step_ratio(t.z, round(b / t.dx_m)) < 5.0
    # the check sees a 1 cm step (independent roads butted together differ by ~1-2 cm there)
    i = round(t.boundaries_m[1] / t.dx_m)
    stepped = t.z + 0.01 * (np.arange(t.z.size) > i)
    assert _step_ratio(stepped, i) > 5.0


def test_segments_have_their_prescribed_roughness():
    t = roadgen.track([(300, 300), (300, 500)], seed=4, lead_in_m=1.0, blend_m=2.0)
    for start, gd in ((5.0, 300.0), (305.0, 500.0)):
        i0 = round(start / t.dx_m)
        window = SimpleNamespace(z=t.z[i0 : i0 + round(290.0 / t.dx_m)], dx_m=t.dx_m)
        # ~1400 ordinates in (0.05, 5) cycles/m: sd ~3%
        assert roadgen.estimate_gd(window, band=(0.05, 5.0)) == pytest.approx(gd, rel=0.1)


def test_amplitude_cross_fades_only_within_the_blend():
    base = roadgen.track([(20, 1.0), (20, 1.0)], seed=2, lead_in_m=0.0, blend_m=2.0)
    t = roadgen.track([(20, 100.0), (20, 400.0)], seed=2, lead_in_m=0.0, blend_m=2.0)
    ratio = t.z / np.where(base.z == 0.0, np.nan, base.z)
    x = t.x
    np.testing.assert_allclose(ratio[x < 19.0], 10.0)
    np.testing.assert_allclose(ratio[x > 21.0], 20.0)
    mid = (x > 19.0) & (x < 21.0)
    assert np.all(np.diff(ratio[mid]) >= -1e-9)


def test_seed_reproducible_and_settings_recorded():
    a = roadgen.track(PAPER, seed=11, amplitudes="rayleigh")
    b = roadgen.track(PAPER, seed=11, amplitudes="rayleigh")
    c = roadgen.track(PAPER, seed=12, amplitudes="rayleigh")
    np.testing.assert_array_equal(a.z, b.z)
    assert np.max(np.abs(a.z - c.z)) > 1e-3
    assert a.settings.seed == 11 and a.settings.amplitudes == "rayleigh"
    assert a.lead_in_m == 1.0 and a.blend_m == 1.0


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"segments": []}, "non-empty"),
        ({"segments": [(50, 300, 1)]}, "pairs"),
        ({"segments": 5}, "sequence"),
        ({"segments": [(50, 300), (-1, 300)]}, r"segments\[1\] length_m"),
        ({"segments": [(50, 300), (50, np.nan)]}, r"segments\[1\] gd"),
        ({"segments": PAPER, "blend_m": 0.001}, "blend_m=0.001"),
        ({"segments": PAPER, "blend_m": 60.0}, "blend_m=60"),
        ({"segments": PAPER, "lead_in_m": 49.8}, r"lead_in_m=49.8 .*\[0, 49.5\]"),
        ({"segments": PAPER, "lead_in_m": -1.0}, "lead_in_m"),
        ({"segments": PAPER, "band": (0.001, 10.0)}, "too short for band"),
        (  # no blend fits at all: the segment is named, not an empty range
            {"segments": [(0.01, 400), (5, 300)], "lead_in_m": 0.0},
            r"segment 0 is 0.01 m long, too short for any blend: shorter than two grid steps "
            r"\(2 dx_m = 0.012 m\)",
        ),
    ],
)
def test_bad_track_input_raises(kwargs, match):
    with pytest.raises(roadgen.RoadgenError, match=match):
        roadgen.track(**kwargs)


def test_one_segment_track_is_the_profile_with_the_same_seed():
    t = roadgen.track([(30.0, 400.0)], seed=3, lead_in_m=1.0)
    p = roadgen.iso8608_profile(30.0, 400.0, seed=3, lead_in_m=1.0)
    np.testing.assert_allclose(t.z, p.z, rtol=0, atol=1e-15)
    assert t.settings == p.settings


def test_enveloped_track_still_starts_at_rest_height():
    t = roadgen.track(PAPER, seed=0)
    env = roadgen.wheel_envelope(t, 0.098)
    assert abs(env.z[0]) < 1e-5


@pytest.mark.parametrize(
    ("change", "match"),
    [
        ({"boundaries_m": (0.0, 100.0, 120.0)}, r"do not match segments.*at \(0, 50, 100\) m"),
        ({"boundaries_m": (10.0, 50.0, 100.0)}, "do not match segments"),
        ({"boundaries_m": (0.0, 500.0, 1000.0)}, "do not match segments"),
        ({"boundaries_m": (0.0, 50.0, 100.0 + 1e-6)}, "do not match segments"),
        ({"segments": ((50, 300), (50, 500), (150, 300))}, r"segments span 250 m but the road"),
        ({"segments": ((50, 300), (50, 500), (49.9, 300))}, r"within dx_m / 2 = 0.003 m"),
    ],
)
def test_track_built_directly_checks_boundaries_against_segments(change, match):
    t = roadgen.track(PAPER, seed=0)
    fields = {name: getattr(t, name) for name in t.__dataclass_fields__}
    with pytest.raises(roadgen.RoadgenError, match=match):
        roadgen.Track(**(fields | change))
    same = roadgen.Track(**(fields | {"boundaries_m": (0, 50, 100)}))
    assert same.gd_at(75.0) == 500.0 and same.boundaries_m == (0.0, 50.0, 100.0)


def test_gd_at_takes_the_nominal_end_that_the_grid_rounds_off():
    """10 + 10 m on a 6 mm grid is 3333 steps, 19.998 m: the segments' end, 20 m, is still a
    position of the last segment (the step function is the segments'); beyond it is not."""
    t = roadgen.track([(10, 100), (10, 200)], seed=0)
    assert t.length_m == pytest.approx(19.998)
    assert t.gd_at(20.0) == 200.0
    np.testing.assert_array_equal(t.gd_at([0.0, 10.0, 19.998, 20.0]), [100, 200, 200, 200])
    with pytest.raises(roadgen.RoadgenError, match=r"allowed positions are \[0, 20\] m"):
        t.gd_at(20.001)
    with pytest.raises(roadgen.RoadgenError, match="allowed positions"):
        t.height_at(20.0)  # the heights end where the grid does
    longer = roadgen.track([(10, 100), (10.004, 200)], seed=0)  # rounded up: 20.004 m of road
    assert longer.length_m == pytest.approx(20.004) and longer.gd_at(20.004) == 200.0
