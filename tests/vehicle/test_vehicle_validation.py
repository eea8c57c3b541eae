"""The Exudyn models against an independent linear state-space solution (scipy.signal.lsim)."""

import numpy as np
import pytest

import roadgen
import vehicle
from vehicle.linear import linear_model


def _rel_rms(a, b):
    return np.sqrt(np.mean((a - b) ** 2)) / np.sqrt(np.mean(b**2))


@pytest.mark.parametrize(
    ("model", "speed", "length"),
    [
        (vehicle.HalfCar(), 15.0, 40.0),
        (vehicle.HalfCar(tyre_damping_ns_per_m=150.0), 8.0, 30.0),
        (vehicle.Jackal(lift_off=False), 1.5, 10.0),
        (vehicle.Jackal(lift_off=False), 0.6, 6.0),
    ],
)
def test_exudyn_matches_linear_state_space_sample_by_sample(model, speed, length):
    road = roadgen.iso8608_profile(length, gd=500, seed=11)
    trace = vehicle.simulate(model, road, speed)
    ref = vehicle.linear_response(model, road, speed, len(trace))
    np.testing.assert_allclose(trace.t, ref.t, atol=1e-9)
    assert _rel_rms(trace.accel_front, ref.accel_front) < 0.02
    assert _rel_rms(trace.accel_rear, ref.accel_rear) < 0.02
    assert _rel_rms(trace.heave, ref.q[:, -2]) < 0.02
    assert _rel_rms(trace.pitch, ref.q[:, -1]) < 0.02
    assert abs(np.var(trace.accel_front) / np.var(ref.accel_front) - 1) < 0.01


def test_halving_the_step_shrinks_the_error_about_fourfold(rough_road):
    """Second-order convergence of generalised-alpha: the residual is the solver's, not a bug."""
    model = vehicle.Jackal(lift_off=False)
    errs = []
    for sub in (5, 10):
        tr = vehicle.simulate(model, rough_road, 1.0, substeps=sub)
        ref = vehicle.linear_response(model, rough_road, 1.0, len(tr))
        errs.append(_rel_rms(tr.accel_front, ref.accel_front))
    assert 2.5 < errs[0] / errs[1] < 6.0


@pytest.mark.parametrize("model", [vehicle.HalfCar(), vehicle.Jackal()])
def test_linear_matrices_are_symmetric_positive_definite(model):
    lm = linear_model(model)
    for mat in (lm.mass, lm.stiffness):
        np.testing.assert_allclose(mat, mat.T)
        assert np.linalg.eigvalsh(mat).min() > 0


def test_jackal_default_modes_near_documented_frequencies():
    lm = linear_model(vehicle.Jackal())
    w2 = np.sort(np.linalg.eigvals(np.linalg.solve(lm.mass, lm.stiffness)).real)
    freqs = np.sqrt(w2) / (2 * np.pi)
    np.testing.assert_allclose(freqs, [9.0, 10.6], atol=0.15)
