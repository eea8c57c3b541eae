"""A campaign's road too short for its window names a road_length_m that passes (session 83).
Before: a run at 1.2345 m/s with a 1000-sample window was told "needs road_length_m >= 11.81 m"
(the need, 11.8115 m, rounded down), and road_length_m=11.81 was refused again."""

import re

import numpy as np
import pytest

import vehicle
import vehicle.campaign


class _Passed(Exception):
    """Raised where the campaign goes on past its road-length check."""


def _past_the_length_check(*args, **kwargs):
    raise _Passed


def test_the_advised_road_length_passes_the_window_check(monkeypatch):
    design = np.array([[1.2345, 50.0]])
    kw = {"window": 1000, "progress": False, "noise_std": 0.0}
    with pytest.raises(vehicle.VehicleError, match="is too short: a 1000-sample window") as err:
        vehicle.run_campaign(design, road_length_m=5.0, **kw)
    need = float(re.search(r"needs road_length_m >= ([\d.e+-]+) m", str(err.value)).group(1))
    monkeypatch.setattr(vehicle.campaign, "_check_drives", _past_the_length_check)
    with pytest.raises(_Passed):
        vehicle.run_campaign(design, road_length_m=need, **kw)
