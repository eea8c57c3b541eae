"""Findings of the s64 fuzz of campaign files and the campaign's run cache (/tmp/fuzz): a
damaged or hostile file is refused with CampaignFileError (a cache entry: recomputed), never an
exception of numpy's header parser, never read two ways."""

import io
import zipfile
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import vehicle

DESIGN = np.array([[0.7, 250.0], [1.6, 550.0]])
SHORT = {"road_length_m": 6.0, "window": 300, "lead_in_m": 0.5, "progress": False, "seed": 1}


@pytest.fixture(scope="module")
def saved(tmp_path_factory):
    """(campaign file, cache folder, campaign) of 2 runs keeping 5 s of traces (accel members
    of 4.8 and 9.6 KB: zipfile reads 4 KB at a time and checks a CRC only at its member's end,
    after numpy has parsed the header)."""
    root = tmp_path_factory.mktemp("fuzz64")
    with ThreadPoolExecutor(1) as ex:
        camp = vehicle.run_campaign(
            DESIGN, keep_s=5.0, cache_dir=root / "cache", executor=ex, **SHORT
        )
    camp.save(root / "c.npz")
    return root / "c.npz", root / "cache", camp


def _members(path) -> dict[str, bytes]:
    with zipfile.ZipFile(path) as zf:
        return {i.filename: zf.read(i) for i in zf.infolist()}


def _zip(members: list[tuple[str, bytes]]) -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        for name, data in members:
            zf.writestr(name, data)
    return buf.getvalue()


@pytest.mark.parametrize(
    ("old", "new"),
    [(b"600), }", b"600(, }"), (b": '<f8'", b": '''8'"), (b"'<f8'", b"',f8'")],
    ids=["unclosed bracket", "unclosed string", "comma dtype"],
)
def test_one_flipped_byte_of_a_large_members_header_is_a_campaign_file_error(
    saved, tmp_path, old, new
):
    """An unclosed bracket or string in a .npy header sends numpy's parser to tokenize, whose
    TokenError escaped ``load_campaign``, and the dtype ',f8' (one bit off '<f8') numpy's
    SyntaxError: numpy parses a member's header before zipfile checks its CRC (at its end,
    4 KB reads). 190 of 11,264 one-bit flips of a campaign file's .npy headers escaped so."""
    path, _, _ = saved
    data = path.read_bytes()
    at = data.index(b"'shape': (2, 600), }")  # accel.npy's header
    head = data[at - 60 : at + 24]
    assert head.count(old) == 1
    damaged = tmp_path / "c.npz"
    damaged.write_bytes(data[: at - 60] + head.replace(old, new) + data[at + 24 :])
    with pytest.raises(vehicle.CampaignFileError, match="is damaged or not a campaign"):
        vehicle.load_campaign(damaged)


def test_a_damaged_header_of_a_cache_entry_is_recomputed(saved, tmp_path):
    _, cache, camp = saved
    folder = tmp_path / "cache"
    folder.mkdir()
    for entry in cache.glob("run-*.npz"):
        data = entry.read_bytes()
        damaged = data.replace(b"'shape': (600,), }", b"'shape': (600,(, }", 1)  # accel.npy's
        assert len(damaged) == len(data) != damaged
        (folder / entry.name).write_bytes(damaged)
    with ThreadPoolExecutor(1) as ex:
        again = vehicle.run_campaign(DESIGN, keep_s=5.0, cache_dir=folder, executor=ex, **SHORT)
    np.testing.assert_array_equal(again.accel, camp.accel)
    np.testing.assert_array_equal(again.f_full, camp.f_full)


def test_a_member_held_twice_is_refused(saved, tmp_path):
    """zipfile reads the last of two members of one name (numpy's np.load too), another reader
    the first: a file that reads two ways is refused, as gpmsa's emulator files are."""
    path, _, _ = saved
    members = list(_members(path).items())
    v = np.lib.format.read_array(io.BytesIO(dict(members)["v.npy"]))
    buf = io.BytesIO()
    np.lib.format.write_array(buf, v * 1.5)
    damaged = tmp_path / "c.npz"
    with pytest.warns(UserWarning, match="Duplicate name"):
        damaged.write_bytes(_zip([*members, ("v.npy", buf.getvalue())]))
    with pytest.raises(vehicle.CampaignFileError, match="'v.npy' more than once"):
        vehicle.load_campaign(damaged)


def test_a_cache_entry_with_non_finite_traces_is_recomputed(saved, tmp_path):
    """An entry of the right key whose kept traces hold NaN passed as a finished run; the
    campaign then failed on its own table (VehicleError "Campaign.accel[0] is not finite")
    instead of recomputing the run."""
    _, cache, camp = saved
    folder = tmp_path / "cache"
    folder.mkdir()
    for entry in cache.glob("run-*.npz"):
        members = _members(entry)
        accel = np.lib.format.read_array(io.BytesIO(members["accel.npy"]))
        accel[5] = np.nan
        buf = io.BytesIO()
        np.lib.format.write_array(buf, accel)
        members["accel.npy"] = buf.getvalue()
        (folder / entry.name).write_bytes(_zip(list(members.items())))
    with ThreadPoolExecutor(1) as ex:
        again = vehicle.run_campaign(DESIGN, keep_s=5.0, cache_dir=folder, executor=ex, **SHORT)
    assert again.ok.all()
    np.testing.assert_array_equal(again.accel, camp.accel)


def test_a_path_that_starts_with_a_tilde_is_the_home_folder(saved, tmp_path, monkeypatch):
    """Campaign.save("~/c.npz") failed "No such file" (a folder named "~" in the working
    directory); a leading ~ is the home folder, as gpmsa's and control's files take it."""
    monkeypatch.setenv("HOME", str(tmp_path))
    monkeypatch.chdir(tmp_path)
    campaign = saved[2]
    campaign.save("~/c.npz")
    assert (tmp_path / "c.npz").is_file()
    np.testing.assert_array_equal(vehicle.load_campaign("~/c.npz").f_full, campaign.f_full)


def test_a_name_that_only_starts_with_a_tilde_is_a_file_of_that_name(saved, tmp_path, monkeypatch):
    """Campaign.save("~x.npz") raised RuntimeError (Path.expanduser reads "~x" as user x's
    home): only "~" and "~/..." are the home folder."""
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    monkeypatch.chdir(tmp_path)
    saved[2].save("~nosuchuser.npz")
    assert (tmp_path / "~nosuchuser.npz").is_file()
    assert vehicle.load_campaign("~nosuchuser.npz").f_full.shape == saved[2].f_full.shape
