"""Bad-input audit (session 75): ``linear_response`` of a model whose fields are far out of
range (finite gains, but the state-space solution overflows) returned NaN accelerations; and
``run_campaign`` let every run fail with NaN f (the error in ``status``) for a rate_hz x
substeps whose solver time grid exceeds the memory limit, where its docstring promises that
check before any run."""

import numpy as np
import pytest

import roadgen
import vehicle
from vehicle import VehicleError


@pytest.fixture(scope="module")
def road():
    return roadgen.iso8608_profile(4.0, 300.0, seed=0, lead_in_m=0.5)


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("mass_kg", 1e-300),
        ("pitch_inertia_kgm2", 1e-300),
        ("tyre_stiffness_n_per_m", 1e300),
        ("tyre_damping_ns_per_m", 1e300),
    ],
)
def test_linear_response_refuses_an_overflowing_model_instead_of_nan(road, field, value):
    with pytest.raises(VehicleError, match="linear response overflows"):
        vehicle.linear_response(vehicle.Jackal(**{field: value}), road, 1.0, 50)


def test_linear_response_of_the_default_model_is_unchanged(road):
    lt = vehicle.linear_response(vehicle.Jackal(), road, 1.0, 50)
    assert np.all(np.isfinite(lt.accel_front)) and lt.accel_front.shape == (50,)


@pytest.mark.parametrize("setting", [{"rate_hz": 1e7}, {"substeps": 10**30}, {"rate_hz": 1e300}])
def test_run_campaign_checks_the_solver_grid_memory_before_any_run(setting):
    design = np.array([[1.0, 300.0], [0.5, 300.0]])
    with pytest.raises(
        VehicleError, match=r"design\[1\] \(v=0.5 m/s\): a drive of .* solver steps"
    ):
        vehicle.run_campaign(design, road_length_m=4.0, window=100, progress=False, **setting)


def test_run_campaign_within_the_limit_still_runs():
    c = vehicle.run_campaign(
        np.array([[1.0, 300.0]]), road_length_m=4.0, window=100, progress=False
    )
    assert list(c.status) == ["ok"] and np.isfinite(c.f_full[0])
