"""Synthesis of ISO 8608 profiles: PSD recovery, slope, band, seeds, lead-in, the Profile API."""

from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import roadgen
from roadgen.iso8608 import gd_spectrum

SEEDS = (0, 1, 2, 3)
GDS = (200.0, 350.0, 450.0, 600.0)


@pytest.mark.parametrize("gd", GDS)
@pytest.mark.parametrize("seed", SEEDS)
def test_fit_recovers_gd_within_1_percent_on_150_m(gd, seed):
    road = roadgen.iso8608_profile(150.0, gd, seed=seed)
    assert roadgen.estimate_gd(road) == pytest.approx(gd, rel=0.01)
    assert roadgen.estimate_gd(road, method="periodogram") == pytest.approx(gd, rel=1e-9)


@pytest.mark.parametrize("gd", GDS)
@pytest.mark.parametrize("seed", SEEDS)
def test_fit_recovers_gd_within_5_percent_on_21_m(gd, seed):
    road = roadgen.iso8608_profile(21.0, gd, seed=seed)
    assert roadgen.estimate_gd(road) == pytest.approx(gd, rel=0.05)


def test_periodogram_equals_prescribed_psd_at_every_harmonic():
    road = roadgen.iso8608_profile(150.0, 450.0, seed=7)
    n, gd = roadgen.profile_psd(road)
    lo, hi = road.settings.band
    inside = (n >= lo) & (n < hi)
    assert np.count_nonzero(inside) > 12000
    np.testing.assert_allclose(gd[inside], gd_spectrum(n[inside], 450.0), rtol=1e-8)


def test_default_band_reaches_the_6_mm_grid_limit():
    road = roadgen.iso8608_profile(21.0, 300.0, seed=0)
    assert road.settings.band[0] == pytest.approx(1.0 / (road.x.size * road.dx_m))
    assert road.settings.band[1] == pytest.approx(0.5 / 0.006)
    n, gd = roadgen.profile_psd(road)
    top = (n > 80.0) & (n < 83.0)
    np.testing.assert_allclose(gd[top], gd_spectrum(n[top], 300.0), rtol=1e-8)


def test_explicit_band_has_no_content_outside():
    road = roadgen.iso8608_profile(50.0, 300.0, seed=0, band=(0.5, 10.0))
    n, gd = roadgen.profile_psd(road)
    total = gd.sum()
    # n_min holds within a relative 1/N (profile.band_edges): the harmonic with 25 cycles over the
    # road's 49.998 m lies at 25 / 50.004 m = 0.49996 cycles/m and is inside
    outside = (n < 0.5 * (1 - 1 / road.x.size) * (1 - 1e-9)) | (n > 10.0 * (1 + 1e-9))
    assert gd[outside].sum() < 1e-20 * total
    inside = ~outside
    np.testing.assert_allclose(gd[inside], gd_spectrum(n[inside], 300.0), rtol=1e-8)


@pytest.mark.parametrize("amplitudes", ["deterministic", "rayleigh"])
def test_psd_slope_is_minus_waviness(amplitudes):
    for seed in SEEDS:
        road = roadgen.iso8608_profile(600.0, 300.0, seed=seed, amplitudes=amplitudes)
        tol = 1e-3 if amplitudes == "deterministic" else 0.15
        assert roadgen.psd_slope(road) == pytest.approx(-2.0, abs=tol)
    road = roadgen.iso8608_profile(150.0, 300.0, seed=0, waviness=2.5)
    assert roadgen.psd_slope(road) == pytest.approx(-2.5, abs=1e-3)
    assert roadgen.estimate_gd(road) == pytest.approx(300.0, rel=0.01)


def test_rayleigh_amplitudes_recover_gd_on_average():
    estimates = [
        roadgen.estimate_gd(roadgen.iso8608_profile(150.0, 400.0, seed=s, amplitudes="rayleigh"))
        for s in range(20)
    ]
    # one 150 m estimate averages ~143 chi-squared ordinates: sd ~8%, so the mean of 20 ~2%
    assert np.mean(estimates) == pytest.approx(400.0, rel=0.06)
    assert np.std(estimates) > 0.02 * 400.0


def test_same_seed_same_profile_and_different_seeds_differ():
    a = roadgen.iso8608_profile(30.0, 300.0, seed=5, amplitudes="rayleigh")
    b = roadgen.iso8608_profile(30.0, 300.0, seed=5, amplitudes="rayleigh")
    c = roadgen.iso8608_profile(30.0, 300.0, seed=6, amplitudes="rayleigh")
    np.testing.assert_array_equal(a.z, b.z)
    assert np.max(np.abs(a.z - c.z)) > 1e-3
    g1 = roadgen.iso8608_profile(30.0, 300.0, seed=np.random.default_rng(9))
    g2 = roadgen.iso8608_profile(30.0, 300.0, seed=np.random.default_rng(9))
    np.testing.assert_array_equal(g1.z, g2.z)
    assert a.settings.seed == 5 and g1.settings.seed is None


def test_grid_length_and_settings():
    road = roadgen.iso8608_profile(150.0, 450.0, seed=0)
    assert road.x.size == 25001
    assert road.length_m == pytest.approx(150.0)
    np.testing.assert_allclose(np.diff(road.x), 0.006)
    assert road.gd == 450.0
    assert road.settings.amplitudes == "deterministic" and road.settings.waviness == 2.0
    with pytest.raises(ValueError):
        road.z[0] = 1.0


def test_lead_in_starts_at_zero_with_zero_slope_and_leaves_the_rest():
    plain = roadgen.iso8608_profile(40.0, 500.0, seed=3)
    road = roadgen.iso8608_profile(40.0, 500.0, seed=3, lead_in_m=1.0)
    assert road.z[0] == 0.0
    assert abs(road.z[1]) < 1e-3 * np.max(np.abs(plain.z))
    after = road.x >= 1.0
    np.testing.assert_array_equal(road.z[after], plain.z[after])
    assert np.all(np.abs(road.z[~after]) <= np.abs(plain.z[~after]))


def test_height_at_interpolates_and_gd_at_is_constant():
    road = roadgen.iso8608_profile(10.0, 300.0, seed=0)
    assert road.height_at(road.x[17]) == pytest.approx(road.z[17])
    mid = 0.5 * (road.x[3] + road.x[4])
    assert road.height_at(mid) == pytest.approx(0.5 * (road.z[3] + road.z[4]))
    s = np.linspace(0.0, road.length_m, 77).reshape(7, 11)
    assert road.height_at(s).shape == (7, 11)
    assert isinstance(road.height_at(2.0), float)
    np.testing.assert_array_equal(road.gd_at(s), np.full((7, 11), 300.0))
    for bad in (-0.1, road.length_m + 0.01, np.nan):
        with pytest.raises(roadgen.RoadgenError, match="allowed positions"):
            road.height_at([1.0, bad])
        with pytest.raises(roadgen.RoadgenError, match="allowed positions"):
            road.gd_at(bad)


@settings(max_examples=25, deadline=None)
@given(
    length=st.floats(5.0, 60.0),
    gd=st.floats(1.0, 1e5),
    dx=st.sampled_from([0.003, 0.006, 0.01, 0.05]),
    seed=st.integers(0, 2**32 - 1),
)
def test_any_valid_profile_has_its_gd_at_every_harmonic(length, gd, dx, seed):
    road = roadgen.iso8608_profile(length, gd, dx_m=dx, seed=seed)
    assert np.all(np.isfinite(road.z))
    assert road.length_m == pytest.approx(round(length / dx) * dx)
    assert abs(np.mean(road.z)) < 1e-9 * max(1.0, np.max(np.abs(road.z)))
    assert roadgen.estimate_gd(road, method="periodogram") == pytest.approx(gd, rel=1e-8)
    n, psd = roadgen.profile_psd(road)
    keep = (n >= 0.2) & (n <= 0.4 / dx)
    slope = np.polyfit(np.log(n[keep]), np.log(psd[keep]), 1)[0]
    assert slope == pytest.approx(-2.0, abs=1e-6)


def test_fit_is_unbiased_on_windows_cut_from_a_longer_road():
    # a window is not periodic: the end-matched fit must not see the wrap-around step
    estimates = []
    for seed in range(20):
        road = roadgen.iso8608_profile(1000.0, 300.0, seed=seed)
        window = SimpleNamespace(z=road.z[10000:26667], dx_m=road.dx_m)
        estimates.append(roadgen.estimate_gd(window))
    assert np.mean(estimates) == pytest.approx(300.0, rel=0.08)


def test_band_starting_at_n0_keeps_the_harmonic_at_n0():
    """On 150 m at 6 mm the period is 150.006 m: 15 cycles over the road lie at 0.099996
    cycles/m, just below the band's n_min = 0.1, and are kept (they were dropped)."""
    road = roadgen.iso8608_profile(150.0, 450.0, seed=0, band=(0.1, 83.3))
    assert road.settings.band == (0.1, 83.3)
    n, gd = roadgen.profile_psd(road)
    k = int(np.argmin(np.abs(n - 0.1)))
    assert n[k] == pytest.approx(15 / 150.006) and n[k] < 0.1
    assert gd[k] == pytest.approx(gd_spectrum(n[k], 450.0), rel=1e-8)
    assert np.all(gd[: k - 1] < 1e-30)  # nothing below it
