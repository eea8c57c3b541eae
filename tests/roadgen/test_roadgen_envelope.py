"""Wheel enveloping: the path of a rigid wheel's lowest point."""

import time

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import roadgen


def _flat(n=500, dx=0.006, height=0.0):
    road = roadgen.iso8608_profile(n * dx, 300.0, dx_m=dx, seed=0)
    return roadgen.Profile(
        x=road.x, z=np.full(road.x.size, height), dx_m=dx, gd=300.0, settings=road.settings
    )


def _with_z(road, z):
    return roadgen.Profile(x=road.x, z=z, dx_m=road.dx_m, gd=road.gd, settings=road.settings)


def test_envelope_is_never_below_the_profile_and_keeps_the_type():
    road = roadgen.iso8608_profile(150.0, 600.0, seed=0)
    env = roadgen.wheel_envelope(road, 0.098)
    assert isinstance(env, roadgen.Profile) and env.gd == road.gd
    assert np.all(env.z >= road.z)
    assert np.max(env.z - road.z) > 1e-4
    t = roadgen.track([(50, 300), (50, 500), (50, 300)], seed=0)
    env_t = roadgen.wheel_envelope(t, 0.098)
    assert isinstance(env_t, roadgen.Track) and env_t.boundaries_m == t.boundaries_m
    assert np.all(env_t.z >= t.z)


def test_flat_road_is_unchanged():
    road = _flat(height=0.02)
    np.testing.assert_array_equal(roadgen.wheel_envelope(road, 0.3).z, road.z)


def test_narrow_pothole_is_bridged_and_a_spike_becomes_a_circular_arc():
    road = _flat()
    r = 0.098
    pit = road.z.copy()
    pit[250:253] = -0.05  # 18 mm wide, 50 mm deep
    env = roadgen.wheel_envelope(_with_z(road, pit), r).z
    assert env[251] > -0.001
    spike = road.z.copy()
    spike[250] = 0.01
    env = roadgen.wheel_envelope(_with_z(road, spike), r).z
    d = (np.arange(road.x.size) - 250) * road.dx_m
    arc = np.where(np.abs(d) <= r, 0.01 + np.sqrt(np.clip(r * r - d * d, 0, None)) - r, 0.0)
    np.testing.assert_allclose(env, np.maximum(arc, 0.0), atol=1e-12)


def test_envelope_removes_short_wavelengths_but_keeps_long_ones():
    road = roadgen.iso8608_profile(150.0, 450.0, seed=1)
    env = roadgen.wheel_envelope(road, 0.098)
    n, g = roadgen.profile_psd(road)
    _, ge = roadgen.profile_psd(env)
    long_ = (n >= 0.05) & (n <= 1.0)
    short = n >= 20.0
    assert ge[long_].sum() / g[long_].sum() == pytest.approx(1.0, rel=0.02)
    assert ge[short].sum() / g[short].sum() < 0.6
    assert roadgen.estimate_gd(env) == pytest.approx(450.0, rel=0.02)


def test_tiny_radius_gives_the_profile_back():
    road = roadgen.iso8608_profile(10.0, 450.0, seed=2)
    np.testing.assert_array_equal(roadgen.wheel_envelope(road, 0.5 * road.dx_m).z, road.z)
    np.testing.assert_allclose(roadgen.wheel_envelope(road, 1e-9).z, road.z)


@settings(max_examples=30, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    r1=st.floats(0.001, 0.3),
    r2=st.floats(0.001, 0.3),
)
def test_envelope_grows_with_radius(seed, r1, r2):
    road = roadgen.iso8608_profile(3.0, 2000.0, seed=seed, amplitudes="rayleigh")
    lo, hi = sorted((r1, r2))
    e_lo = roadgen.wheel_envelope(road, lo).z
    e_hi = roadgen.wheel_envelope(road, hi).z
    assert np.all(road.z <= e_lo + 1e-15)
    assert np.all(e_lo <= e_hi + 1e-15)


def test_150_m_envelope_is_fast():
    road = roadgen.iso8608_profile(150.0, 450.0, seed=0)
    times = []
    for _ in range(5):
        t0 = time.perf_counter()
        roadgen.wheel_envelope(road, 0.098)
        times.append(time.perf_counter() - t0)
    assert np.median(times) < 0.25


@pytest.mark.parametrize("radius", [0.0, -0.1, np.nan, np.inf, "big"])
def test_bad_radius_raises(radius):
    road = roadgen.iso8608_profile(3.0, 300.0, seed=0)
    with pytest.raises(roadgen.RoadgenError, match="radius_m"):
        roadgen.wheel_envelope(road, radius)
