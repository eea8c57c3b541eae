"""Following the numbers roadgen's errors advise clears the error (session 83). Before: a band
whose n_min lay below a 50 m road's fundamental was told "needs length_m >= 66.6607 m (or use
n_min >= 0.0199984 cycles/m)", and both, given back, were refused again (the length is rounded
to whole steps, and both were rounded towards failing); a grid too coarse for estimate_gd's
default band was told "pass a band inside (0, 0.714286]", above its Nyquist frequency
0.7142857 and refused; a Welch fit whose band lay inside the road's content band but within its
2-bin margins was told "pass a band inside settings.band", which it already was."""

import re

import pytest

import roadgen
from roadgen.errors import bound_text


def _number(pattern: str, text: str) -> float:
    return float(re.search(pattern, text).group(1))


@pytest.mark.parametrize(
    ("length_m", "dx_m", "n_min"), [(50.0, 0.006, 0.015), (1.0, 0.006, 0.2), (1.0, 0.006, 0.9)]
)
def test_the_advised_length_and_n_min_pass_the_band_check(length_m, dx_m, n_min):
    band = (n_min, 10.0)
    with pytest.raises(roadgen.RoadgenError, match="is too short for band") as err:
        roadgen.iso8608_profile(length_m, 10.0, dx_m, seed=0, band=band)
    text = str(err.value)
    need = _number(r"needs length_m >= ([\d.e+-]+) m", text)
    least = _number(r"or use n_min >= ([\d.e+-]+) cycles/m", text)
    roadgen.iso8608_profile(need, 10.0, dx_m, seed=0, band=band)
    roadgen.iso8608_profile(length_m, 10.0, dx_m, seed=0, band=(least, 10.0))


def test_the_advised_band_for_a_coarse_grid_is_accepted():
    road = roadgen.iso8608_profile(200.0, 10.0, dx_m=0.7, seed=0)
    with pytest.raises(roadgen.RoadgenError, match="too coarse") as err:
        roadgen.estimate_gd(road)
    top = _number(r"pass a band inside \(0, ([\d.e+-]+)\]", str(err.value))
    assert roadgen.estimate_gd(road, band=(0.05, top)) > 0


def test_a_welch_band_within_the_margins_is_told_the_bins_it_can_fit():
    road = roadgen.iso8608_profile(30.0, 10.0, seed=0)
    with pytest.raises(roadgen.RoadgenError, match="less 2 Welch bins") as err:
        roadgen.estimate_gd(road, method="welch", band=(0.05, 0.3))
    assert "pass a band inside settings.band" not in str(err.value)
    first = _number(r"Welch bins it fits, ([\d.e+-]+) to", str(err.value))
    assert roadgen.estimate_gd(road, method="welch", band=(0.05, first)) > 0
    assert roadgen.estimate_gd(road, method="fit", band=(0.05, 0.3)) > 0


@pytest.mark.parametrize("value", [66.66074, 0.01999840012798976, 0.7142857142857143, 1e-300])
def test_bound_text_rounds_towards_the_bound(value):
    assert float(bound_text(value, up=True)) >= value
    assert float(bound_text(value, up=False)) <= value
    assert len(bound_text(value, up=True).replace(".", "").split("e")[0].lstrip("0")) <= 6
