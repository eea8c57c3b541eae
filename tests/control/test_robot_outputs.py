"""The replay's and the recorder's outputs, and the MCAP reader: an output never replaces what is
read (the whole bag folder of a file given inside one, the emulator file) nor a file that is no
CSV of estimates, and a truncated bare MCAP file is named as truncated."""

import os
import shutil

import numpy as np
import pytest

pytest.importorskip("rosbags")
pytest.importorskip("mcap")

from control.errors import BagError, ControlError  # noqa: E402
from control.robot import read_recording, replay_bag, write_sensor_bag  # noqa: E402
from control.robot.replay import CSV_HEADER  # noqa: E402
from control.robot.storage import MIN_MCAP_BYTES  # noqa: E402
from control.shipped import shipped_emulator_path  # noqa: E402


def _drive(n: int = 400):
    """(IMU time s, accel, odometry time s, position, speed) of n samples at 120 Hz, 1 m/s."""
    t = 1.0 + np.arange(n) / 120.0
    accel = np.random.default_rng(1).normal(size=n)
    return t, accel, t, t - 1.0, np.ones(n)


@pytest.fixture
def bag(tmp_path):
    """A short, healthy ROS 2 bag (MCAP storage), fresh per test: a test may damage it."""
    return write_sensor_bag(tmp_path / "drive", *_drive())


def test_outputs_inside_the_bag_folder_of_a_given_mcap_file_are_refused(bag):
    """Given the bag as its *.mcap file, the folder is what is read: csv= its metadata.yaml
    replaced that file (the bag no longer loaded) and out_bag= a folder in it was written."""
    mcap = next(bag.glob("*.mcap"))
    before = {p.name: p.read_bytes() for p in bag.iterdir()}
    for kwargs in ({"csv": bag / "metadata.yaml"}, {"csv": bag / "estimates.csv"},
                   {"out_bag": bag / "sub"}):  # fmt: skip
        name = next(iter(kwargs))
        with pytest.raises(ControlError, match=rf"{name}=.* would overwrite the recording "
                                               rf".*its bag folder .* is read"):  # fmt: skip
            replay_bag(mcap, "A", **kwargs)
    assert {p.name: p.read_bytes() for p in bag.iterdir()} == before
    assert read_recording(bag).imu.stamp_ns.size == 400


def test_the_emulator_file_given_is_never_an_output(bag, tmp_path):
    emulator = tmp_path / "jackal.gpmsa"
    shutil.copy(shipped_emulator_path("A"), emulator)
    before = emulator.read_bytes()
    os.link(emulator, tmp_path / "hard.csv")
    for csv in (emulator, str(emulator), tmp_path / "hard.csv"):
        with pytest.raises(ControlError, match=r"csv=.* would overwrite the emulator file"):
            replay_bag(bag, emulator, csv=csv)
    with pytest.raises(ControlError, match=r"out_bag=.* would overwrite the emulator file"):
        replay_bag(bag, str(emulator), out_bag=emulator)
    assert emulator.read_bytes() == before


def test_csv_replaces_only_an_empty_file_or_a_csv_of_estimates(bag, tmp_path):
    data = tmp_path / "data.csv"
    data.write_text("a,b\n1,2\n")
    other_bag = write_sensor_bag(tmp_path / "other", *_drive())
    foreign = [data, next(other_bag.glob("*.mcap")), other_bag / "metadata.yaml"]
    before = [p.read_bytes() for p in foreign]
    for path in foreign:
        with pytest.raises(ControlError, match=r"csv=.* exists and is not a CSV of estimates"):
            replay_bag(bag, "A", csv=path)
    assert [p.read_bytes() for p in foreign] == before
    os.mkfifo(tmp_path / "fifo")
    with pytest.raises(ControlError, match=r"csv=.*fifo.* is not a regular file"):
        replay_bag(bag, "A", csv=tmp_path / "fifo")

    empty, table = tmp_path / "empty.csv", tmp_path / "estimates.csv"
    empty.touch()
    table.write_bytes(CSV_HEADER + b"\r\n1,2\r\n")  # an earlier replay's table
    result = replay_bag(bag, "A", csv=empty)
    replay_bag(bag, "A", csv=table)
    for path in (empty, table):
        lines = path.read_text().splitlines()
        assert lines[0].encode() == CSV_HEADER and len(lines) == result.gd_mean.size + 1
    with pytest.raises(ControlError, match=r"path=.*data.csv.* is not a CSV of estimates"):
        result.to_csv(data)
    assert data.read_bytes() == before[0]
    assert result.to_csv(table) == table


def test_a_truncated_bare_mcap_file_is_named_truncated_with_its_size(bag, tmp_path):
    data = next(bag.glob("*.mcap")).read_bytes()
    cut = tmp_path / "cut.mcap"  # no metadata.yaml beside it: a bare MCAP file
    short = "bytes, shorter than an MCAP file's magic bytes, header and footer"
    for n in (0, 5, 10, MIN_MCAP_BYTES - 1):
        cut.write_bytes(data[:n])
        with pytest.raises(BagError, match=rf"{cut} is truncated: {n} {short}"):
            read_recording(cut)
    no_end = "bytes do not end with MCAP's magic bytes"
    for n in (MIN_MCAP_BYTES, len(data) // 2, len(data) - 1):
        cut.write_bytes(data[:n])
        with pytest.raises(BagError, match=rf"{cut} is truncated: its {n} {no_end}"):
            read_recording(cut)
    cut.write_bytes(np.random.default_rng(0).bytes(5000))
    with pytest.raises(BagError, match=rf"{cut} is not an MCAP file"):
        read_recording(cut)
    cut.write_bytes(data)
    assert read_recording(cut).imu.stamp_ns.size == 400  # whole, it reads


def _snapshot(folder):
    """Every path under ``folder`` with the bytes of each file (None for a folder)."""
    return {p: (p.read_bytes() if p.is_file() else None) for p in folder.rglob("*")}


def test_terrain_replay_never_writes_into_the_recording_it_reads(bag, tmp_path, monkeypatch,
                                                                 capsys):  # fmt: skip
    """As replay_bag refuses csv and out_bag there: replaying "." put the default --out, "_bcr",
    inside the bag folder, and an --out in it (or the folder itself) was written into."""
    from control.robot import cli

    mcap = next(bag.glob("*.mcap"))
    before = _snapshot(bag)
    monkeypatch.chdir(bag)
    for argv, default in (
        (["."], True),  # the default --out, "_bcr", in the bag folder
        ([mcap.name], True),  # a file of the bag folder: the folder is read
        ([bag, "--out", bag / "sub"], False),
        ([bag, "--out", bag], False),
        ([mcap, "--out", bag / "sub" / "deeper"], False),
        ([".", "--out", "sub"], False),
    ):
        code = cli.main([str(a) for a in argv] + ["--emulator", "A"])
        err = capsys.readouterr().err
        assert code == 2 and "lies inside the recording" in err, (argv, err)
        assert ("the default --out" in err) == default, err
        assert err.count("\n") == 1
    assert _snapshot(bag) == before
    assert read_recording(bag).imu.stamp_ns.size == 400
    monkeypatch.chdir(tmp_path)  # beside the bag, the default is made and written
    assert cli.main([str(bag.name), "--emulator", "A"]) == 0
    assert (tmp_path / "drive_bcr" / "replay.json").is_file()
