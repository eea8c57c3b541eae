"""PSD estimates, the GD fit, Welch, and ISO 8608 road classes."""

from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import roadgen


@pytest.mark.parametrize(
    ("gd", "cls"),
    [
        (1.0, "A"),
        (31.99, "A"),
        (32.0, "B"),
        (100.0, "B"),
        (127.99, "B"),
        (128.0, "C"),
        (300.0, "C"),
        (511.9, "C"),
        (512.0, "D"),
        (2047.0, "D"),
        (2048.0, "E"),
        (8192.0, "F"),
        (32767.0, "F"),
        (32768.0, "G"),
        (131071.0, "G"),
        (131072.0, "H"),
        (1e9, "H"),
    ],
)
def test_road_class_bounds(gd, cls):
    assert roadgen.road_class(gd) == cls


@given(st.floats(1e-3, 1e7))
def test_road_class_grows_by_a_factor_of_4(gd):
    letters = "ABCDEFGH"
    a, b = letters.index(roadgen.road_class(gd)), letters.index(roadgen.road_class(4.0 * gd))
    assert b == min(a + 1, 7) or (a == 0 and b <= 1)


@pytest.mark.parametrize("gd", [0.0, -5.0, np.nan, np.inf, None])
def test_road_class_rejects_bad_gd(gd):
    with pytest.raises(roadgen.RoadgenError, match="gd="):
        roadgen.road_class(gd)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_welch_and_fit_agree_on_long_profiles(seed):
    road = roadgen.iso8608_profile(600.0, 400.0, seed=seed, amplitudes="rayleigh")
    band = (0.05, 5.0)
    fit = roadgen.estimate_gd(road, band=band)
    welch = roadgen.estimate_gd(road, method="welch", band=band)
    assert welch == pytest.approx(fit, rel=0.05)
    assert fit == pytest.approx(400.0, rel=0.1)


def test_welch_psd_follows_the_prescribed_line():
    road = roadgen.iso8608_profile(600.0, 400.0, seed=3)
    n, gd = roadgen.profile_psd(road, method="welch")
    assert n[0] == pytest.approx(1.0 / (road.x.size // 4 * road.dx_m))
    mid = (n > 0.5) & (n < 20.0)
    ratio = gd[mid] / roadgen.gd_spectrum(n[mid], 400.0)
    assert np.mean(ratio) == pytest.approx(1.0, rel=0.05)


def test_estimates_scale_with_gd_and_use_the_roads_waviness():
    road = roadgen.iso8608_profile(150.0, 100.0, seed=0, waviness=3.0)
    assert roadgen.estimate_gd(road) == pytest.approx(100.0, rel=0.01)
    assert roadgen.estimate_gd(road, waviness=2.0) != pytest.approx(100.0, rel=0.1)
    plain = SimpleNamespace(z=road.z * 2.0, dx_m=road.dx_m)  # no settings: w defaults to 2
    assert roadgen.estimate_gd(plain, waviness=3.0) == pytest.approx(400.0, rel=0.01)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"method": "median"}, "method='median'"),
        ({"band": (0.5, 0.1)}, r"band=\(0.5, 0.1\).*n_min < n_max"),
        ({"band": (0.0, 1.0)}, "band="),
        ({"band": (0.1, 100.0)}, r"83.33"),
        ({"band": (0.1, np.nan)}, "band="),
        ({"band": "wide"}, "band="),
        ({"waviness": -1.0}, "waviness"),
    ],
)
def test_bad_estimate_arguments_raise(kwargs, match):
    road = roadgen.iso8608_profile(30.0, 300.0, seed=0)
    with pytest.raises(roadgen.RoadgenError, match=match):
        roadgen.estimate_gd(road, **kwargs)


def test_too_short_a_road_for_the_band_raises():
    road = roadgen.iso8608_profile(12.0, 300.0, seed=0)
    with pytest.raises(roadgen.RoadgenError, match="too short for band"):
        roadgen.estimate_gd(road, band=(0.05, 0.08))
    with pytest.raises(roadgen.RoadgenError, match="too short for band.*'welch'"):
        roadgen.estimate_gd(road, method="welch")
    with pytest.raises(roadgen.RoadgenError, match="nperseg=4"):
        roadgen.profile_psd(road, method="welch", nperseg=4)
    few = SimpleNamespace(z=road.z[:20], dx_m=road.dx_m)  # Welch's default segment < 8 points
    with pytest.raises(roadgen.RoadgenError, match="method='welch' needs a road of >= 32 heights"):
        roadgen.estimate_gd(few, method="welch", band=(10.0, 80.0))
    with pytest.raises(roadgen.RoadgenError, match="method='fft'"):
        roadgen.profile_psd(road, method="fft")


def test_the_papers_check_refuses_a_road_too_short_to_have_a_harmonic_near_n0():
    """method="periodogram" scales one ordinate to n0 along the slope: from a harmonic a decade
    away (a road under a metre) that was an extrapolation returned as a number."""
    z = np.random.default_rng(0).normal(scale=0.01, size=16)
    short = SimpleNamespace(z=z, dx_m=0.05)  # 0.8 m: harmonics every 1.25 cycles/m
    with pytest.raises(roadgen.RoadgenError, match=r"\(0.8 m: harmonics every 1.25 cycles/m\) is "
                       r"1.25 cycles/m, more than a factor 2 from n0.*at least 5 m"):  # fmt: skip
        roadgen.estimate_gd(short, method="periodogram")
    five = roadgen.iso8608_profile(5.0, 450.0, seed=0)  # its first harmonic, 0.2, is within
    assert np.isfinite(roadgen.estimate_gd(five, method="periodogram"))


def test_short_or_flat_roads_are_named_for_what_they_lack():
    rng = np.random.default_rng(0)
    default_too_long = r"with the default nperseg \(N // 4\) needs a road of >= 32 heights"
    cases = ((5, "method='welch' needs a road of >= 8 heights, got 5"), (16, default_too_long))
    for n, match in cases:
        with pytest.raises(roadgen.RoadgenError, match=match):
            roadgen.profile_psd(SimpleNamespace(z=rng.normal(size=n), dx_m=0.05), method="welch")
    for flat in (np.zeros(4000), np.linspace(0.0, 1.0, 4000)):  # no power, not too few bins
        with pytest.raises(roadgen.RoadgenError, match=r"holds no power: the road is flat there"):
            roadgen.psd_slope(SimpleNamespace(z=flat, dx_m=0.006))
    with pytest.raises(roadgen.RoadgenError, match=r"fewer than 2 PSD bins of this road \(0.8 m"):
        roadgen.psd_slope(SimpleNamespace(z=rng.normal(size=16), dx_m=0.05))


def test_estimate_gd_fits_only_inside_the_profiles_band():
    """A band-limited profile is fitted where it has content (settings.band); the paper's check
    at n0 works from a band that starts there and is refused where n0 has no content."""
    from_n0 = roadgen.iso8608_profile(150.0, 450.0, seed=0, band=(0.1, 83.3))
    assert roadgen.estimate_gd(from_n0) == pytest.approx(450.0, rel=1e-3)  # was 424.8
    assert roadgen.estimate_gd(from_n0, method="periodogram") == pytest.approx(450.0, rel=1e-9)
    narrow = roadgen.iso8608_profile(150.0, 450.0, seed=0, band=(0.05, 0.5))
    assert roadgen.estimate_gd(narrow) == pytest.approx(450.0, rel=1e-3)  # was 214
    mid = roadgen.iso8608_profile(150.0, 450.0, seed=0, band=(0.5, 10.0))
    assert roadgen.estimate_gd(mid, method="welch") == pytest.approx(450.0, rel=0.02)
    with pytest.raises(roadgen.RoadgenError, match="n0 = 0.1 cycles/m.*no content there"):
        roadgen.estimate_gd(mid, method="periodogram")
    high = roadgen.iso8608_profile(150.0, 450.0, seed=0, band=(2.0, 10.0))
    for method in ("fit", "welch"):  # was 0.01
        with pytest.raises(roadgen.RoadgenError, match=r"content band settings.band=\(2, 10\)"):
            roadgen.estimate_gd(high, method=method)
    assert roadgen.estimate_gd(high, band=(2.0, 10.0)) == pytest.approx(450.0, rel=1e-3)


@pytest.mark.parametrize(
    ("settings", "match"),
    [
        ({"waviness": "abc"}, r"^road.settings.waviness='abc' must be a real number"),
        ({"waviness": np.nan}, r"^road.settings.waviness=nan must be finite"),
        ({"waviness": -2.0}, r"^road.settings.waviness=-2.0 is out of range"),
        ({"waviness": 2.0, "band": "wide"}, r"^road.settings.band='wide' must be a pair"),
        ({"waviness": 2.0, "band": (0.1, np.nan)}, r"^road.settings.band=\(0.1, nan\)"),
    ],
)
def test_estimate_gd_checks_the_settings_it_reads(settings, match):
    road = roadgen.iso8608_profile(30.0, 300.0, seed=0)
    like = SimpleNamespace(z=road.z, dx_m=road.dx_m, settings=SimpleNamespace(**settings))
    with pytest.raises(roadgen.RoadgenError, match=match):
        roadgen.estimate_gd(like)


def test_welch_on_a_short_road_names_the_welch_min_bin_rule():
    road = roadgen.iso8608_profile(21.0, 450.0, seed=0)
    with pytest.raises(roadgen.RoadgenError, match=r"WELCH_MIN_BIN=6 .*n >= 1.14286 cycles/m, "
                       r"and its bins in the band reach only 0.952\d* cycles/m; use a road "
                       r"longer than 25.2 m"):  # fmt: skip
        roadgen.estimate_gd(road, method="welch")
    assert roadgen.estimate_gd(road, method="welch", band=(0.05, 5.0)) == pytest.approx(
        450.0, rel=0.1
    )


def test_default_band_on_a_coarse_grid_names_the_grid():
    road = roadgen.iso8608_profile(150.0, 450.0, dx_m=1.0, seed=0)
    with pytest.raises(roadgen.RoadgenError, match=r"dx_m=1 m .*too coarse for the default fit "
                       r"band FIT_BAND=\(0.05, 1.0\)"):  # fmt: skip
        roadgen.estimate_gd(road)
    assert roadgen.estimate_gd(road, band=(0.05, 0.5)) == pytest.approx(450.0, rel=0.01)
