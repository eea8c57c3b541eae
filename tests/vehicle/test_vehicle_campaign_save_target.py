"""Campaign.save and what already lies at its path: a campaign file is replaced (keeping its
permissions), anything else is refused and left whole."""

import os
import stat
import zipfile

import numpy as np
import pytest

import vehicle


def _campaign(f: float = 40.0) -> vehicle.Campaign:
    """A two-run table built by hand (no simulation)."""
    fs = np.array([f, 2 * f])
    return vehicle.Campaign(
        v=np.array([0.7, 1.6]), gd=np.array([250.0, 550.0]), seed=np.array([3, 4]),
        f_full=fs, f_window=fs, f_full_noisy=fs + 1, f_window_noisy=fs + 1,
        status=np.array(["ok", "ok"]), settings={"note": "hand-made"},
    )  # fmt: skip


def _emulator_like(path) -> None:
    """A zip of another program's members, as a gpmsa emulator file is."""
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr("manifest.json", '{"format": "gpmsa/1"}')
        zf.writestr("arrays/theta.npy", b"\x93NUMPY")


@pytest.mark.parametrize(
    "write",
    [
        lambda p: p.write_text("measured on the robot, 3 days of work\n"),
        _emulator_like,
        lambda p: np.savez(p, v=np.arange(3.0)),  # an npz of other arrays
        lambda p: p.write_bytes(b"PK\x03\x04 truncated"),
    ],
    ids=["text", "emulator-zip", "other-npz", "damaged-zip"],
)
def test_save_refuses_to_replace_a_file_that_is_not_a_campaign(tmp_path, write):
    path = tmp_path / "target.npz"
    write(path)
    before = path.read_bytes()
    with pytest.raises(vehicle.CampaignFileError, match="not a campaign file.*remove it first"):
        _campaign().save(path)
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["target.npz"]  # no temporary left


def test_save_refuses_a_folder_by_name(tmp_path):
    folder = tmp_path / "runs"
    folder.mkdir()
    with pytest.raises(vehicle.CampaignFileError, match="runs'.*not a regular file"):
        _campaign().save(folder)
    assert folder.is_dir() and not any(folder.iterdir())


def test_save_replaces_a_campaign_file_or_an_empty_file(tmp_path):
    path = tmp_path / "c.npz"
    _campaign(40.0).save(path)
    _campaign(50.0).save(path)
    np.testing.assert_array_equal(vehicle.load_campaign(path).f_full, [50.0, 100.0])
    empty = tmp_path / "empty.npz"
    empty.touch()
    _campaign(60.0).save(empty)
    np.testing.assert_array_equal(vehicle.load_campaign(empty).f_full, [60.0, 120.0])


@pytest.mark.skipif(os.name != "posix", reason="POSIX permission bits")
def test_a_replaced_campaign_file_keeps_its_permissions(tmp_path):
    path = tmp_path / "private.npz"
    _campaign(40.0).save(path)
    path.chmod(0o600)
    _campaign(50.0).save(path)
    assert stat.S_IMODE(path.stat().st_mode) == 0o600
    np.testing.assert_array_equal(vehicle.load_campaign(path).f_full, [50.0, 100.0])
