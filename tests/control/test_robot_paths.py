"""Paths and writers of robot recordings: what a user recorded is never replaced by
`record_run` (an MCAP file another program wrote, a bag's file), a sqlite3 bag is read and
written whatever characters its path holds (or refused before anything is written), and a
channel whose schema the file lacks is a `BagError`."""

import os
import shutil

import pytest

pytest.importorskip("rosbags")
pytest.importorskip("mcap")

from _robot_cases import short_drive, small_result  # noqa: E402

import control  # noqa: E402
from control.errors import BagError, ControlError  # noqa: E402
from control.robot import messages as msgs  # noqa: E402
from control.robot import read_recording, replay_bag, write_sensor_bag  # noqa: E402
from control.robot.bags import merge_in_time, sensor_messages  # noqa: E402

TOPICS = ("/imu/data", "/odometry/filtered")


def _write_mcap(path, library: str = "foxglove", bad_schema: bool = False, chunked=True):
    """An MCAP file of ROS 2 IMU and odometry messages written by ``library``; ``bad_schema``:
    the odometry channel names a schema the file does not hold."""
    from mcap.writer import Writer

    t_imu, imu, t_odom, odom = sensor_messages(*short_drive())
    store = msgs.typestore()
    with open(path, "wb") as f:
        writer = Writer(f, use_chunking=chunked)
        writer.start(profile="ros2", library=library)
        channels = []
        for topic, msgtype in zip(TOPICS, (msgs.IMU_TYPE, msgs.ODOMETRY_TYPE), strict=True):
            definition, _ = store.generate_msgdef(msgtype, ros_version=2)
            schema = writer.register_schema(msgtype, "ros2msg", definition.encode())
            odd = bad_schema and topic == TOPICS[1]
            channels.append(writer.register_channel(topic, "cdr", 99 if odd else schema))
        for channel, stamp, data in merge_in_time(
            [(channels[0], t_imu, imu), (channels[1], t_odom, odom)]
        ):
            writer.add_message(channel, log_time=stamp, data=data, publish_time=stamp)
        writer.finish()
    return path


def test_a_recording_never_replaces_an_mcap_file_another_program_wrote(tmp_path):
    """record_run replaced any MCAP file: a robot's recording (a bag's file, Foxglove's)."""
    result = small_result()
    bag = write_sensor_bag(tmp_path / "bag", *short_drive())
    bag_file = next(bag.glob("*.mcap"))
    foreign = _write_mcap(tmp_path / "field.mcap")
    header_lost = tmp_path / "header_lost.mcap"
    data = foreign.read_bytes()
    header_lost.write_bytes(data[:8] + b"\x07" + data[9:])  # not a Header record
    for target, why in ((bag_file, "written by 'rosbags-"), (foreign, "written by 'foxglove'"),
                        (header_lost, "does not say which program wrote it")):  # fmt: skip
        before = target.read_bytes()
        with pytest.raises(ControlError, match=why):
            control.record_run(result, target)
        assert target.read_bytes() == before
    assert read_recording(bag).imu.stamp_ns.size == 60  # the bag as recorded
    ours = tmp_path / "run.mcap"
    control.record_run(result, ours)
    stub = tmp_path / "stub.mcap"
    stub.write_bytes(ours.read_bytes()[:20])  # cut inside its header: holds nothing
    for target in (ours, stub):  # an earlier recording of record_run is replaced
        assert control.record_run(result, target) == target
        assert target.read_bytes() == ours.read_bytes()


def test_record_run_names_a_folder_it_cannot_make(tmp_path):
    (tmp_path / "notes").write_text("x")
    with pytest.raises(ControlError, match="path=.*cannot make its folder"):
        control.record_run(small_result(), tmp_path / "notes" / "runs" / "run.mcap")


@pytest.mark.parametrize("chunked", [True, False])
def test_a_channel_whose_schema_the_file_lacks_is_a_bag_error(chunked, tmp_path):
    path = _write_mcap(tmp_path / "odd.mcap", bad_schema=True, chunked=chunked)
    with pytest.raises(BagError, match="odometry.*holds messages without a schema"):
        read_recording(path)


@pytest.mark.parametrize("name", ["trial#3", "a?b", "p%41q"])
def test_a_sqlite3_bag_reads_whatever_its_folder_is_named(name, tmp_path):
    """The reader opened the database as a URI: '#' or '?' cut the path (and made an empty
    database there), '%41' read another file."""
    bag = write_sensor_bag(tmp_path / "bag", *short_drive(), storage="sqlite3")
    shutil.copytree(bag, tmp_path / name)
    before = sorted(os.listdir(tmp_path))
    assert read_recording(tmp_path / name).imu.stamp_ns.size == 60
    assert sorted(os.listdir(tmp_path)) == before  # reading made no file


@pytest.mark.parametrize("name", ["trial#3", "a?b", "p%41q"])
def test_a_sqlite3_bag_is_not_written_where_its_database_would_be_lost(name, tmp_path):
    """rosbags' sqlite3 writer put the database beside the folder (or failed with sqlite3's
    bare error) and the bag was written without it."""
    with pytest.raises(ControlError, match="sqlite3 bag cannot be written to a path holding"):
        write_sensor_bag(tmp_path / name, *short_drive(), storage="sqlite3")
    assert os.listdir(tmp_path) == []
    assert read_recording(write_sensor_bag(tmp_path / name, *short_drive())).imu.stamp_ns.size == 60
    with pytest.raises(ControlError, match="out_bag=.*sqlite3 bag cannot be written"):
        replay_bag(tmp_path / name, "A", storage="sqlite3", out_bag=tmp_path / f"out{name}")


def test_a_bag_is_not_written_onto_a_link_to_nowhere(tmp_path):
    os.symlink(tmp_path / "nowhere", tmp_path / "link")
    with pytest.raises(ControlError, match="exists already"):
        write_sensor_bag(tmp_path / "link", *short_drive())


def test_a_path_that_starts_with_a_tilde_is_the_home_folder(tmp_path, monkeypatch):
    """record_run("~/runs/run.mcap") made a folder literally named "~" in the working
    directory; a leading ~ is the home folder, as the shell reads it (write_sensor_bag too)."""
    home, work = tmp_path / "home", tmp_path / "work"
    home.mkdir(), work.mkdir()
    monkeypatch.setenv("HOME", str(home))
    monkeypatch.chdir(work)
    assert control.record_run(small_result(), "~/runs/run.mcap") == home / "runs" / "run.mcap"
    assert write_sensor_bag("~/bags/b", *short_drive()) == home / "bags" / "b"
    assert not (work / "~").exists() and (home / "runs" / "run.mcap").is_file()


def test_a_name_that_only_starts_with_a_tilde_is_a_file_of_that_name(tmp_path, monkeypatch):
    """record_run("~x.mcap") raised RuntimeError (Path.expanduser reads "~x" as user x's home):
    only "~" and "~/..." are the home folder."""
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    monkeypatch.chdir(tmp_path)
    written = control.record_run(small_result(), "~nosuchuser.mcap")
    assert written.resolve() == tmp_path / "~nosuchuser.mcap"
    assert (tmp_path / "~nosuchuser.mcap").is_file()
