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


class NoRunExecutor:
    """Fails the test if a campaign gets as far as submitting a run."""

    def submit(self, *args, **kwargs):
        raise AssertionError("a run was submitted")


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"road_length_m": 1900.0}, r"^design\[1\] \(v=0.5 m/s\) drives 1899.74 m .* 3799 s"),
        ({"keep_s": 3700.0}, r"^design\[1\] \(v=0.5 m/s\) drives 1851.5 m .* 3703 s"),
    ],
)
def test_a_campaign_whose_drives_exceed_the_drive_limit_is_refused_before_any_run(kwargs, match):
    """simulate refuses a drive over MAX_DRIVE_S: every run would fail, so the campaign says so
    before it makes any road (a long road_length_m, or keep_s that lengthens the roads)."""
    args = {"design": np.array([[1.0, 300.0], [0.5, 300.0]]), "progress": False,
            "executor": NoRunExecutor()} | kwargs  # fmt: skip
    with pytest.raises(vehicle.VehicleError, match=match):
        vehicle.run_campaign(**args)


def test_a_constant_speed_drive_over_the_limit_is_refused_at_once(monkeypatch):
    """The drive limit holds exactly for a constant speed (not up to a block of solver steps
    beyond it), named with the drive's duration."""
    from vehicle import kinematics

    monkeypatch.setattr(kinematics, "MAX_DRIVE_S", 10.0)
    road = roadgen.iso8608_profile(11.0, 300.0, seed=0)
    with pytest.raises(vehicle.VehicleError, match=r"^the drive takes 10.74 s: allowed <= 10 s"):
        vehicle.simulate(vehicle.Jackal(), road, 1.0)
    assert len(vehicle.simulate(vehicle.Jackal(), road, 1.1)) > 1000


def test_a_position_schedule_is_refused_before_its_fine_grid_outgrows_the_limit(monkeypatch):
    """speed_of="position" tabulates the schedule every mm of the drive (48 bytes a point): that
    grid is checked against the memory limit before it is made, as the time grid is."""
    from vehicle import kinematics

    monkeypatch.setattr(checks, "MAX_MEMORY_BYTES", 12_000_000)
    s, _ = kinematics.schedule_grid(2.0, "time", 0.0, 300.0, 1 / 600, 2.0)  # 9 MB: allowed
    assert s[-1] >= 300.0
    with pytest.raises(vehicle.VehicleError, match=r"^a speed schedule of position tabulated"):
        kinematics.schedule_grid(2.0, "position", 0.0, 300.0, 1 / 600, 2.0)
    road = roadgen.iso8608_profile(300.0, 300.0, seed=0)
    with pytest.raises(
        vehicle.VehicleError, match=r"\(300001 points\) needs .*checks.MAX_MEMORY_BYTES"
    ):
        vehicle.simulate(vehicle.Jackal(), road, lambda s: 2.0 + 0 * s, speed_of="position",
                         start_m=0.0)  # fmt: skip
