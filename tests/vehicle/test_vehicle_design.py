"""lhs_design and design validation."""

import numpy as np
import pytest

import vehicle
from vehicle.design import check_design


def test_lhs_is_stratified_in_both_dimensions_and_seeded():
    d = vehicle.lhs_design(50, v_range=(0.5, 2.0), gd_range=(200, 600), seed=7)
    assert d.shape == (50, 2)
    for col, (lo, hi) in enumerate([(0.5, 2.0), (200, 600)]):
        bins = np.floor((d[:, col] - lo) / (hi - lo) * 50).astype(int)
        assert sorted(bins) == list(range(50))  # exactly one point per stratum
    np.testing.assert_array_equal(d, vehicle.lhs_design(50, seed=7))
    assert not np.array_equal(d, vehicle.lhs_design(50, seed=8))


def test_default_design_is_the_papers():
    d = vehicle.lhs_design(seed=0)
    assert d.shape == (198, 2)
    assert d[:, 0].min() >= 0.5 and d[:, 0].max() <= 2.0
    assert d[:, 1].min() >= 200 and d[:, 1].max() <= 600


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [({"n": 0}, "n=0"), ({"v_range": (2.0, 0.5)}, "v_range"), ({"gd_range": (0, 600)}, "gd_range")],
)
def test_bad_design_arguments_raise(kwargs, match):
    with pytest.raises(vehicle.VehicleError, match=match):
        vehicle.lhs_design(**kwargs)


@pytest.mark.parametrize(
    ("design", "match"),
    [
        ([[2.5, 300.0]], r"v=2.5 m/s: allowed \(0, 2\]"),
        ([[1.0, 300.0], [0.0, 300.0]], r"design\[1\] has v=0.0"),
        ([[1.0, float("nan")]], "GD=nan"),
        ([1.0, 300.0], r"shape \(2,\)"),
    ],
)
def test_design_outside_the_models_validity_raises(design, match):
    with pytest.raises(vehicle.VehicleError, match=match):
        check_design(design, vehicle.Jackal())
