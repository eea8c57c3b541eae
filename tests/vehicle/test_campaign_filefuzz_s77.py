"""Findings of the s77 file fuzz of campaign files: settings JSON that parses under no reader's
limits (an integer of more digits than Python converts) or a ``keep_s`` beyond float64 raised a
bare ValueError or OverflowError out of ``load_campaign``; now a CampaignFileError naming the
settings."""

import io
import json
import zipfile

import numpy as np
import pytest

import vehicle
from vehicle.errors import CampaignFileError


def _saved(tmp_path):
    fs = np.array([1.0, 2.0])
    camp = vehicle.Campaign(
        v=np.array([0.7, 1.6]), gd=np.array([250.0, 550.0]), seed=np.array([3, 4]),
        f_full=fs, f_window=fs, f_full_noisy=fs + 1, f_window_noisy=fs + 1,
        status=np.array(["ok", "ok"]), settings={"keep_s": 0.0, "note": "hand-made"},
    )  # fmt: skip
    camp.save(tmp_path / "c.npz")
    return tmp_path / "c.npz"


def _with_settings(path, text: str):
    """The campaign file at ``path`` with its settings member holding ``text``."""
    with zipfile.ZipFile(path) as zf:
        members = {n: zf.read(n) for n in zf.namelist()}
    buf = io.BytesIO()
    np.save(buf, np.asarray(text), allow_pickle=False)
    members["settings.npy"] = buf.getvalue()
    with zipfile.ZipFile(path, "w") as zf:
        for name, data in members.items():
            zf.writestr(name, data)
    return path


@pytest.mark.parametrize(
    "settings",
    [
        '{"format": "vehicle.campaign/1", "seed": ' + "9" * 5000 + "}",  # > 4300 digits
        '{"format": "vehicle.campaign/1", "keep_s": ' + "9" * 400 + "}",  # beyond float64
    ],
    ids=["int-5000-digits", "keep_s-beyond-float64"],
)
def test_settings_beyond_a_readers_numbers_are_a_campaign_file_error(tmp_path, settings):
    path = _with_settings(_saved(tmp_path), settings)
    with pytest.raises(CampaignFileError, match=r"c\.npz.*settings"):
        vehicle.load_campaign(path)


def test_a_keep_s_within_float64_still_names_the_missing_traces(tmp_path):
    path = _with_settings(_saved(tmp_path), json.dumps({"format": "vehicle.campaign/1",
                                                        "keep_s": 2.5}))  # fmt: skip
    with pytest.raises(CampaignFileError, match=r"keep 2\.5 s of traces per run"):
        vehicle.load_campaign(path)
