"""roadgen's advised numbers are not needlessly moved off the bound, and a Welch fit's usable
bins read as a range a band can hold (session 83 review).

Before: a 9.99 m road at 0.01 m (fundamental 0.1 cycles/m) was told "or use n_min >= 0.100001"
(0.1 itself passes: the float 0.1 lies a hair above 0.1, and the advice was rounded up from
there); and a Welch fit with one usable bin was told "the Welch bins it fits, 1.33334 to
1.33333 cycles/m" (each end rounded inwards), two bins "1.33334 to 1.46666": a band from the
first to the last was refused (out of range, or holding neither bin)."""

import re

import pytest

import roadgen
from roadgen.errors import bound_text


@pytest.mark.parametrize(
    ("value", "up", "digits", "text"),
    [(0.1, True, 6, "0.1"), (66.666, False, 6, "66.666"), (1e-7, False, 6, "1e-07"),
     (0.3, False, 4, "0.3"), (66.66074, True, 6, "66.6608"), (66.66066, False, 6, "66.6606"),
     (123456.5, True, 6, "123457"), (-66.66074, True, 6, "-66.6607")],
)  # fmt: skip
def test_bound_text_rounds_to_nearest_where_that_meets_the_bound(value, up, digits, text):
    assert bound_text(value, up=up, digits=digits) == text


def test_the_advised_n_min_is_the_fundamental_where_it_passes():
    with pytest.raises(roadgen.RoadgenError, match="is too short for band") as err:
        roadgen.iso8608_profile(9.99, 1.0, 0.01, seed=0, band=(0.05, 10.0))
    assert "n_min >= 0.1 cycles/m" in str(err.value)
    roadgen.iso8608_profile(9.99, 1.0, 0.01, seed=0, band=(0.1, 10.0))


@pytest.mark.parametrize("top", [1.7, 1.8, 2.0])  # one, two and three usable Welch bins
def test_the_welch_bins_named_read_as_a_band_that_holds_them(top):
    road = roadgen.iso8608_profile(30.0, 10.0, 0.01, seed=0, band=(1.0, top))
    with pytest.raises(roadgen.RoadgenError, match="Welch bins it fits") as err:
        roadgen.estimate_gd(road, method="welch", band=(0.5, 1.0))
    num = r"([\d.e+-]+)"
    first, last = map(
        float, re.search(f"it fits, {num} to {num} cycles/m", str(err.value)).groups()
    )
    assert first < last
    assert roadgen.estimate_gd(road, method="welch", band=(first, last)) > 0
