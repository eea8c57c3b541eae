"""The simulation record of a recording (vehicle, noise sd) carries a SHA-256 of its own
(`SIMULATION_SHA256`): a digit changed in the record (another valid vehicle, another noise sd)
is a BagError naming the record, where it read before as another vehicle; a record written
before the checksum (none beside it) reads as before. Found in the pass that reads the
messages (an MCAP file without a summary was read a second time for it)."""

from types import SimpleNamespace

import numpy as np
import pytest

pytest.importorskip("rosbags")
pytest.importorskip("mcap")

from _robot_cases import short_drive, small_result  # noqa: E402

import control  # noqa: E402
import vehicle  # noqa: E402
from control.errors import BagError, ControlWarning  # noqa: E402
from control.robot import bags, read_recording, replay_bag, write_sensor_bag  # noqa: E402
from control.robot import messages as msgs  # noqa: E402
from control.robot.replay import replay_recording  # noqa: E402
from control.robot.storage import LIBRARY  # noqa: E402

MODEL = vehicle.Jackal(mass_kg=21.5)
TOPICS = ("/imu/data", "/odometry/filtered")


def _result(n: int = 240):
    """A small closed-loop result of ``MODEL`` with noise sd 0.25 (no drive needed)."""
    return small_result(n, {"model": MODEL, "noise_std": 0.25})


def _flip(path, old: bytes, new: bytes) -> None:
    """Replace ``old`` by ``new`` (as long) once in the file: a corrupted digit."""
    data = path.read_bytes()
    assert data.count(old) == 1 and len(old) == len(new)
    path.write_bytes(data.replace(old, new))


def _unindexed(path, out):
    """The MCAP file ``path`` without its summary (as a recording cut short and repaired)."""
    import struct

    data, pos = path.read_bytes(), len(storage_magic())
    while True:
        op, length = struct.unpack_from("<BQ", data, pos)
        pos += 9 + length
        if op == 0x0F:  # DataEnd
            break
    out.write_bytes(data[:pos] + struct.pack("<BQQQI", 0x02, 20, 0, 0, 0) + storage_magic())
    return out


def storage_magic() -> bytes:
    from control.robot.storage import MAGIC

    return MAGIC


@pytest.mark.parametrize("summary", [True, False])
def test_a_changed_digit_in_an_mcap_files_record_is_a_bag_error(tmp_path, summary):
    path = control.record_run(_result(), tmp_path / "run.mcap")
    if not summary:
        path = _unindexed(path, tmp_path / "cut.mcap")
    rec = read_recording(path)
    assert rec.vehicle == MODEL and rec.noise_std == 0.25
    for old, new in ((b'"mass_kg": 21.5', b'"mass_kg": 21.6'), (b"0.25", b"0.26")):
        _flip(path, old, new)
        with pytest.raises(BagError, match="'terrain_gpmsa.simulation' metadata record does "
                                           "not match its SHA-256"):  # fmt: skip
            read_recording(path)
        _flip(path, new, old)
    assert read_recording(path).vehicle == MODEL


def test_a_changed_digit_in_a_bags_metadata_is_a_bag_error(tmp_path):
    bag = write_sensor_bag(tmp_path / "bag", *short_drive(), model=MODEL, noise_std=0.25,
                           storage="sqlite3")  # fmt: skip
    assert read_recording(bag).vehicle == MODEL
    meta = bag / "metadata.yaml"
    for old, new in ((b" 21.5,", b" 21.6,"), (b"'0.25'", b"'0.35'")):
        _flip(meta, old, new)
        with pytest.raises(BagError, match=r"metadata.yaml is damaged: its simulation record "
                                           r"\(custom_data .*\) does not match"):  # fmt: skip
            read_recording(bag)
        _flip(meta, new, old)
    digest = bags.simulation_checksum(bags.simulation_record(MODEL, 0.25)).encode()
    _flip(meta, digest, b"x" + digest[1:])
    with pytest.raises(BagError, match="simulation_sha256' is not a SHA-256"):
        read_recording(bag)


def test_a_record_written_before_the_checksum_reads_as_before(tmp_path):
    from mcap.writer import Writer
    from ruamel.yaml import YAML

    from control.robot.bags import SIMULATION_KEYS, merge_in_time, sensor_messages

    record = bags.simulation_record(MODEL, 0.25)
    bag = write_sensor_bag(tmp_path / "bag", *short_drive(), model=MODEL, noise_std=0.25)
    yaml = YAML(typ="safe")
    meta = yaml.load((bag / "metadata.yaml").read_text())
    del meta["rosbag2_bagfile_information"]["custom_data"][bags.SIMULATION_SHA256]
    with (bag / "metadata.yaml").open("w") as f:
        yaml.dump(meta, f)
    path = tmp_path / "old.mcap"  # as record_run wrote it before
    t_imu, imu, t_odom, odom = sensor_messages(*short_drive())
    store = msgs.typestore()
    with open(path, "wb") as f:
        writer = Writer(f)
        writer.start(profile="ros2", library=LIBRARY)
        writer.add_metadata(bags.SIMULATION_RECORD, record)
        channels = []
        for topic, msgtype in zip(TOPICS, (msgs.IMU_TYPE, msgs.ODOMETRY_TYPE), strict=True):
            definition, _ = store.generate_msgdef(msgtype, ros_version=2)
            schema = writer.register_schema(msgtype, "ros2msg", definition.encode())
            channels.append(writer.register_channel(topic, "cdr", schema))
        for channel, stamp, data in merge_in_time(
            [(channels[0], t_imu, imu), (channels[1], t_odom, odom)]
        ):
            writer.add_message(channel, log_time=stamp, data=data, publish_time=stamp)
        writer.finish()
    assert SIMULATION_KEYS["vehicle"] in (bag / "metadata.yaml").read_text()
    assert bags.SIMULATION_SHA256 not in (bag / "metadata.yaml").read_text()
    for old in (bag, path, _unindexed(path, tmp_path / "old_cut.mcap")):
        rec = read_recording(old)
        assert rec.vehicle == MODEL and rec.noise_std == 0.25


def _warned_here(record) -> None:
    """The ControlWarnings caught point at this file (the user's call), not into control."""
    found = [w for w in record if issubclass(w.category, ControlWarning)]
    assert found and {w.filename for w in found} == {__file__}, [w.filename for w in found]


def test_a_noise_sd_mismatch_warns_at_the_callers_line(emulator_a, likelihood_a, tmp_path):
    """The warning pointed into replay.py (replay_bag's call of replay_recording)."""
    t = np.arange(1200) / 120.0
    bag = write_sensor_bag(tmp_path / "noisy", t, np.zeros(t.size), t, 0.5 * t,
                           np.full(t.size, 0.5), model=vehicle.Jackal(), noise_std=1.0)  # fmt: skip
    with pytest.warns(ControlWarning, match="simulated with noise_std = 1") as record:
        replay_bag(bag, emulator_a, likelihood=likelihood_a)
    _warned_here(record)
    with pytest.warns(ControlWarning, match="simulated with noise_std = 1") as record:
        replay_recording(read_recording(bag), emulator_a, likelihood=likelihood_a)
    _warned_here(record)


def test_check_emulators_warnings_point_at_its_caller(emulator_a):
    """They pointed one frame above the caller (stacklevel=3 from check_emulator itself)."""
    with pytest.warns(ControlWarning, match="noise_std = 0.5") as record:
        control.check_emulator(emulator_a, noise_std=0.5)
    _warned_here(record)
    bare = SimpleNamespace(**{k: getattr(emulator_a, k) for k in ("domain", "t_names")},
                           metadata={})  # fmt: skip
    with pytest.warns(ControlWarning, match=r"no '(vehicle|noise_std)'") as record:
        control.check_emulator(bare, model=vehicle.Jackal(), noise_std=0.0)
    _warned_here(record)
