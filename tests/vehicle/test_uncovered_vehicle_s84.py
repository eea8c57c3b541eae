"""Paths of vehicle that no test reached before session 84's coverage review: a campaign file's
members of another kind than `Campaign.save` writes (hand-made), a speed schedule of
(points, speeds) that is no such pair, and a drive shorter than one sample period."""

import io
import json
import zipfile

import numpy as np
import pytest

import vehicle
from vehicle import CampaignFileError, VehicleError, load_campaign

_TABLE = {name: np.zeros(2) for name in ("v", "gd", "f_full", "f_window", "f_full_noisy",
                                         "f_window_noisy")}  # fmt: skip
_TABLE |= {"seed": np.zeros(2, dtype=np.int64), "status": np.array(["ok", "ok"])}


def _npz(path, members, compression=zipfile.ZIP_STORED, edit=None):
    """A hand-made .npz: each member's .npy bytes, ``edit``ed where it names the member."""
    with zipfile.ZipFile(path, "w", compression=compression) as zf:
        for name, array in members.items():
            buf = io.BytesIO()
            np.lib.format.write_array(buf, array, allow_pickle=True)
            data = buf.getvalue()
            if edit and name in edit:
                data = edit[name](data)
            zf.writestr(f"{name}.npy", data)
    return path


@pytest.mark.parametrize(
    ("members", "kw", "match"),
    [
        ({"settings": np.array(["{}", "{}"])}, {},
         r"settings must be one JSON string, got a <U2 array of shape \(2,\)"),
        ({"settings": np.array(json.dumps({"format": "other/9"}))}, {},
         r"unknown format, need 'vehicle.campaign/1'"),
        ({"settings": np.array("[1]")}, {}, r"unknown format"),
        ({"settings": np.array("{}")}, {"compression": zipfile.ZIP_BZIP2},
         r"damaged or not a campaign: member v.npy is compressed with method 12"),
        ({"settings": np.array("{}")}, {"edit": {"v": lambda b: b[:6] + b"\x03\x00" + b[8:]}},
         r"member v.npy has .npy version \(3, 0\): need 1.0 or 2.0"),
        ({"settings": np.array("{}"), "v": np.array([1, None], dtype=object)}, {},
         r"member v.npy holds Python objects \(dtype object\): no pickle"),
        ({"settings": np.array("{}")}, {"edit": {"v": lambda b: b + b"xx"}},
         r"member v.npy has data after its array"),
    ],
)  # fmt: skip
def test_a_hand_made_campaign_file_is_refused_naming_what_is_wrong(tmp_path, members, kw, match):
    path = _npz(tmp_path / "c.npz", {**_TABLE, **members}, **kw)
    with pytest.raises(CampaignFileError, match=match):
        load_campaign(path)


@pytest.mark.parametrize(
    ("speed", "speed_of", "match"),
    [
        ((1.0, 2.0, 3.0), "time", r"speed is a tuple of 3 items: need \(points, speeds\)"),
        (([0.0, 1.0], [1.0]), "time", r"speed=\(points \(2,\), speeds \(1,\)\): need two \(K,\)"),
        (([], []), "time", r"need two \(K,\) arrays, K >= 1"),
        (([1.0, 0.0], [1.0, 1.0]), "position", r"speed points must be finite and strictly incr"),
        (([0.0, np.nan], [1.0, 1.0]), "time", r"speed points must be finite and strictly incr"),
    ],
)
def test_a_speed_table_that_is_no_pair_of_points_and_speeds_is_named(
    flat_road, speed, speed_of, match
):
    with pytest.raises(VehicleError, match=match):
        vehicle.simulate(vehicle.Jackal(), flat_road, speed, speed_of=speed_of)


def test_a_drive_shorter_than_one_sample_period_is_named_with_its_remedy(flat_road):
    with pytest.raises(VehicleError, match=r"the drive from 1 m to 1.001 m is shorter than one "
                                           r"sample period \(1/120 s\)"):  # fmt: skip
        vehicle.simulate(vehicle.Jackal(), flat_road, 1.0, start_m=1.0, end_m=1.001)


def test_a_drive_too_slow_for_the_time_limit_is_named(flat_road):
    with pytest.raises(VehicleError, match=r"the drive takes \d.\d+e\+04 s: allowed <= 3600 s"):
        vehicle.simulate(vehicle.Jackal(), flat_road, 1e-4, speed_of="position")
    with pytest.raises(VehicleError, match=r"the drive takes more than 3600 s"):
        vehicle.simulate(vehicle.Jackal(), flat_road, lambda t: 1e-4 + 0.0 * t)
