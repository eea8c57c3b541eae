"""estimate_gd on roads without roughness: GD 0, not a false diagnosis of underflow."""

import numpy as np
import pytest

import roadgen


def _road(z, dx=0.006):
    return roadgen.Road(x=np.arange(len(z)) * dx, z=z, dx_m=dx)


@pytest.mark.parametrize("slope", [1.0, 0.25, 1e-3])
@pytest.mark.parametrize("n_points", [1001, 25001])
def test_a_straight_ramp_has_gd_zero_with_the_end_matched_fit(slope, n_points):
    # end matching removes a ramp exactly: no roughness is left, so GD is 0 (heights of metres,
    # nowhere near float64's underflow)
    ramp = _road(slope * np.arange(n_points))
    assert roadgen.estimate_gd(ramp) == pytest.approx(0.0, abs=1e-20)
    assert roadgen.estimate_gd(ramp, band=(0.1, 10.0)) == pytest.approx(0.0, abs=1e-20)


def test_a_ramp_of_huge_heights_is_not_called_an_underflow():
    huge_ramp = _road(np.arange(5) * 1e200, dx=0.1)  # the end match removes it exactly
    assert roadgen.estimate_gd(huge_ramp, band=(0.5, 5.0)) == pytest.approx(0.0, abs=1e-20)


def test_a_ramp_plus_roughness_recovers_the_roughness():
    p = roadgen.iso8608_profile(150.0, 450.0, seed=0)
    tilted = _road(p.z + 0.02 * p.x)
    assert roadgen.estimate_gd(tilted) == pytest.approx(roadgen.estimate_gd(p), rel=1e-6)


@pytest.mark.parametrize("method", ["fit", "welch", "periodogram"])
def test_heights_whose_squares_underflow_are_still_refused(method):
    p = roadgen.iso8608_profile(150.0, 450.0, seed=0)
    tiny = _road(p.z * 1e-170)
    with pytest.raises(roadgen.RoadgenError, match="PSD underflows float64"):
        roadgen.estimate_gd(tiny, method=method)
    tiny_ramp = _road(1e-170 * (np.arange(p.z.size) + 1e3 * p.z))
    with pytest.raises(roadgen.RoadgenError, match="PSD underflows float64"):
        roadgen.estimate_gd(tiny_ramp, method=method)


@pytest.mark.parametrize(
    ("bad", "match"),
    [
        (
            (1.0, 100.0, 3.0),
            r"^segments\[2000\]=\(1\.0, 100\.0, 3\.0\) is not a \(length_m, gd\) pair",
        ),
        (5, r"^segments\[2000\]=5 is not a \(length_m, gd\) pair"),
        ("ab", r"^segments\[2000\] length_m='a' must be a real number"),
    ],
)
def test_a_malformed_segment_is_named_by_its_index_not_by_the_whole_list(bad, match):
    segments = [(1.0, 100.0)] * 2000 + [bad] + [(1.0, 100.0)]
    with pytest.raises(roadgen.RoadgenError, match=match) as info:
        roadgen.track(segments, seed=0)
    assert len(str(info.value)) < 300  # not the repr of 2002 segments


@pytest.mark.parametrize("segments", [None, 5, 2.5])
def test_segments_that_are_no_sequence_are_refused_by_type(segments):
    with pytest.raises(roadgen.RoadgenError, match=r"segments=.* must be a sequence of"):
        roadgen.track(segments, seed=0)
