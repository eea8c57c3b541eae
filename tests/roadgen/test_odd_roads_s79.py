"""Odd but valid roads (session 79): estimate_gd's default fit at low waviness."""

import numpy as np
import pytest

import roadgen


def test_fit_refuses_waviness_where_its_end_match_gives_garbage():
    # w = 0.5 is a waviness iso8608_profile accepts; the end-matched fit read GD 450 as 836
    # (seed 15, 150 m) and 1.09 x GD on average over 30 seeds: now refused, naming the remedy
    road = roadgen.iso8608_profile(150, 450, seed=15, waviness=0.5)
    with pytest.raises(roadgen.RoadgenError, match=r"FIT_MIN_WAVINESS=1.*w=0\.5.*'welch'"):
        roadgen.estimate_gd(road)
    with pytest.raises(roadgen.RoadgenError, match=r"w=0\.5"):
        roadgen.estimate_gd(roadgen.iso8608_profile(150, 450, seed=0), waviness=0.5)


def test_low_waviness_remedies_return_the_gd():
    road = roadgen.iso8608_profile(150, 450, seed=15, waviness=0.5)
    assert roadgen.estimate_gd(road, method="periodogram") == pytest.approx(450, rel=1e-9)
    assert roadgen.estimate_gd(road, method="welch") == pytest.approx(450, rel=0.15)


def test_fit_still_recovers_gd_from_the_lowest_waviness_it_takes():
    gds = [
        roadgen.estimate_gd(roadgen.iso8608_profile(150, 450, seed=s, waviness=1.0)) / 450
        for s in range(10)
    ]
    assert np.max(np.abs(np.array(gds) - 1.0)) < 0.06


@pytest.mark.parametrize("gd", [1e-12, 1.0, 1e5, 1e12])
@pytest.mark.parametrize("dx_m", [0.002, 0.02])
def test_gd_extremes_and_grid_steps_come_back(gd, dx_m):
    road = roadgen.iso8608_profile(60, gd, dx_m=dx_m, seed=3)
    assert roadgen.estimate_gd(road, method="periodogram") == pytest.approx(gd, rel=1e-9)
    assert roadgen.estimate_gd(road) == pytest.approx(gd, rel=0.02)


def test_the_psd_plot_of_a_low_waviness_road_recovers_its_gd_by_welch():
    """plot_profile_psd read the recovered GD by the default fit, which now refuses w = 0.5."""
    road = roadgen.iso8608_profile(150, 450, seed=15, waviness=0.5)
    fig = roadgen.plot_profile_psd(road)
    labels = fig.axes[1].get_legend_handles_labels()[1]
    welch = roadgen.estimate_gd(road, method="welch")
    assert f"recovered GD {welch:.1f}" in labels, labels
