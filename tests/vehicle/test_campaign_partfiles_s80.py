"""Campaign.save and the campaign cache with odd but valid paths (session 80 sweep): a save
killed outright leaves no temporary file for ever, a path-like giving bytes and a missing folder
are named."""

import os
import subprocess
import sys

import pytest

import vehicle
from tests.vehicle.test_vehicle_campaign_save_target import _campaign
from vehicle import campaign


def _dead_pid() -> int:
    """The id of a process that ran and ended (and was waited for)."""
    proc = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True)  # fmt: skip
    return int(proc.stdout)


@pytest.mark.skipif(sys.platform == "win32", reason="no process check on Windows")
def test_a_temporary_of_a_killed_save_is_removed_by_the_next_save_to_that_folder(tmp_path):
    """50 SIGKILLs of a process saving a campaign in a loop left 28 hidden '.c.npz.*.part'
    files, which no later save removed (a campaign cache shared by workers gathers them)."""
    host = campaign._host_id()
    dead = f".c.npz.{_dead_pid()}@{host}.0123456789ab.part"
    alive = f".c.npz.{os.getppid()}@{host}.0123456789ab.part"  # the parent runs
    other_host = "0" * 8 if host != "0" * 8 else "1" * 8
    elsewhere = f".c.npz.{_dead_pid()}@{other_host}.0123456789ab.part"
    other = f".d.npz.{_dead_pid()}@{host}.0123456789ab.part"  # another target's
    for name in (dead, alive, elsewhere, other):
        (tmp_path / name).write_bytes(b"half a file")
    _campaign().save(tmp_path / "c.npz")
    assert sorted(os.listdir(tmp_path)) == sorted(["c.npz", alive, elsewhere])
    later = f".e.npz.{_dead_pid()}@{host}.0123456789ab.part"  # killed after the sweep: kept
    (tmp_path / later).write_bytes(b"half a file")  # until another process's first save
    _campaign().save(tmp_path / "f.npz")
    assert later in os.listdir(tmp_path)
    assert vehicle.load_campaign(tmp_path / "c.npz").v.size == 2


def test_a_temporary_names_its_process_and_host(tmp_path, monkeypatch):
    seen = []
    real = os.replace

    def replace(src, dst):
        seen.append(os.path.basename(src))
        real(src, dst)

    monkeypatch.setattr(campaign.os, "replace", replace)
    name = "émulateur_地形" + "x" * 234 + ".npz"  # 255 bytes: the most a name may have
    assert len(os.fsencode(name)) == 255
    _campaign().save(tmp_path / name)
    assert seen[0].startswith(f".{name[:32]}.{os.getpid()}@{campaign._host_id()}.")
    assert len(os.fsencode(seen[0])) < 255 and os.listdir(tmp_path) == [name]


class PathLike:
    def __init__(self, value) -> None:
        self.value = value

    def __fspath__(self):
        return self.value


def test_a_path_like_giving_bytes_is_a_vehicle_error(tmp_path):
    """It raised pathlib's bare TypeError from Campaign.save and load_campaign."""
    given = PathLike(os.fsencode(tmp_path / "c.npz"))
    with pytest.raises(vehicle.VehicleError, match="__fspath__ gives bytes.*os.fsdecode"):
        _campaign().save(given)
    with pytest.raises(vehicle.VehicleError, match="__fspath__ gives bytes"):
        vehicle.load_campaign(given)
    assert os.listdir(tmp_path) == []


def test_a_save_into_a_missing_folder_names_the_folder_not_the_temporary(tmp_path):
    target = tmp_path / "missing" / "c.npz"
    with pytest.raises(
        vehicle.CampaignFileError, match="the folder .*missing' does not exist"
    ) as e:
        _campaign().save(target)
    assert ".part" not in str(e.value) and not target.parent.exists()
