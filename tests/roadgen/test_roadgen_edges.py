"""Edges found by a probe of roadgen's public API: arguments that do not apply, waviness beyond
what a method fits, grids and GDs beyond float64, radii beyond the road, tracks of many
segments, and roads built by hand."""

import dataclasses
from types import SimpleNamespace

import numpy as np
import pytest

import roadgen
from roadgen import envelope
from roadgen.track import _amplitude


@pytest.fixture(scope="module")
def road():
    return roadgen.iso8608_profile(150.0, 450.0, seed=0)


def test_psd_slope_fits_inside_the_roads_content_band():
    banded = roadgen.iso8608_profile(150.0, 450.0, seed=0, band=(0.5, 10.0))
    assert roadgen.psd_slope(banded) == pytest.approx(-2.0, abs=0.15)  # 4.33 before
    with pytest.raises(roadgen.RoadgenError, match=r"no content there"):
        roadgen.psd_slope(banded, band=(0.05, 0.3))


def test_welch_refuses_a_waviness_its_correction_does_not_hold():
    steep = roadgen.iso8608_profile(150.0, 450.0, seed=0, waviness=3.5)
    assert roadgen.estimate_gd(steep, method="welch") == pytest.approx(450.0, rel=0.1)
    for w in (4.0, 5.0):
        wavy = roadgen.iso8608_profile(150.0, 450.0, seed=0, waviness=w)
        with pytest.raises(roadgen.RoadgenError, match=r"WELCH_MAX_WAVINESS=3.5.*method='fit'"):
            roadgen.estimate_gd(wavy, method="welch")
        assert roadgen.estimate_gd(wavy) == pytest.approx(450.0, rel=0.01)


def test_arguments_that_do_not_apply_are_refused(road):
    with pytest.raises(roadgen.RoadgenError, match=r"end_match applies to method='periodogram'"):
        roadgen.profile_psd(road, method="welch", end_match=True)
    with pytest.raises(roadgen.RoadgenError, match=r"nperseg applies to method='welch'"):
        roadgen.profile_psd(road, nperseg=10**9)
    with pytest.raises(roadgen.RoadgenError, match=r"band applies to method='fit' and 'welch'"):
        roadgen.estimate_gd(road, method="periodogram", band=(0.01, 0.02))


def test_the_periodogram_method_reads_a_coarse_grid():
    coarse = roadgen.iso8608_profile(1000.0, 450.0, dx_m=1.0, seed=0)
    assert roadgen.estimate_gd(coarse, method="periodogram") == pytest.approx(450.0, rel=1e-6)


def test_grid_steps_and_gds_beyond_float64_are_named(road):
    for dx in (5e-324, 1e-12, 1e308):
        with pytest.raises(roadgen.RoadgenError, match=r"dx_m=.* out of range: allowed \[1e-09"):
            roadgen.Road(x=[0.0, dx, 2 * dx], z=[0.0, 1.0, 0.0], dx_m=dx)
    with pytest.raises(roadgen.RoadgenError, match=r"dx_m=1e\+299 is out of range"):
        roadgen.iso8608_profile(1e300, 450.0, dx_m=1e299, seed=0)
    for make in (lambda: roadgen.iso8608_profile(150.0, 1e-320, seed=0),
                 lambda: roadgen.gd_spectrum([1.0], 1e-320),
                 lambda: roadgen.track([(50.0, 300.0), (50.0, 1e-300)], seed=0)):  # fmt: skip
        with pytest.raises(roadgen.RoadgenError, match=r"gd=.* out of range: allowed \[1e-12"):
            make()
    with pytest.raises(roadgen.RoadgenError, match="Gd\\(n\\) underflows"):
        roadgen.gd_spectrum([1e200], 450.0)
    tiny = SimpleNamespace(z=road.z * 1e-170, dx_m=road.dx_m)
    for method in ("fit", "welch", "periodogram"):
        with pytest.raises(roadgen.RoadgenError, match="PSD underflows float64"):
            roadgen.estimate_gd(tiny, method=method)
    flat = SimpleNamespace(z=np.zeros(road.z.size), dx_m=road.dx_m)
    assert roadgen.estimate_gd(flat) == 0.0  # a flat road is GD 0, not an underflow


def test_a_radius_beyond_the_road_or_the_work_limit_is_refused(road, monkeypatch):
    short = roadgen.iso8608_profile(21.0, 450.0, seed=0)
    for r in (1.1e306, 1e200, 22.0):
        with pytest.raises(roadgen.RoadgenError, match=r"radius_m=.* allowed \(0, 21"):
            roadgen.wheel_envelope(short, r)
    monkeypatch.setattr(envelope, "MAX_ENVELOPE_WORK", 1e5)
    with pytest.raises(roadgen.RoadgenError, match=r"reaches 16 grid steps .* MAX_ENVELOPE_WORK"):
        roadgen.wheel_envelope(road, 0.1)
    monkeypatch.undo()
    assert np.all(roadgen.wheel_envelope(road, 0.1).z >= road.z)


def test_the_rounded_length_message_states_the_real_limit():
    assert roadgen.iso8608_profile(1.0, 450.0, dx_m=0.6, seed=0).length_m == pytest.approx(1.2)
    with pytest.raises(roadgen.RoadgenError, match=r"allowed \(0, length_m / 1.5\]"):
        roadgen.iso8608_profile(1.0, 450.0, dx_m=0.7, seed=0)


def test_a_track_of_many_segments_costs_o_n_and_matches_the_running_sum():
    rng = np.random.default_rng(3)
    for _ in range(30):
        lengths = rng.uniform(0.02, 5.0, rng.integers(1, 40))
        blend = max(min(1.0, lengths.min()), 0.012)
        x = np.arange(int(round(lengths.sum() / 0.006)) + 1) * 0.006
        starts = np.concatenate([[0.0], np.cumsum(lengths)[:-1]])
        amps = np.sqrt(rng.uniform(200.0, 600.0, lengths.size))
        reference = np.full_like(x, amps[0])  # every boundary's step over the whole grid
        for start, step in zip(starts[1:], np.diff(amps), strict=True):
            t = np.clip((x - start) / blend + 0.5, 0.0, 1.0)
            reference += step * 0.5 * (1.0 - np.cos(np.pi * t))
        np.testing.assert_array_equal(_amplitude(x, starts, amps, blend), reference)
    many = roadgen.track(
        [(1.0, 300.0 + 200.0 * (i % 2)) for i in range(3000)], seed=0, lead_in_m=0.5
    )
    assert many.gd_at(1500.5) == 300.0 and many.length_m == pytest.approx(3000.0)


def test_roads_built_by_hand_check_what_they_were_made_from(road):
    fields = {"x": road.x, "z": road.z, "dx_m": road.dx_m, "gd": 450.0}
    for change, match in (
        ({"band": (np.nan, 1.0)}, r"band=\(nan, 1.0\) is out of range"),  # ProfileSettings'
        ({"amplitudes": "x"}, r"amplitudes='x' is not allowed"),  # own check (session 75)
        ({"waviness": -3.0}, r"waviness=-3.0 is out of range"),
        ({"seed": "s"}, r"seed='s' must be None or an integer"),
        ({"lead_in_m": -1.0}, r"lead_in_m=-1.0 is out of range"),
        ({"lead_in_m": 1e9}, r"settings.lead_in_m=1000000000.0 is out of range"),
    ):
        with pytest.raises(roadgen.RoadgenError, match=match):
            roadgen.Profile(**fields, settings=dataclasses.replace(road.settings, **change))
    with pytest.raises(roadgen.RoadgenError, match=r"need a roadgen ProfileSettings"):
        roadgen.Profile(**fields, settings={"band": (0.1, 1.0)})
    paper = roadgen.track([(50, 300), (50, 500), (50, 300)], seed=0)
    base = {f.name: getattr(paper, f.name) for f in dataclasses.fields(paper)}
    for change, match in (({"lead_in_m": 1e9}, r"lead_in_m=1e\+09 is out of range"),
                          ({"blend_m": 1e9}, r"blend_m=1e\+09 is out of range")):  # fmt: skip
        with pytest.raises(roadgen.RoadgenError, match=match):
            roadgen.Track(**(base | change))
