"""A campaign path the file system's encoding cannot write (a lone surrogate) is a VehicleError
up front, in saving, loading and as a cache folder, not a UnicodeEncodeError from os.open."""

import os

import numpy as np
import pytest

import vehicle
from vehicle.campaign import Campaign, load_campaign


def _campaign() -> Campaign:
    one = np.ones(2)
    return Campaign(v=one, gd=one, seed=[1, 2], f_full=one, f_window=one, f_full_noisy=one,
                    f_window_noisy=one, status=["ok", "ok"], settings={})  # fmt: skip


def test_saving_a_campaign_to_a_name_the_file_system_cannot_encode_is_a_vehicle_error(tmp_path):
    with pytest.raises(vehicle.VehicleError, match=r"holds '\\ud800', which the file system"):
        _campaign().save(tmp_path / "c\ud800.npz")
    assert os.listdir(tmp_path) == []


def test_loading_such_a_name_and_such_a_cache_folder_are_vehicle_errors(tmp_path):
    with pytest.raises(vehicle.VehicleError, match="ud800"):
        load_campaign(tmp_path / "c\ud800.npz")
    with pytest.raises(vehicle.VehicleError, match="cache_dir=.*ud800"):
        vehicle.run_campaign(np.array([[1.0, 10.0]]), cache_dir=tmp_path / "\ud800")
