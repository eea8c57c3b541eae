"""What the replay and ``terrain-replay`` take: wrong arguments and settings are a ControlError
naming them, a failed run leaves no output folder, and the report is strict JSON."""

import json
import os

import numpy as np
import pytest

import gpmsa

pytest.importorskip("rosbags")
pytest.importorskip("mcap")

from control.errors import ControlError  # noqa: E402
from control.robot import (  # noqa: E402
    ReplayResult,
    ReplaySettings,
    cli,
    replay_bag,
    write_sensor_bag,
)


def _drive(n: int = 400):
    """(IMU time s, accel, odometry time s, position, speed) of n samples at 120 Hz, 1 m/s."""
    t = 1.0 + np.arange(n) / 120.0
    accel = np.random.default_rng(1).normal(size=n)
    return t, accel, t, t - 1.0, np.ones(n)


@pytest.fixture(scope="module")
def bag(tmp_path_factory):
    """A short, healthy ROS 2 bag."""
    return write_sensor_bag(tmp_path_factory.mktemp("bags") / "drive", *_drive())


def _run(capsys, *argv) -> tuple[int, str, str]:
    """(exit status, stdout, stderr) of ``terrain-replay argv``."""
    code = cli.main([str(a) for a in argv])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def _no_nan(name: str):
    raise AssertionError(f"{name} in strict JSON")


# --- the report is strict JSON; a recording too short for an estimate says so ---------------------


def test_a_bag_too_short_for_an_estimate_gives_strict_json_and_says_why(tmp_path, capsys):
    t, accel, _, _, _ = _drive()
    one = slice(5, 6)  # one odometry message: its topic has no rate
    short = write_sensor_bag(tmp_path / "one_odom", t, accel, t[one], t[one] - 1.0, [1.0])
    out = tmp_path / "out"
    code, printed, _ = _run(capsys, short, "--emulator", "A", "--out", out)
    assert code == 0  # the docs: a recording too short for an estimate is no error
    assert "no estimate: only 1 IMU sample(s) lie within the odometry's time span" in printed
    assert "fewer than the 42 of one BCR update" in printed
    assert "without a rate" in printed
    text = (out / "replay.json").read_text()
    report = json.loads(text, parse_constant=_no_nan)  # NaN, Infinity: not JSON
    assert report["odometry"]["rate_hz"] is None and report["status_counts"] == {}
    assert report["imu"]["rate_hz"] == pytest.approx(120.0)


def test_the_report_of_a_healthy_bag_is_strict_json_with_numbers(bag, tmp_path, capsys):
    out = tmp_path / "out"
    code, printed, _ = _run(capsys, bag, "--emulator", "A", "--out", out)
    assert code == 0 and "estimates over" in printed
    report = json.loads((out / "replay.json").read_text(), parse_constant=_no_nan)
    assert report["odometry"]["rate_hz"] == pytest.approx(120.0)
    assert sum(report["status_counts"].values()) == 400 // 42


# --- no output folder is left by a failed run -----------------------------------------------------


def test_a_failed_replay_leaves_no_output_folder(bag, tmp_path, capsys):
    (tmp_path / "notabag.mcap").write_text("hello")
    for case, argv in (
        ("missing", [tmp_path / "none"]),
        ("not a bag", [tmp_path / "notabag.mcap"]),
        ("no topic", [bag, "--imu-topic", "/imu/raw"]),
    ):
        out = tmp_path / "made" / "out"
        code, _, err = _run(capsys, *argv, "--emulator", "A", "--out", out)
        assert code == 2 and err.startswith("terrain-replay: error: "), case
        assert not (tmp_path / "made").exists(), case
    mine = tmp_path / "mine"  # a folder the user had stays, with what it held
    mine.mkdir()
    (mine / "notes.txt").write_text("kept")
    code, _, _ = _run(capsys, tmp_path / "none", "--emulator", "A", "--out", mine)
    assert code == 2 and [p.name for p in mine.iterdir()] == ["notes.txt"]


def test_a_failed_write_removes_the_folder_it_made_only(bag, tmp_path, capsys, monkeypatch):
    def full_disk(self, path, storage=None):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(ReplayResult, "write_bag", full_disk)
    out = tmp_path / "made" / "out"
    code, _, err = _run(capsys, bag, "--emulator", "A", "--out", out)
    assert code == 2 and "No space left on device" in err
    assert list(tmp_path.iterdir()) == []
    mine = tmp_path / "mine"  # a folder the user had keeps what it held, and nothing else
    mine.mkdir()
    (mine / "notes.txt").write_text("kept")
    code, _, _ = _run(capsys, bag, "--emulator", "A", "--out", mine)
    assert code == 2 and [p.name for p in mine.iterdir()] == ["notes.txt"]


@pytest.mark.parametrize("name", ["estimates.csv", "estimates", "replay.json"])
def test_no_output_of_an_earlier_run_is_overwritten(bag, tmp_path, capsys, name):
    out = tmp_path / "out"
    out.mkdir()
    (out / name).write_text("an earlier run's")
    code, _, err = _run(capsys, bag, "--emulator", "A", "--out", out)
    assert code == 2 and f"{out / name} exists already: choose another --out" in err
    assert [p.name for p in out.iterdir()] == [name]
    assert (out / name).read_text() == "an earlier run's"


# --- messages about --out and --emulator ----------------------------------------------------------


def test_an_out_path_that_is_a_file_is_named_as_such(bag, tmp_path, capsys):
    file = tmp_path / "file.txt"
    file.write_text("")
    for out, there in ((os.devnull, os.devnull), (file, file), (file / "sub", file)):
        code, _, err = _run(capsys, bag, "--emulator", "A", "--out", out)
        assert code == 2 and "exists and is not a folder" in err, err
        assert repr(str(there)) in err and "Errno" not in err


def test_an_empty_path_is_refused_not_read_as_the_current_folder(bag, tmp_path, capsys):
    for argv, name in (
        (["", "--emulator", "A"], "BAG"),
        ([bag, "--emulator", "A", "--out", ""], "--out"),
        ([bag, "--emulator", " "], "--emulator"),
    ):
        code, _, err = _run(capsys, *argv)
        assert code == 2 and f"error: {name} is an empty path" in err, err
        assert err.count("\n") == 1


def test_an_emulator_path_that_is_no_file_is_named_as_such(bag, tmp_path, capsys):
    for emulator, what in (
        (os.devnull, "is not a regular file, not an emulator file"),
        (tmp_path, "is a folder, not an emulator file"),
        (tmp_path / "none.gpmsa", "no such file"),
    ):
        code, _, err = _run(capsys, bag, "--emulator", emulator, "--out", tmp_path / "o")
        assert code == 2 and f"--emulator {str(emulator)!r}" in err and what in err, err
        assert not (tmp_path / "o").exists()


# --- settings name the field that is wrong --------------------------------------------------------


@pytest.mark.parametrize(
    "field, value, message",
    [
        ("highpass_hz", "1", r"highpass_hz must be a real number, got '1' \(str\)"),
        ("highpass_hz", 1e-9, r"highpass_hz must be >= 0.0001 Hz .* got 1e-09"),  # was LinAlgError
        ("max_odometry_gap_s", "1", "max_odometry_gap_s must be a real number"),
        ("rate_tolerance", "0.1", "rate_tolerance must be a real number"),
        ("rate_tolerance", None, "rate_tolerance must be a real number"),
        ("imu_sign", True, r"imu_sign must be a real number, got True \(bool\)"),
        ("imu_sign", "1", "imu_sign must be a real number"),
        ("imu_sign", 0.5, r"imu_sign must be \+1 or -1, got 0.5"),
        ("imu_topic", 3, r"imu_topic must be a .*str, got 3 \(int\)"),
        ("imu_axis", None, r"imu_axis must be a .*str, got None"),
    ],
)
def test_replay_settings_refuse_a_value_of_the_wrong_type_naming_the_field(field, value, message):
    with pytest.raises(ControlError, match=message):
        ReplaySettings(**{field: value})


def test_one_topic_cannot_be_both_the_imu_and_the_odometry(bag, emulator_a, tmp_path):
    """A topic holds one message type: the writer refuses to put both on one, and the reader
    names it (a bag with two types on a topic had crashed the topic check)."""
    from control.robot.bags import write_sensor_bag

    t = np.arange(10) / 120.0
    with pytest.raises(ControlError, match="imu_topic and odom_topic must differ, both are '/x'"):
        write_sensor_bag(tmp_path / "same", t, np.zeros(10), t, t, np.ones(10), imu_topic="/x",
                         odom_topic="/x")  # fmt: skip
    assert not (tmp_path / "same").exists()
    with pytest.raises(ControlError, match="imu_topic and odom_topic must differ"):
        replay_bag(bag, emulator_a, imu_topic="/imu/data", odom_topic="/imu/data")


def test_replay_bag_names_an_override_that_is_no_setting(bag, emulator_a):
    with pytest.raises(ControlError, match="'imu_rate': no ReplaySettings field .* imu_topic"):
        replay_bag(bag, emulator_a, imu_rate=200)
    with pytest.raises(ControlError, match="settings must be a ReplaySettings, got dict"):
        replay_bag(bag, emulator_a, {"imu_topic": "/imu"})


def test_replay_settings_take_either_sign_as_int_or_float():
    assert [ReplaySettings(imu_sign=s).imu_sign for s in (1, -1, 1.0, -1.0)] == [1, -1, 1, -1]


# --- the bag and emulator arguments of replay_bag -------------------------------------------------


@pytest.mark.parametrize("value", [None, 3, "", b"drive"])
def test_replay_bag_refuses_a_bag_that_is_not_a_path(value, emulator_a):
    with pytest.raises(ControlError, match=r"bag must be the path \(a str or os.PathLike\)"):
        replay_bag(value, emulator_a)


@pytest.mark.parametrize("value", [None, 3, ["A"], "C"])
def test_replay_bag_refuses_an_emulator_of_another_kind(value, bag):
    match = "no such file" if value == "C" else "emulator must be a gpmsa.Emulator, the path"
    with pytest.raises(ControlError, match=match):
        replay_bag(bag, value)


def test_replay_bag_takes_the_emulators_forms_the_command_takes(bag, emulator_a, likelihood_a):
    want = replay_bag(bag, emulator_a, likelihood=likelihood_a)
    from control.shipped import shipped_emulator_path

    for form in ("A", shipped_emulator_path("A"), str(shipped_emulator_path("A"))):
        got = replay_bag(bag, form, likelihood=likelihood_a)
        assert got.status.tolist() == want.status.tolist()
        assert np.array_equal(got.gd_mean, want.gd_mean, equal_nan=True)


def test_a_damaged_emulator_file_is_a_control_error_chaining_gpmsas(bag, tmp_path):
    damaged = tmp_path / "jackal.gpmsa"
    damaged.write_bytes(np.random.default_rng(0).bytes(3000))
    with pytest.raises(ControlError, match=f"emulator {str(damaged)!r}: ") as info:
        replay_bag(bag, damaged)
    assert isinstance(info.value.__cause__, gpmsa.EmulatorFileError)
    with pytest.raises(ControlError, match="emulator 'nofile.gpmsa': no such file"):
        replay_bag(bag, "nofile.gpmsa")


# --- from a probe of the robot I/O: outputs, clocks, stamps, odd files ---------------------------


def test_replay_bag_checks_its_outputs_before_the_replay(bag, tmp_path):
    mcap = next(bag.glob("*.mcap"))
    before = mcap.read_bytes()
    for kwargs in ({"csv": mcap}, {"csv": bag}, {"out_bag": bag / "estimates"}):
        with pytest.raises(ControlError, match="would overwrite the recording"):
            replay_bag(bag, "A", **kwargs)
    assert mcap.read_bytes() == before
    (tmp_path / "taken").mkdir()
    csv = tmp_path / "x.csv"
    with pytest.raises(ControlError, match="out_bag=.*taken.* exists already"):
        replay_bag(bag, "A", csv=csv, out_bag=tmp_path / "taken")
    assert not csv.exists()  # refused before anything was written
    os.symlink(tmp_path / "nowhere", tmp_path / "dangling")
    with pytest.raises(ControlError, match="out_bag=.*dangling.* exists already"):
        replay_bag(bag, "A", out_bag=tmp_path / "dangling")
    with pytest.raises(ControlError, match="csv and out_bag are the same path"):
        replay_bag(bag, "A", csv=tmp_path / "same", out_bag=tmp_path / "same")
    with pytest.raises(ControlError, match="csv=.*taken.* is a folder"):
        replay_bag(bag, "A", csv=tmp_path / "taken")
    result = replay_bag(bag, "A", csv=csv, out_bag=tmp_path / "fresh")
    assert csv.is_file() and (tmp_path / "fresh" / "metadata.yaml").is_file()
    assert len(csv.read_text().splitlines()) == result.gd_mean.size + 1


def test_a_topic_without_header_stamps_puts_both_topics_on_the_receive_clock(tmp_path):
    """The fall-back to receive times was decided per topic: an IMU on receive times and
    odometry on header stamps 0.5 s apart paired every sample with the odometry of 0.5 s
    before."""
    t, accel, _, pos, spd = _drive()
    log = np.concatenate([t + 0.5, t + 0.5])
    path = write_sensor_bag(tmp_path / "zero", 0.0 * t, accel, t - 1.0 + 1.0, pos, spd,
                            log_time=log)  # fmt: skip
    result = replay_bag(path, "A")
    assert result.imu.time_base == result.odometry.time_base == "log"
    assert "receive times used for both topics" in result.imu.note
    assert result.sample_position[0] == pytest.approx(0.0, abs=1e-9)  # 0.5 before
    np.testing.assert_allclose(result.sample_position, result.sample_time, atol=1e-6)


def test_written_stamps_are_checked_and_offset(tmp_path):
    t, accel, _, pos, spd = _drive()
    for value, name in ((np.full(800, np.nan), "log_time"), (np.full(800, -1.0), "log_time"),
                        (np.full(800, 1e12), "log_time")):  # fmt: skip
        with pytest.raises(ControlError, match=rf"{name} holds .* allowed finite times"):
            write_sensor_bag(tmp_path / "b", t, accel, t, pos, spd, log_time=value)
    with pytest.raises(ControlError, match=r"imu_time holds nan s"):
        write_sensor_bag(tmp_path / "b", np.where(t > 2, np.nan, t), accel, t, pos, spd)
    with pytest.raises(ControlError, match=r"imu_time holds 300000000[01].0 s"):
        write_sensor_bag(tmp_path / "b", t + 3e9, accel, t, pos, spd)
    text = r"accel must be an array of real numbers, got dtype <U1"
    with pytest.raises(ControlError, match=text):
        write_sensor_bag(tmp_path / "b", t, ["a"] * t.size, t, pos, spd)
    assert not (tmp_path / "b").exists()


def test_a_recording_that_is_a_fifo_is_refused_not_waited_on(bag, tmp_path):
    fifo = tmp_path / "f.mcap"
    os.mkfifo(fifo)
    with pytest.raises(Exception, match="not a regular file"):
        replay_bag(fifo, "A")
    folder = tmp_path / "bag"
    folder.mkdir()
    for item in bag.iterdir():
        if item.suffix == ".mcap":
            os.mkfifo(folder / item.name)
        else:
            (folder / item.name).write_bytes(item.read_bytes())
    with pytest.raises(Exception, match="is not a regular file"):
        replay_bag(folder, "A")


def test_terrain_replay_refuses_a_dangling_link_among_its_outputs(bag, tmp_path, capsys):
    out = tmp_path / "out"
    out.mkdir()
    elsewhere = tmp_path / "elsewhere.json"
    os.symlink(elsewhere, out / "replay.json")
    code, _, err = _run(capsys, bag, "--emulator", "A", "--out", out)
    assert code == 2 and "replay.json exists already" in err
    assert os.path.islink(out / "replay.json") and not elsewhere.exists()


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_a_topic_with_two_message_types_is_named_as_such(tmp_path, storage):
    from control.robot import messages as msgs
    from control.robot.bags import merge_in_time, open_bag_writer, sensor_messages

    t, accel, _, pos, spd = _drive()
    t_imu, imu, t_odom, odom = sensor_messages(t, accel, t, pos, spd)
    store = msgs.typestore()
    field = store.types["sensor_msgs/msg/MagneticField"]
    header, vec = store.types["std_msgs/msg/Header"], store.types["geometry_msgs/msg/Vector3"]
    stamp = store.types["builtin_interfaces/msg/Time"](sec=1, nanosec=0)
    mag = field(header=header(stamp=stamp, frame_id="imu"), magnetic_field=vec(x=0.0, y=0.0, z=1.0),
                magnetic_field_covariance=np.zeros(9))  # fmt: skip
    path = tmp_path / f"two_{storage}"
    with open_bag_writer(path, storage) as writer:
        c_imu = writer.add_connection("/imu/data", msgs.IMU_TYPE, typestore=store)
        c_mag = writer.add_connection("/imu/data", "sensor_msgs/msg/MagneticField", typestore=store)
        c_odom = writer.add_connection("/odometry/filtered", msgs.ODOMETRY_TYPE, typestore=store)
        data = [bytes(store.serialize_cdr(mag, "sensor_msgs/msg/MagneticField"))]
        streams = [(c_imu, t_imu, imu), (c_mag, t_imu[:1], data), (c_odom, t_odom, odom)]
        for conn, ns, raw in merge_in_time(streams):
            writer.write(conn, ns, raw)
    with pytest.raises(Exception, match=r"'/imu/data' in .* holds several message types"):
        replay_bag(path, "A")


def test_stamps_a_nanosecond_apart_are_refused_before_a_huge_lowpass(tmp_path):
    """400 IMU stamps 1 ns apart asked 'lowpass' for a filter of ~1.7e8 taps: 36 s and 8 GB
    before a BagError."""
    from control.errors import BagError

    t, accel, _, pos, spd = _drive()
    path = write_sensor_bag(tmp_path / "ns", 1.0 + np.arange(t.size) * 1e-9, accel, t, pos, spd)
    with pytest.raises(BagError, match=r"needs a filter of \d+ taps, above MAX_LOWPASS_TAPS"):
        replay_bag(path, "A", resample="lowpass")


def test_a_recorded_run_named_without_the_mcap_suffix_replays(bag, tmp_path):
    """An MCAP file is known by its magic bytes, whatever its name (record_run writes any)."""
    from control.errors import BagError
    from control.robot.bags import read_recording

    for name in ("run", "run.MCAP"):
        (tmp_path / name).write_bytes(_mcap_file(bag).read_bytes())
        rec = read_recording(tmp_path / name)
        assert rec.kind == "mcap" and rec.imu.stamp_ns.size == 400
    (tmp_path / "notes.txt").write_text("not a recording")
    with pytest.raises(BagError, match="not a recording this reader knows"):
        read_recording(tmp_path / "notes.txt")


def _mcap_file(folder):
    (path,) = folder.glob("*.mcap")
    return path


@pytest.mark.parametrize("value", [None, 3, ""])
def test_writing_a_bag_to_a_path_that_is_no_path_is_a_control_error(value, bag, emulator_a):
    with pytest.raises(ControlError, match="path must be the path"):
        write_sensor_bag(value, *_drive())
    result = replay_bag(bag, emulator_a)
    with pytest.raises(ControlError, match="path must be the path"):
        result.write_bag(value)


@pytest.mark.parametrize(
    "topic, message",
    [(3, "must be a str"), ("", "must start with '/'"), ("imu", "must start with '/'")],
)
def test_written_topics_are_checked_as_the_replay_reads_them(topic, message, tmp_path):
    for name in ("imu_topic", "odom_topic"):
        with pytest.raises(ControlError, match=rf"{name} {message}"):
            write_sensor_bag(tmp_path / "b", *_drive(), **{name: topic})
    assert not (tmp_path / "b").exists()


@pytest.mark.parametrize("topic", [None, 3, ["/imu/data"]])
def test_reading_a_topic_that_is_no_str_is_a_control_error(topic, bag):
    from control.robot.bags import read_recording

    with pytest.raises(ControlError, match="imu_topic must be a str"):
        read_recording(bag, imu_topic=topic)


def test_imu_stamp_errors_name_the_imu_topic(tmp_path):
    """As docs/robot.md says of the BagErrors about a topic: "fewer than two distinct time
    stamps" said "the IMU topic" without its name, as did an IMU too slow and stamps too close
    for "lowpass"."""
    from control.errors import BagError

    t, accel, _, pos, spd = _drive()
    cases = (
        (np.full(t.size, 1.5), {}, "has fewer than two distinct time stamps"),
        (1.0 + np.arange(t.size) / 60.0, {}, r"runs at 60 Hz, slower than the emulator's"),
        (1.0 + np.arange(t.size) * 1e-9, {"resample": "lowpass"}, r"needs a filter of \d+ taps"),
    )
    for k, (stamps, settings, message) in enumerate(cases):
        odom = np.linspace(stamps[0], stamps[-1] + 1.0, t.size)
        path = write_sensor_bag(tmp_path / f"b{k}", stamps, accel, odom, pos, spd,
                                imu_topic="/my/imu")  # fmt: skip
        with pytest.raises(BagError, match=rf"IMU topic '/my/imu'.*{message}"):
            replay_bag(path, "A", imu_topic="/my/imu", **settings)


def test_ctrl_c_during_a_replay_is_one_line_and_leaves_no_output(bag, tmp_path, capsys,
                                                                 monkeypatch):  # fmt: skip
    """Ctrl-C printed a traceback; it is one line, exit status 130, no output folder left."""

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "replay_bag", interrupted)
    out = tmp_path / "made" / "out"
    code, _, err = _run(capsys, bag, "--emulator", "A", "--out", out)
    assert (code, err) == (130, "terrain-replay: interrupted (Ctrl-C)\n")
    assert not (tmp_path / "made").exists()
