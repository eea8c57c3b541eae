"""Seeds, oversized requests and the recorded versions of vehicle (issue 15, sections 4-5)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import roadgen
import vehicle
from vehicle import checks

BAD_SEEDS = st.one_of(
    st.integers(max_value=-1),
    st.integers(min_value=2**128, max_value=2**300),
    st.floats(allow_nan=True),
    st.text(max_size=3),
    st.booleans(),
    st.lists(st.integers(0, 9), max_size=2),
)


@settings(max_examples=30, deadline=None, derandomize=True)
@given(seed=BAD_SEEDS)
def test_invalid_seeds_give_a_clear_error_before_any_work(seed, flat_road):
    model = vehicle.Jackal()
    for call in (
        lambda: vehicle.run_campaign(seed=seed, progress=False),
        lambda: vehicle.lhs_design(10, seed=seed),
        lambda: vehicle.simulate(model, flat_road, 1.0, seed=seed),
        lambda: vehicle.Simulation(model, flat_road, seed=seed),
    ):
        with pytest.raises(vehicle.VehicleError, match=r"^seed="):
            call()


def test_oversized_requests_are_refused_before_allocating(flat_road):
    with pytest.raises(vehicle.VehicleError, match=r"n=1000000000000 points needs about .* GiB"):
        vehicle.lhs_design(10**12)
    with pytest.raises(vehicle.VehicleError, match=r"vehicle.checks.MAX_MEMORY_BYTES = 4 GiB"):
        vehicle.simulate(vehicle.Jackal(), flat_road, 1.0, rate_hz=1e9)
    with pytest.raises(roadgen.RoadgenError, match="roadgen.checks.MAX_MEMORY_BYTES"):
        vehicle.run_campaign(np.array([[1.0, 300.0]]), road_length_m=1e7, progress=False)


def test_a_long_advance_stops_at_the_track_end_without_allocating_its_dt(monkeypatch):
    """advance(dt) with a huge dt integrates only up to the end of the track (the samples past
    it were dropped anyway), so it neither allocates dt x rate steps nor changes the result."""
    road = roadgen.iso8608_profile(4.0, 300.0, seed=0, lead_in_m=0.5)
    monkeypatch.setattr(checks, "MAX_MEMORY_BYTES", 50_000_000)
    a = vehicle.Simulation(vehicle.Jackal(), road, seed=1, start_m=0.5)
    far = a.advance(1e12, 1.5)
    b = vehicle.Simulation(vehicle.Jackal(), road, seed=1, start_m=0.5)
    near = b.advance(10.0, 1.5)  # long enough to reach the end
    assert a.finished and b.finished and far.t.size == near.t.size > 100
    np.testing.assert_array_equal(far.accel_front, near.accel_front)


def test_campaign_records_the_versions_that_made_it(tmp_path):
    camp = vehicle.run_campaign(np.array([[1.0, 300.0]]), road_length_m=5.0, window=100,
                                lead_in_m=0.5, progress=False, seed=2)  # fmt: skip
    import exudyn
    import scipy

    versions = camp.settings["versions"]
    assert versions["numpy"] == np.__version__ and versions["scipy"] == scipy.__version__
    assert versions["exudyn"] == exudyn.__version__ and versions["python"].count(".") == 2
    assert "blas" in versions and "machine" in versions
    camp.save(tmp_path / "c.npz")
    assert vehicle.load_campaign(tmp_path / "c.npz").settings["versions"] == versions
