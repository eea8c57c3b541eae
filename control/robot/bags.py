"""Reading and writing robot recordings: ROS 2 bags (MCAP or sqlite3), ROS 1 bags, MCAP files.

What is read, as arrays: the IMU's header stamps, receive (log) times and linear accelerations,
and the odometry's stamps, receive times, positions and linear velocities. Any of these opens:

- a ROS 2 bag folder (``metadata.yaml`` beside ``*.mcap`` or ``*.db3`` files; ROS 2's default
  storage is MCAP, older bags are sqlite3), read with rosbags;
- a ``*.db3`` or ``*.mcap`` file inside such a folder (the folder is read);
- a ROS 1 ``*.bag`` file (rosbags);
- a bare ``*.mcap`` file with ROS 2 (CDR) messages, e.g. one `control.record_run` wrote or
  Foxglove recorded (the ``mcap`` package); a file of another name is one too where its
  first bytes are MCAP's magic (`control.record_run` writes to any name).

A recording this package wrote from a simulation also records the simulated vehicle and noise
sd (`SIMULATION_KEYS`, `SIMULATION_RECORD`), read into `Recording.vehicle` and ``noise_std``;
any other recording (a robot's) reads with None for both.

rosbags and mcap are the ``robot`` extra; they are imported when a function needs them.
A recording whose bytes are damaged (truncated, corrupted) raises `BagError` naming the file
and what is wrong, whichever library found it.
"""

from __future__ import annotations

import hashlib
import importlib
import json
import os
import re
import shutil
import struct
import sys
import tempfile
import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path, PurePath

import numpy as np

import vehicle
from control.errors import BagError, ControlError
from control.faults import FaultInjector, SensorFault
from control.feature import STANDARD_GRAVITY
from control.robot import messages as msgs
from control.robot import storage as storage_mod
from control.robot.extra import require
from control.validation import check_lookup, float_array, is_choice, is_integer, path_argument
from gpmsa.io.atomic import flush_folder
from roadgen.checks import home_path
from vehicle.models import Model

STORAGES = ("mcap", "sqlite3")
DIGEST_KEY = "terrain_gpmsa.messages_sha256"
"""The ``custom_data`` key of a ROS 2 bag this package writes (`open_bag_writer`): JSON
{topic: `messages_digest` of its messages}, which `read_recording` checks, so that a damaged
message is refused in a sqlite3 bag too (an MCAP bag's chunks carry CRCs as well)."""
SIMULATION_KEYS = {"vehicle": "terrain_gpmsa.vehicle", "noise_std": "terrain_gpmsa.noise_std"}
"""The ``custom_data`` keys of a ROS 2 bag this package writes from a simulation
(`write_sensor_bag` given ``model=`` / ``noise_std=``): the simulated vehicle's
``model.describe()`` as JSON, the accelerometer noise sd (m/s^2) as a JSON number; which
`read_recording` reads into `Recording.vehicle` and `Recording.noise_std`."""
SIMULATION_RECORD = "terrain_gpmsa.simulation"
"""The name of the MCAP Metadata record of a run `control.record_run` writes, holding the same
two fields as `SIMULATION_KEYS` under the keys "vehicle" and "noise_std"."""
SIMULATION_SHA256 = "terrain_gpmsa.simulation_sha256"
"""The checksum written beside that record, the `simulation_checksum` of its fields: a ROS 2
bag's ``custom_data`` key, and the name of an MCAP Metadata record with the one field "sha256"
(a record of its own: readers before it refuse a field they do not know in `SIMULATION_RECORD`).
`read_recording` refuses a record that does not match it; a record without it (written before)
reads unchecked."""
SIMULATION_NAMES = (SIMULATION_RECORD, SIMULATION_SHA256)
MAX_SIMULATION_CHARS = 4096
"""Longest text of a field of that record (a Jackal's description is ~300 characters)."""
_METADATA_BYTES = 2 * len(SIMULATION_KEYS) * (MAX_SIMULATION_CHARS + 64)
"""Longest indexed Metadata record read for that record or its checksum, bytes."""
URI_PARTS = re.compile(r"[?#]|%[0-9A-Fa-f]{2}")
"""What rosbags' sqlite3 writer misreads in a path (it opens ``file:PATH`` as a URI): a query,
a fragment, a percent-encoded byte."""


@dataclass(frozen=True, eq=False)
class ImuMessages:
    """The messages of an IMU topic, in the recording's order.

    Attributes:
        topic: the topic name.
        log_ns: (n,) receive times, int ns.
        stamp_ns: (n,) header stamps, int ns.
        accel: (n, 3) ``linear_acceleration`` (x, y, z), m/s^2, in the IMU's frame.
        accel_unknown: (n,) bool: the messages that mark their linear acceleration unknown
            (``linear_acceleration_covariance[0] == -1``, the Imu message's "no estimate";
            their ``accel`` is whatever the driver left there); None: none does.
    """

    topic: str
    log_ns: np.ndarray
    stamp_ns: np.ndarray
    accel: np.ndarray
    accel_unknown: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class OdometryMessages:
    """The messages of an odometry topic, in the recording's order.

    Attributes:
        topic: the topic name.
        log_ns, stamp_ns: (n,) receive times and header stamps, int ns.
        position: (n, 3) ``pose.pose.position``, m, in the odometry frame.
        velocity: (n, 3) ``twist.twist.linear``, m/s, in the child (body) frame.
    """

    topic: str
    log_ns: np.ndarray
    stamp_ns: np.ndarray
    position: np.ndarray
    velocity: np.ndarray


@dataclass(frozen=True, eq=False)
class Recording:
    """What `read_recording` found.

    Attributes:
        path: the recording.
        kind: "rosbag2" (with ``storage``), "ros1" or "mcap".
        storage: "mcap" or "sqlite3" for a ROS 2 bag folder; "" otherwise.
        topics: every topic of the recording and its message type.
        imu, odometry: the messages of the two topics asked for.
        read_s: wall-clock time of the reading, s.
        vehicle: the simulated vehicle model a recording this package wrote from a simulation
            records (`SIMULATION_KEYS`, `SIMULATION_RECORD`); None for any other (a robot's).
        noise_std: the simulated accelerometer noise sd such a recording records, m/s^2; None
            where none is recorded.
    """

    path: Path
    kind: str
    storage: str
    topics: dict[str, str]
    imu: ImuMessages
    odometry: OdometryMessages
    read_s: float
    vehicle: Model | None = None
    noise_std: float | None = None


def _normalise(msgtype: str) -> str:
    """``pkg/msg/Name`` for ``pkg/Name`` (ROS 1 and some MCAP writers leave out ``msg``)."""
    parts = msgtype.split("/")
    return f"{parts[0]}/msg/{parts[1]}" if len(parts) == 2 else msgtype


def _topic_error(path: Path, topic: str, role: str, topics: dict[str, str], option: str) -> str:
    listing = ", ".join(f"{t} ({ty})" for t, ty in sorted(topics.items())) or "none"
    return (
        f"the {role} topic {topic!r} is not in {path}; its topics: {listing} "
        f"(choose another with {option})"
    )


def _check_distinct(imu_topic: str, odom_topic: str, error: type[Exception]) -> None:
    """``error`` unless the IMU and odometry topics differ (a topic holds one message type)."""
    if imu_topic == odom_topic:
        raise error(f"imu_topic and odom_topic must differ, both are {imu_topic!r}")


def _check_topic_names(imu_topic: str, odom_topic: str, *, written: bool = False) -> None:
    """`ControlError` for a topic name that is not a str, or (``written``) does not start with
    "/" (a recorder's names do, and `ReplaySettings` refuses others)."""
    for name, topic in (("imu_topic", imu_topic), ("odom_topic", odom_topic)):
        if not isinstance(topic, str):
            raise ControlError(f"{name} must be a str, got {topic!r:.60} ({type(topic).__name__})")
        if written and not topic.startswith("/"):
            raise ControlError(f"{name} must start with '/', got {topic!r}")


def _check_topics(path: Path, topics: dict[str, str], imu_topic: str, odom_topic: str) -> None:
    _check_distinct(imu_topic, odom_topic, BagError)
    for topic, role, want, option in (
        (imu_topic, "IMU", msgs.IMU_TYPE, "imu_topic / --imu-topic"),
        (odom_topic, "odometry", msgs.ODOMETRY_TYPE, "odom_topic / --odom-topic"),
    ):
        if topic not in topics:
            raise BagError(_topic_error(path, topic, role, topics, option))
        if topics[topic] is None:
            raise BagError(
                f"the {role} topic {topic!r} in {path} holds several message types; the replay "
                f"reads one, {want}, per topic"
            )
        if _normalise(topics[topic]) != want:
            held = topics[topic] or "messages without a schema (no message type)"
            raise BagError(f"the {role} topic {topic!r} in {path} holds {held}, expected {want}")


def in_bag_folder(path: Path) -> bool:
    """Whether ``path`` is a ``*.mcap`` or ``*.db3`` file of a ROS 2 bag folder (beside its
    ``metadata.yaml``): then the folder is what is read."""
    return path.suffix in (".mcap", ".db3") and (path.parent / "metadata.yaml").is_file()


def source_of(path: Path) -> Path:
    """What reading the recording ``path`` reads: the bag folder for a file inside one
    (`in_bag_folder`), else ``path`` itself."""
    return path.parent if in_bag_folder(path) else path


def _resolve(path: Path) -> tuple[Path, str]:
    """(what to open, its kind) for a path the user gave."""
    check_lookup(path, "path", BagError)
    if not path.exists():
        raise BagError(f"no recording at {path}")
    if not (path.is_dir() or path.is_file()):  # a FIFO would block the reader for ever
        raise BagError(f"{path} is not a regular file nor a folder (a FIFO, device or socket)")
    if path.is_dir():
        if not (path / "metadata.yaml").is_file():
            data = sorted(p.name for p in path.glob("*") if p.suffix in (".mcap", ".db3"))
            raise BagError(
                f"{path} is a folder without metadata.yaml: not a ROS 2 bag (give the bag's "
                "folder, a *.mcap file or a ROS 1 *.bag file)" + (
                    f"; it holds {', '.join(data[:3])}{' ...' if len(data) > 3 else ''}: a "
                    "recorder stopped before it wrote metadata.yaml leaves such a folder, "
                    f"which `ros2 bag reindex {path} -s {_storage_id(data[0])}` mends"
                    if data else ""
                )
            )  # fmt: skip
        return path, "rosbag2"
    if in_bag_folder(path):
        return path.parent, "rosbag2"
    if path.suffix == ".mcap" or _starts_with(path, storage_mod.MAGIC):  # record_run: any name
        return path, "mcap"
    if path.suffix == ".bag":
        return path, "ros1"
    if path.suffix == ".db3":
        raise BagError(
            f"{path} is a sqlite3 bag file without its folder's metadata.yaml (a recorder "
            f"stopped before it wrote it: `ros2 bag reindex {path.parent} -s sqlite3` mends "
            "the folder)"
        )
    raise BagError(
        f"{path}: not a recording this reader knows (a ROS 2 bag folder, *.mcap, *.db3 in its "
        "bag folder, or a ROS 1 *.bag)"
    )


def _storage_id(name: str) -> str:
    """The ``ros2 bag`` storage id of a bag's data file."""
    return "mcap" if name.endswith(".mcap") else "sqlite3"


def _starts_with(path: Path, magic: bytes) -> bool:
    """Whether the file ``path`` begins with ``magic`` (False where it cannot be read)."""
    try:
        with open(path, "rb") as f:
            return f.read(len(magic)) == magic
    except OSError:
        return False


def recording_path(value, name: str = "path") -> Path:
    """``value`` (a str or `os.PathLike`, not empty) as a Path; `ControlError` naming the
    argument ``name`` for anything else (None, a number, ...)."""
    return path_argument(value, name, " of a ROS 2 bag folder, a *.mcap file or a ROS 1 *.bag")


def read_recording(
    path: str | os.PathLike, imu_topic: str = "/imu/data", odom_topic: str = "/odometry/filtered"
) -> Recording:
    """Read the IMU and odometry messages of a recording (see the module docstring for what
    opens), each topic in receive-time order. Raises `BagError` naming the topic when a topic is
    missing, holds another message type or has no messages, and naming the file when it is
    damaged; `ControlError` when ``path`` is not a path or a topic not a str; `MissingExtraError`
    when the ``robot`` extra is not installed."""
    tic = time.perf_counter()
    path = recording_path(path)
    _check_topic_names(imu_topic, odom_topic)
    require("rosbags.typesys", "reading a robot recording")
    target, kind = _resolve(path)
    if kind == "mcap":
        require("mcap.reader", "reading an MCAP file")
    wanted = [imu_topic, odom_topic]
    raw, storage, digests, simulated, checksum = None, "", {}, {}, None
    if kind == "rosbag2":
        info = _bag_information(target)
        files, storage, simple = _bag_files(target, info)
        digests = _recorded_digests(target, info)
        simulated, checksum = _custom_simulation(target, info)
        if simple and storage == "mcap":
            raw = storage_mod.mcap_messages(files, wanted)
        elif simple and storage == "sqlite3":
            raw = storage_mod.sqlite_messages(files, wanted)
    elif kind == "mcap":
        raw = storage_mod.mcap_messages([target], wanted, SIMULATION_NAMES, _METADATA_BYTES)
    if raw is not None:
        for topic in wanted:
            _check_digest(
                target, digests, topic, raw.log_ns.get(topic, []), raw.data.get(topic, [])
            )
        topics, imu, odom = _from_raw(target, raw, imu_topic, odom_topic)
        metadata = raw.metadata
    elif kind == "mcap":
        topics, imu, odom, metadata = _read_mcap(target, imu_topic, odom_topic)
    else:
        topics, imu, odom = _read_rosbags(target, kind, imu_topic, odom_topic, digests)
    for topic, got in ((imu_topic, imu), (odom_topic, odom)):
        if got.stamp_ns.size == 0:
            raise BagError(f"the topic {topic!r} in {target} has no messages")
    if kind == "mcap":
        simulated, checksum = _mcap_simulation(target, metadata)
    model, noise_std = simulation_from_record(simulated, checksum)
    return Recording(
        target, kind, storage, topics, imu, odom, time.perf_counter() - tic, model, noise_std
    )


_TOO_DEEP = "its metadata.yaml is nested too deep to parse (a damaged or hostile file)"


def _bag_information(folder: Path):
    """The ``rosbag2_bagfile_information`` of a bag folder's metadata.yaml, read once; None
    where it does not read (rosbags reads, and reports on, whatever this does not); `BagError`
    for one nested too deep to parse (rosbags' parser would take seconds more to fail too)."""
    yaml = require("ruamel.yaml", "reading a ROS 2 bag")
    try:
        # bytes: YAML's own encodings (UTF-8 as ROS 2 writes it, or a BOM's), not the locale's
        return yaml.YAML(typ="safe").load((folder / "metadata.yaml").read_bytes())[
            "rosbag2_bagfile_information"
        ]
    except RecursionError as exc:
        raise BagError(f"cannot open {folder} as a ROS bag: {_TOO_DEEP}") from exc
    except Exception:  # rosbags reads (and reports on) whatever this does not understand
        return None


def _bag_files(folder: Path, info) -> tuple[list[Path], str, bool]:
    """(storage files, storage id, whether the fast readers can take them) of a bag folder
    (``info``: its `_bag_information`)."""
    try:
        files = [folder / PurePath(x).name for x in info["relative_file_paths"]]
        storage = str(info["storage_identifier"])
        compression = str(info.get("compression_mode", "") or "").lower()
    except Exception:  # rosbags reads (and reports on) whatever this does not understand
        return [], "", False
    seen: set[Path] = set()
    for f in files:  # a file listed twice: each of its messages would be read twice
        if f in seen:
            raise BagError(
                f"{folder / 'metadata.yaml'} is damaged: its relative_file_paths list the file "
                f"{f.name!r} more than once"
            )
        seen.add(f)
    odd = [f for f in files if f.exists() and not f.is_file()]
    if odd:  # a FIFO would block the reader for ever
        raise BagError(f"{odd[0]}, a file of the bag {folder}, is not a regular file")
    simple = compression in ("", "none") and all(f.is_file() for f in files) and bool(files)
    return files, storage, simple


def _recorded_digests(folder: Path, info) -> dict[str, str]:
    """{topic: SHA-256} recorded in a ROS 2 bag's metadata (``info``: its `_bag_information`)
    by `open_bag_writer` (``custom_data`` ``DIGEST_KEY``); {} for a bag without the record
    (another writer's). `BagError` for a record that is not such a mapping."""
    try:
        custom = info.get("custom_data") or {}
        text = custom.get(DIGEST_KEY) if isinstance(custom, dict) else None
    except Exception:  # rosbags reads (and reports on) whatever this does not understand
        return {}
    if text is None:
        return {}
    try:
        record = json.loads(text) if isinstance(text, str) else None
    except ValueError:
        record = None
    good = isinstance(record, dict) and all(
        isinstance(k, str) and isinstance(v, str) and re.fullmatch(r"[0-9a-f]{64}", v)
        for k, v in record.items()
    )
    if not good:
        raise BagError(
            f"{folder / 'metadata.yaml'} is damaged: its custom_data {DIGEST_KEY} is not the "
            "record of the messages' SHA-256 that this package writes"
        )
    return record


def _custom_simulation(folder: Path, info) -> tuple[dict[str, tuple[str, object]], tuple | None]:
    """The simulation record (`SIMULATION_KEYS`) in a ROS 2 bag's custom_data (``info``: its
    `_bag_information`) as {field: (where, value)}, {} for a bag without it; and its checksum
    (`SIMULATION_SHA256`) as (what the record is, for a message; value), None where absent."""
    try:
        custom = info.get("custom_data") or {}
    except Exception:  # rosbags reads (and reports on) whatever this does not understand
        return {}, None
    if not isinstance(custom, dict):
        return {}, None
    meta = folder / "metadata.yaml"
    fields = {
        name: (f"{meta} is damaged: its custom_data {key!r}", custom[key])
        for name, key in SIMULATION_KEYS.items()
        if key in custom
    }
    if SIMULATION_SHA256 not in custom:
        return fields, None
    keys = ", ".join(repr(k) for k in SIMULATION_KEYS.values())
    what = f"{meta} is damaged: its simulation record (custom_data {keys})"
    return fields, (what, custom[SIMULATION_SHA256])


def _mcap_simulation(
    path: Path, metadata: dict[str, list[dict[str, str]]]
) -> tuple[dict[str, tuple[str, object]], tuple | None]:
    """The MCAP file's `SIMULATION_RECORD` Metadata record as {field: (where, value)}, {} for a
    file without it, and its checksum (`SIMULATION_SHA256`) as (what the record is, for a
    message; value), None where absent; ``metadata``: {name: the metadata of each record of that
    name}, as read with the messages. `BagError` for several such records or one with fields
    other than those written."""
    where = f"{path} is damaged: its {SIMULATION_RECORD!r} metadata record"
    fields = _only_record(where, metadata.get(SIMULATION_RECORD, []), set(SIMULATION_KEYS))
    sums = metadata.get(SIMULATION_SHA256, [])
    digest = _only_record(f"{path} is damaged: its {SIMULATION_SHA256!r} metadata record", sums,
                          {"sha256"})  # fmt: skip
    named = {name: (f"{where}, field {name!r}", value) for name, value in fields.items()}
    return named, ((where, digest.get("sha256")) if sums else None)


def _only_record(where: str, records: list[dict], allowed: set[str]) -> dict:
    """The fields of the one record of ``records`` ({} for none); `BagError` for several or
    for a field not in ``allowed``."""
    if not records:
        return {}
    if len(records) > 1:
        raise BagError(f"{where} is there {len(records)} times; a recording holds one at most")
    unknown = sorted(set(records[0]) - allowed)
    if unknown:
        raise BagError(
            f"{where} holds unknown field(s) {[k[:40] for k in unknown[:5]]}; allowed "
            f"{sorted(allowed)}"
        )
    return records[0]


def simulation_checksum(record: dict[str, str]) -> str:
    """SHA-256 (hex) of a simulation record's canonical JSON: its {field: text} (as
    `simulation_record` gives it) with sorted keys, no spaces, ASCII."""
    text = json.dumps(record, sort_keys=True, separators=(",", ":"), ensure_ascii=True)
    return hashlib.sha256(text.encode()).hexdigest()


def simulation_record(model=None, noise_std=None) -> dict[str, str]:
    """{field: text} recording a simulated vehicle model (``model.describe()`` as JSON) and
    its accelerometer noise sd (m/s^2, a JSON number), each where given (not None);
    `ControlError` naming the argument otherwise."""
    out = {}
    if model is not None:
        try:
            model = vehicle.models.check_model(model)
        except vehicle.VehicleError as exc:
            raise ControlError(str(exc)) from None
        out["vehicle"] = json.dumps(model.describe(), sort_keys=True)
    if noise_std is not None:
        try:
            out["noise_std"] = json.dumps(vehicle.sensor.check_noise(noise_std))
        except vehicle.VehicleError as exc:
            raise ControlError(str(exc)) from None
    return out


def simulation_from_record(
    fields: dict[str, tuple[str, object]], checksum: tuple[str, object] | None = None
) -> tuple[Model | None, float | None]:
    """(vehicle model, noise sd m/s^2) from a recording's simulation record ({field: (where it
    is, for a message; its text)}), None for each field absent. `BagError` naming the field
    where its text is not a str of at most `MAX_SIMULATION_CHARS` characters holding JSON of a
    vehicle description (`vehicle.from_description`: a known model, known parameters, finite
    values in range) or of a noise sd (a finite number >= 0); then, where ``checksum`` (what the
    record is, for a message; the recorded `simulation_checksum`) is given, naming the record
    where it does not match (a digit changed: another vehicle) or is not a SHA-256."""
    values = {}
    for name, (where, text) in fields.items():
        if not isinstance(text, str):
            raise BagError(f"{where} is a {type(text).__name__}, not the JSON text written")
        if len(text) > MAX_SIMULATION_CHARS:
            raise BagError(
                f"{where} is {len(text)} characters long, more than {MAX_SIMULATION_CHARS} "
                "allowed (a damaged or hostile record)"
            )
        try:
            values[name] = json.loads(text)
        except (ValueError, RecursionError) as exc:
            raise BagError(f"{where} is not JSON ({_why(exc)})") from exc
    model = noise = None
    if "vehicle" in values:
        try:
            model = vehicle.from_description(values["vehicle"])
        except (vehicle.VehicleError, TypeError) as exc:
            where = fields["vehicle"][0]
            raise BagError(f"{where} is not a vehicle description: {exc}") from exc
    if "noise_std" in values:
        try:
            noise = vehicle.sensor.check_noise(values["noise_std"])
        except vehicle.VehicleError as exc:
            raise BagError(f"{fields['noise_std'][0]} is not a noise sd: {exc}") from exc
    if checksum is not None:
        _check_simulation_checksum({name: text for name, (_, text) in fields.items()}, *checksum)
    return model, noise


def _check_simulation_checksum(record: dict[str, str], what: str, recorded) -> None:
    """`BagError` naming the record (``what``) where ``recorded`` is not a SHA-256 or not the
    `simulation_checksum` of ``record``."""
    if not (isinstance(recorded, str) and re.fullmatch(r"[0-9a-f]{64}", recorded)):
        raise BagError(f"{what}: its checksum {SIMULATION_SHA256!r} is not a SHA-256 (64 hex "
                       f"digits), got {str(recorded)[:80]!r}")  # fmt: skip
    if simulation_checksum(record) != recorded:
        raise BagError(
            f"{what} does not match its SHA-256 ({SIMULATION_SHA256!r}): it was changed after it "
            "was written (another vehicle or noise sd than the one simulated)"
        )


def messages_digest(log_ns: Sequence[int], data: Sequence[bytes]) -> str:
    """SHA-256 of a topic's messages, whatever order a storage returns them in: of each
    message's (receive time ns, SHA-256 of its bytes), sorted."""
    return _sorted_digest(log_ns, [hashlib.sha256(d).digest() for d in data])


def _sorted_digest(log_ns: Sequence[int], digests: Sequence[bytes]) -> str:
    """SHA-256 of the (receive time, message SHA-256) pairs, sorted: of each pair's time as a
    little-endian int64 then its 32 bytes, by time, then by digest. Hashed as one array (a 400 Hz
    IMU's 40,000 pairs in a few ms instead of ~20); `_sorted_digest_pairs` where a time does not
    fit int64, as the format has always been written."""
    n = len(digests)
    try:
        stamps = np.array([int(t) for t in log_ns], dtype=np.int64)
    except OverflowError:
        return _sorted_digest_pairs(log_ns, digests)
    joined = b"".join(digests)
    if stamps.size != n or len(joined) != 32 * n:
        return _sorted_digest_pairs(log_ns, digests)
    pairs = np.empty(n, dtype=[("t", "<i8"), ("d", "V32")])
    pairs["t"] = stamps
    pairs["d"] = np.frombuffer(joined, dtype="V32")
    if n > 1 and not np.all(stamps[1:] > stamps[:-1]):  # disordered or tied: sort as tuples do
        words = np.frombuffer(joined, dtype=">u8").reshape(n, 4)  # bytes order, word by word
        pairs = pairs[np.lexsort((words[:, 3], words[:, 2], words[:, 1], words[:, 0], stamps))]
    return hashlib.sha256(pairs.tobytes()).hexdigest()


def _sorted_digest_pairs(log_ns: Sequence[int], digests: Sequence[bytes]) -> str:
    """`_sorted_digest` pair by pair (its definition; struct.error for a time beyond int64)."""
    h = hashlib.sha256()
    for stamp, digest in sorted(zip((int(t) for t in log_ns), digests, strict=True)):
        h.update(struct.pack("<q", stamp))
        h.update(digest)
    return h.hexdigest()


def _check_digest(path: Path, digests: dict[str, str], topic: str, log_ns, data) -> None:
    """`BagError` where the bag recorded the SHA-256 of ``topic``'s messages and they no longer
    have it (a message's bytes or time changed, one lost or added)."""
    want = digests.get(topic)
    if want is not None and messages_digest(log_ns, data) != want:
        raise BagError(
            f"{path} is damaged: the messages of the topic {topic!r} are not those written (their "
            f"SHA-256, recorded in metadata.yaml's custom_data {DIGEST_KEY!r}, differs)"
        )


class _DigestingWriter:
    """A rosbags writer that also keeps, per topic, what `messages_digest` needs."""

    def __init__(self, writer):
        self._writer = writer
        self._messages: dict[str, tuple[list[int], list[bytes]]] = {}  # times, SHA-256s

    def add_connection(self, topic: str, *args, **kwargs):
        self._messages.setdefault(topic, ([], []))
        return self._writer.add_connection(topic, *args, **kwargs)

    def write(self, connection, timestamp: int, data: bytes) -> None:
        """Write one message; `ControlError`, before anything is written, for a ``timestamp``
        that is not an integer receive time in [0, 2**63) ns or ``data`` that is not bytes
        (rosbags' MCAP writer took such a message into its chunk's records before it refused
        it, and the bag then raised on closing: every message before it lost)."""
        if not (is_integer(timestamp) and 0 <= timestamp < MAX_LOG_NS):
            raise ControlError(
                f"timestamp must be an integer receive time in [0, 2**63) ns, got "
                f"{timestamp!r:.60}: the message is not written (the bag stays open)"
            )
        try:
            memoryview(data)  # bytes, or an array of them (rosbags' serialize_cdr)
        except TypeError:
            raise ControlError(
                f"data must be a message's serialized bytes (CDR), got {type(data).__name__}: "
                "the message is not written (the bag stays open)"
            ) from None
        self._writer.write(connection, timestamp, data)
        log, digests = self._messages[connection.topic]
        log.append(int(timestamp))
        digests.append(hashlib.sha256(data).digest())

    def record(self) -> str:
        """The JSON of {topic: SHA-256 of its messages} (`messages_digest` of what was written)."""
        out = {topic: _sorted_digest(*messages) for topic, messages in self._messages.items()}
        return json.dumps(out, sort_keys=True)


def _from_raw(path: Path, raw, imu_topic: str, odom_topic: str):
    """(topics, IMU, odometry) from raw messages read by `control.robot.storage`."""
    _check_topics(path, raw.types, imu_topic, odom_topic)
    out = []
    for topic, make in ((imu_topic, _imu), (odom_topic, _odometry)):
        _check_encoding(path, topic, raw.encodings.get(topic, "cdr"))
        log = _receive_times(path, topic, raw.log_ns[topic])
        order = np.argsort(log, kind="stable")
        data, which = raw.data[topic], raw.schema_index.get(topic)
        if np.any(np.diff(order) != 1):
            data = [data[i] for i in order]
            if which is not None:
                which = [which[i] for i in order]
        decode = _schema_decoder(path, topic, raw.types[topic], raw.definitions.get(topic), which)
        out.append(make(path, topic, log[order], data, decode))
    return raw.types, out[0], out[1]


def _schema_decoder(
    path: Path,
    topic: str,
    msgtype: str,
    definitions: Sequence[tuple[str, bytes | str]] | None,
    which: Sequence[int] | None,
):
    """``decode(k, data)``: message k of ``topic`` (``msgtype``) deserialised with the
    typestore of its own channel's schema, ``definitions[which[k]]`` (``which`` None: the
    first; no definitions: ROS 2's standard types); each typestore made when first needed
    (`_decoding_store`), so that messages the fast decoder reads never need one."""
    made: dict[int, object] = {}
    name = _normalise(msgtype)

    def decode(k: int, data: bytes):
        i = which[k] if which else 0
        if i not in made:
            encoding, text = definitions[i] if definitions else ("", "")
            made[i] = _decoding_store(path, topic, msgtype, encoding, text)
        return made[i].deserialize_cdr(data, name)

    return decode


def _decoding_store(path: Path, topic: str, msgtype: str, encoding: str, data: bytes | str):
    """The typestore that decodes ``topic``'s ``msgtype``: the definition its file carries
    (schema ``encoding`` ros2msg or ros2idl, text ``data``), as rosbags reads a bag, else (none,
    or an empty one) ROS 2's standard one (Humble). A sub-message type the definition uses
    but does not define (a schema without its "MSG: <type>" blocks) is taken from ROS 2's
    standard types where it is one of them. `BagError` for a definition that does not parse,
    or that lacks a sub-message type that is not a standard one (naming it)."""
    stores = require("rosbags.typesys", "reading a ROS bag")
    standard = stores.get_typestore(stores.Stores.ROS2_HUMBLE)
    try:
        text = data.decode() if isinstance(data, bytes) else data
        if encoding not in ("ros2msg", "ros2idl") or not text.strip():
            return standard
        if encoding == "ros2msg":
            types = stores.get_types_from_msg(text, _normalise(msgtype))
        elif text.startswith(_IDL_BLOCK):  # MCAP's form: one "IDL: <type>" block a type
            types = {}
            for block in text.split(_SEPARATOR)[1:]:
                types.update(stores.get_types_from_idl(block.partition("\n")[2]))
        else:
            types = stores.get_types_from_idl(text)
        missing = _complete(types, standard.fielddefs)
        if missing:
            raise BagError(
                f"{path}: the schema {msgtype!r} ({encoding}) of the topic {topic!r} uses the "
                f"type {missing!r} without its definition, which is not a standard ROS 2 "
                "type either (a schema carries the definition of each type its fields use)"
            )
        store = stores.get_typestore(stores.Stores.EMPTY)
        store.register(types)
    except (UnicodeDecodeError, stores.TypesysError) as exc:
        raise BagError(
            f"{path} is damaged: the schema of the topic {topic!r} does not parse ({_why(exc)})"
        ) from exc
    return store


def _complete(types: dict, standard: dict) -> str | None:
    """Add to ``types`` (a rosbags Typesdict: name -> (constants, fields)) each type its fields
    use, at any depth, that it lacks and ``standard`` holds; the first type used that neither
    holds, None where none."""
    nodes = require("rosbags.interfaces", "reading a ROS bag").Nodetype
    pending = list(types)
    while pending:
        for _, desc in types[pending.pop()][1]:
            while desc[0] in (nodes.ARRAY, nodes.SEQUENCE):  # (kind, (element, size))
                desc = desc[1][0]
            kind, used = desc
            if kind != nodes.NAME or used in types:
                continue
            if used not in standard:
                return used
            types[used] = standard[used]
            pending.append(used)
    return None


_SEPARATOR = "=" * 80 + "\n"
_IDL_BLOCK = _SEPARATOR + "IDL: "


def _damage_errors() -> tuple[type[BaseException], ...]:
    """What rosbags raises on a recording's damaged bytes, opening, reading or deserialising
    them: its own errors, apsw's (a sqlite3 bag), the zstd module's (a compressed ROS 2 bag)
    and (found by corrupting bags byte by byte) Python's for a garbled length or offset (a
    read of more memory than there is, a seek outside the file), index, text or number, a
    failed assertion on the format, a sqlite3 value of another type than the column's
    (passed on to the decompressor), or a metadata.yaml nested too deep for its YAML parser
    (RecursionError)."""
    purpose = "reading a ROS bag"
    zstd = "compression.zstd" if sys.version_info >= (3, 14) else "backports.zstd"  # as rosbags
    backends = tuple(  # rosbags' own dependencies, absent from its older releases
        getattr(module, error)
        for name, error in (("apsw", "Error"), (zstd, "ZstdError"))
        if (module := _imported(name)) is not None
    )
    return (
        require("rosbags.serde", purpose).SerdeError,
        require("rosbags.highlevel", purpose).AnyReaderError,
        require("rosbags.rosbag1", purpose).ReaderError,
        require("rosbags.rosbag2", purpose).ReaderError,
        *backends,
        AssertionError, EOFError, LookupError, ValueError, ArithmeticError, MemoryError,
        OSError, TypeError, struct.error, RecursionError,
    )  # fmt: skip


def _imported(name: str):
    """The module ``name``, or None where it is not installed."""
    try:
        return importlib.import_module(name)
    except ImportError:
        return None


def _why(exc: BaseException) -> str:
    """An exception's type and message (some carry none), for a `BagError`'s message."""
    text = " ".join(str(exc).split())
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def _receive_times(path: Path, topic: str, log_ns) -> np.ndarray:
    """Receive times as int64 ns; `BagError` for one outside int64's range or not a number (a
    damaged file)."""
    try:
        return np.asarray(log_ns, dtype=np.int64)
    except (OverflowError, TypeError, ValueError) as exc:
        raise BagError(
            f"{path} is damaged: a receive time of the topic {topic!r} is not an int64 ns "
            f"({_why(exc)})"
        ) from exc


def _decoded(path: Path, topic: str, raws: list, decode, read, what: str) -> list:
    """``read(message)`` of each message deserialised by ``decode(k, raw)`` (a generic
    deserialiser; k: the message's index); `BagError` naming the message where it does not
    deserialise, or where its type, as its schema defines it, lacks ``what`` ``read`` reads."""
    errors = _damage_errors()
    out = []
    for k, raw in enumerate(raws):
        try:
            message = decode(k, raw)
        except BagError:  # the schema's own (`_decoding_store`), a ValueError too
            raise
        except errors as exc:
            raise BagError(
                f"{path} is damaged: message {k} of the topic {topic!r} does not deserialise "
                f"({_why(exc)})"
            ) from exc
        try:
            out.append(read(message))
        except (AttributeError, TypeError, ValueError, IndexError) as exc:
            raise BagError(
                f"message {k} of the topic {topic!r} in {path} lacks the fields the replay "
                f"reads ({what}): its schema defines its type otherwise ({_why(exc)})"
            ) from exc
    return out


_IMU_FIELDS = "header.stamp, linear_acceleration, linear_acceleration_covariance"
_ODOMETRY_FIELDS = "header.stamp, pose.pose.position, twist.twist.linear"


def _imu(path: Path, topic: str, log_ns, raws: list, decode, cdr: bool = True) -> ImuMessages:
    log = _receive_times(path, topic, log_ns)
    try:
        if not cdr:
            raise msgs.CdrLayoutError("not CDR")
        stamp, accel, unknown = msgs.decode_imu(raws)
    except msgs.CdrLayoutError:

        def read(m) -> tuple:
            covariance = float(m.linear_acceleration_covariance[0])
            return _stamp(m, ros1=not cdr), _xyz(m.linear_acceleration), covariance

        fields = _decoded(path, topic, raws, decode, read, _IMU_FIELDS)
        stamp = np.array([f[0] for f in fields], dtype=np.int64)
        accel = np.array([f[1] for f in fields]).reshape(-1, 3)
        unknown = np.array([f[2] == msgs.UNKNOWN_COVARIANCE for f in fields], dtype=bool)
    return ImuMessages(topic, log, stamp, accel, unknown if unknown.any() else None)


def _odometry(
    path: Path, topic: str, log_ns, raws: list, decode, cdr: bool = True
) -> OdometryMessages:
    log = _receive_times(path, topic, log_ns)
    try:
        if not cdr:
            raise msgs.CdrLayoutError("not CDR")
        stamp, position, velocity = msgs.decode_odometry(raws)
    except msgs.CdrLayoutError:

        def read(m) -> tuple:
            return _stamp(m, ros1=not cdr), _xyz(m.pose.pose.position), _xyz(m.twist.twist.linear)

        fields = _decoded(path, topic, raws, decode, read, _ODOMETRY_FIELDS)
        stamp = np.array([f[0] for f in fields], dtype=np.int64)
        position = np.array([f[1] for f in fields]).reshape(-1, 3)
        velocity = np.array([f[2] for f in fields]).reshape(-1, 3)
    return OdometryMessages(topic, log, stamp, position, velocity)


def _stamp(msg, ros1: bool = False) -> int:
    """A message's header stamp, ns. A ROS 1 time's seconds are a uint32 (to 2106), which
    rosbags decodes as ROS 2's int32: a stamp from 2038 on reads negative, and is mended."""
    stamp = msg.header.stamp
    sec = int(stamp.sec) % 2**32 if ros1 else int(stamp.sec)
    return sec * 1_000_000_000 + int(stamp.nanosec)


def _xyz(v) -> tuple[float, float, float]:
    return float(v.x), float(v.y), float(v.z)


def _read_rosbags(path: Path, kind: str, imu_topic: str, odom_topic: str, digests=None):
    highlevel = require("rosbags.highlevel", "reading a ROS bag")
    stores = require("rosbags.typesys", "reading a ROS bag")
    default = stores.get_typestore(
        stores.Stores.ROS1_NOETIC if kind == "ros1" else stores.Stores.ROS2_HUMBLE
    )
    try:
        reader = highlevel.AnyReader([path], default_typestore=default)
        reader.open()
    except _damage_errors() as exc:
        why = _TOO_DEEP if isinstance(exc, RecursionError) else _why(exc)  # rosbags' YAML parser
        raise BagError(f"cannot open {path} as a ROS bag: {why}") from exc
    try:
        topics = {t: info.msgtype for t, info in reader.topics.items()}
        _check_topics(path, topics, imu_topic, odom_topic)
        out = []
        for topic, make in ((imu_topic, _imu), (odom_topic, _odometry)):
            conns = [c for c in reader.connections if c.topic == topic]
            log, raws = _messages(reader, conns, path, topic)
            _check_digest(path, digests or {}, topic, log, raws)
            msgtype = conns[0].msgtype

            def decode(_k: int, raw: bytes, msgtype=msgtype):
                return reader.deserialize(raw, msgtype)

            out.append(make(path, topic, log, raws, decode, cdr=reader.is2))
        return topics, out[0], out[1]
    finally:
        reader.close()


def _messages(reader, conns: list, path: Path, topic: str) -> tuple[list[int], list[bytes]]:
    """(receive times, raw data) of a topic's connections, read by a rosbags reader."""
    log, raws = [], []
    try:
        for _, stamp, raw in reader.messages(connections=conns):
            log.append(stamp)
            raws.append(raw)
    except _damage_errors() as exc:
        raise BagError(
            f"{path} is damaged: reading the topic {topic!r} failed ({_why(exc)})"
        ) from exc
    return log, raws


def _read_mcap(path: Path, imu_topic: str, odom_topic: str):
    """(topics, IMU, odometry, metadata) of an MCAP file the fast reader does not take, read
    with the mcap package (or, for a file without a summary, its stream reader): each message
    decoded, where the fast decoder does not read it, with its own channel's schema."""
    reader_mod = require("mcap.reader", "reading an MCAP file")
    wanted = (imu_topic, odom_topic)
    with open(path, "rb") as f:
        try:
            reader = reader_mod.make_reader(f, validate_crcs=True)
            summary = reader.get_summary()
        except Exception as exc:  # the mcap package raises its own errors for damaged files
            if cut := storage_mod.truncation(f):  # its errors for these say nothing of why
                raise BagError(f"{path} {cut}") from exc
            raise BagError(f"cannot read {path} as an MCAP file: {_why(exc)}") from exc
        if summary is not None:
            channels = {  # None: no schema (id 0), or one the summary lacks (a damaged file)
                cid: (ch, summary.schemas.get(ch.schema_id)) for cid, ch in summary.channels.items()
            }
            topics = _channel_topics(path, channels.values(), wanted)
            metadata = storage_mod.indexed_metadata(
                path, f, summary, SIMULATION_NAMES, _METADATA_BYTES
            )
            messages = reader.iter_messages(topics=list(wanted))
        else:  # an unindexed (e.g. truncated) file: find the topics by reading it all
            channels, metadata = {}, {name: [] for name in SIMULATION_NAMES}
            messages = _unindexed_messages(f, metadata, channels)
        collected: dict[str, tuple[list, list, list]] = {t: ([], [], []) for t in wanted}
        definitions: dict[str, list[tuple[str, bytes]]] = {t: [] for t in wanted}
        try:
            for schema, channel, message in messages:
                if channel.topic not in collected:
                    continue
                log, data, which = collected[channel.topic]
                known = definitions[channel.topic]
                key = (schema.encoding, schema.data) if schema is not None else ("", b"")
                if key not in known:
                    known.append(key)
                log.append(message.log_time)
                data.append(message.data)
                which.append(known.index(key))
        except BagError:
            raise
        except Exception as exc:
            raise BagError(f"cannot read the messages of {path}: {_why(exc)}") from exc
    if summary is None:
        topics = _channel_topics(path, channels.values(), wanted)
    elif summary.statistics is not None:
        _check_counts(path, summary, {t: len(log) for t, (log, _, _) in collected.items()})
    out = []
    for topic, make in ((imu_topic, _imu), (odom_topic, _odometry)):
        log, data, which = collected[topic]
        decode = _schema_decoder(path, topic, topics[topic], definitions[topic], which)
        out.append(make(path, topic, log, data, decode))
    return topics, out[0], out[1], metadata


def _channel_topics(path: Path, channels, wanted: Sequence[str]) -> dict[str, str | None]:
    """{topic: its message type (None: several)} of an MCAP file's (channel, schema or None)
    pairs, the topics ``wanted`` (IMU, odometry) checked (`_check_topics`, `_check_encoding`)
    as the fast reader checks them."""
    topics: dict[str, str | None] = {}
    encodings: dict[str, str] = {}
    for channel, schema in channels:
        storage_mod.note_type(topics, channel.topic, schema.name if schema is not None else "")
        if channel.topic in wanted:
            storage_mod.note_encoding(encodings, channel.topic, channel.message_encoding)
            if schema is not None:
                _check_schema_text(path, channel.topic, schema.data)
    _check_topics(path, topics, *wanted)
    for topic in wanted:
        _check_encoding(path, topic, encodings[topic])
    return topics


def _check_schema_text(path: Path, topic: str, data: bytes) -> None:
    """`BagError` where a schema's text is not UTF-8 (as the fast reader words it)."""
    try:
        data.decode()
    except UnicodeDecodeError as exc:
        raise BagError(f"{path} is damaged: the schema of {topic!r} is not UTF-8 text") from exc


def _check_encoding(path: Path, topic: str, encoding: str) -> None:
    """`BagError` unless the messages of ``topic`` are encoded as cdr (ROS 2's)."""
    if encoding != "cdr":
        raise BagError(
            f"the topic {topic!r} in {path} is encoded as {encoding!r}; the replay reads ROS 2 "
            "(cdr) messages"
        )


def _unindexed_messages(
    f, metadata: dict[str, list[dict[str, str]]], channels: dict[int, tuple]
) -> Iterator[tuple]:
    """(schema, channel, message) of each message of the MCAP file ``f`` (without a summary) in
    log-time order, as the mcap package's reader gives them, appending to ``metadata``
    ({name: []}) the metadata of each Metadata record of those names met on the way, and
    to ``channels`` (channel id -> (channel, its schema or None)) each Channel record: one
    pass over the file for all."""
    records = require("mcap.records", "reading an MCAP file")
    error = require("mcap.exceptions", "reading an MCAP file").McapError
    f.seek(0)
    stream = require("mcap.stream_reader", "reading an MCAP file").StreamReader(f)
    schemas, found = {}, []
    for record in stream.records:
        if isinstance(record, records.Message):
            if record.channel_id not in channels:
                raise error(f"no channel record found with id {record.channel_id}")
            channel, schema = channels[record.channel_id]
            found.append((schema, channel, record))
        elif isinstance(record, records.Schema):
            schemas[record.id] = record
        elif isinstance(record, records.Channel):
            if record.schema_id != 0 and record.schema_id not in schemas:
                raise error(f"no schema record found with id {record.schema_id}")
            channels[record.id] = (record, schemas.get(record.schema_id))
        elif isinstance(record, records.Metadata) and record.name in metadata:
            metadata[record.name].append(dict(record.metadata))
    found.sort(key=lambda item: item[2].log_time)  # stable, as the mcap package's reader
    yield from found


def _check_counts(path: Path, summary, found: dict[str, int]) -> None:
    """`BagError` where the messages read of a topic are not as many as the MCAP file's
    statistics count: the mcap package passes over a chunk whose index is damaged, and over
    messages outside chunks, without a word."""
    counts = summary.statistics.channel_message_counts
    for topic, n in found.items():
        want = sum(counts.get(c, 0) for c, ch in summary.channels.items() if ch.topic == topic)
        if want != n:
            raise BagError(
                f"{path} is damaged: its statistics count {want} messages of the topic "
                f"{topic!r}, its indexed chunks hold {n} (a damaged chunk index, or messages "
                "outside chunks, which the mcap package does not read)"
            )


# --- writing ------------------------------------------------------------------------------------


def _check_storage(storage: str) -> None:
    if not is_choice(storage, STORAGES):
        raise ControlError(f"storage must be one of {STORAGES}, got {storage!r}")


STAMP_LIMIT_NS = msgs.MAX_STAMP_NS + 1
"""A ROS 2 header stamp's seconds are an int32: stamps lie in [0, 2**31) s."""
MAX_LOG_NS = 2**63
"""A bag's receive times are int64 ns."""


def stamps_ns(name: str, t, limit: int = STAMP_LIMIT_NS, offset_ns: int = 0) -> np.ndarray:
    """Times ``t`` (s, 1-D) as int64 ns plus ``offset_ns`` (an integer); `ControlError` naming
    ``name`` unless every one is a finite number that lands in [0, ``limit``) ns, ``limit`` at
    most 2**63 (checked in integers: near 2**31 s a float64 sum is off by up to 256 ns)."""
    arr = np.atleast_1d(float_array(t, name))
    if arr.ndim != 1:
        raise ControlError(f"{name} must be 1-D (times in s), got shape {arr.shape}")
    with np.errstate(invalid="ignore", over="ignore"):
        ns = np.rint(arr * 1e9)
    bad = ~(np.abs(ns) < 2.0**63)  # NaN, inf, beyond int64
    whole = np.where(bad, 0.0, ns).astype(np.int64)
    low, high = max(-offset_ns, -(2**63)), min(limit - offset_ns, 2**63) - 1  # whole's bounds
    bad |= (whole < low) | (whole > high) if low <= high else True
    if np.any(bad):
        first = float(arr[bad][0])
        raise ControlError(
            f"{name} holds {first!r} s: allowed finite times that, with an offset of "
            f"{offset_ns} ns, lie in [0, {limit / 1e9:.6g}) s"
        )
    return whole + np.int64(offset_ns)


def _vectors(name: str, a, n: int, axis: str = "x") -> np.ndarray:
    a = float_array(a, name)
    if a.ndim == 1:
        if a.size != n:
            raise ControlError(f"{name} must have length {n}, got {a.size}")
        out = np.zeros((n, 3))
        out[:, "xyz".index(axis)] = a
        return out
    if a.shape != (n, 3):
        raise ControlError(f"{name} must have shape ({n},) or ({n}, 3), got {a.shape}")
    return a


def check_bag_path(path: Path, storage: str, name: str = "path") -> None:
    """`ControlError` naming ``name`` where a bag of ``storage`` cannot be written to ``path``:
    a sqlite3 bag to a path holding a '?', a '#' or a '%' and two hex digits (`URI_PARTS`:
    rosbags' sqlite3 writer would put its database elsewhere and leave the bag without one)."""
    odd = URI_PARTS.search(str(path))
    if storage == "sqlite3" and odd:
        raise ControlError(
            f"{name}={str(path)!r}: a sqlite3 bag cannot be written to a path holding "
            f"{odd.group()!r} (rosbags' sqlite3 writer reads the path as a URI: its database would "
            "land elsewhere and the bag hold none); choose another path or storage 'mcap'"
        )


@contextmanager
def open_bag_writer(
    path: str | os.PathLike, storage: str = "mcap", custom_data: dict[str, str] | None = None
) -> Iterator:
    """A rosbags ROS 2 bag writer (format version 9), open, for a new folder ``path``.

    The bag is written in a hidden folder beside ``path`` and moved to ``path`` once closed, so
    an interrupted write (an exception, a killed process) never leaves a bag without its metadata at
    ``path``; on an exception the hidden folder is removed (the moved bag too where an I/O error
    keeps its parent folder from being flushed to disk: `_flush_parent`; the folders made for it
    have their names flushed into their parents as they are made: `_flush_made`). Each chunk of
    an MCAP bag is given the CRC32 of its records (`storage.write_chunk_crcs`; rosbags' writer
    leaves it 0), so that a reader refuses a chunk whose bytes changed, and the bag's metadata
    records the SHA-256 of each topic's messages (``DIGEST_KEY``), which `read_recording` checks
    in any storage (sqlite3 has no checksums of its own); ``custom_data`` ({str: str}) is added
    to that metadata's custom_data. `ControlError` where ``path`` exists (a link to nowhere too)
    or `check_bag_path` refuses it."""
    _check_storage(storage)
    path = path_argument(path, "path", " of the new bag folder")
    check_lookup(path, "path")
    rosbag2 = require("rosbags.rosbag2", "writing a ROS 2 bag")
    if os.path.lexists(path):  # a link to nowhere too: the bag could not be moved onto it
        raise ControlError(f"{path} exists already; a bag is written to a new folder")
    check_bag_path(path, storage)
    plugin = rosbag2.StoragePlugin.MCAP if storage == "mcap" else rosbag2.StoragePlugin.SQLITE3
    made = _missing_folders(path.parent)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        _remove_made(made)
        raise ControlError(f"{path}: cannot write ({exc.strerror})") from exc
    _flush_made(path, made)
    try:
        work = Path(tempfile.mkdtemp(prefix=f".{path.name}.", suffix=".part", dir=path.parent))
    except OSError as exc:
        raise ControlError(f"{path}: cannot write ({exc.strerror})") from exc
    try:
        with rosbag2.Writer(work / path.name, version=9, storage_plugin=plugin) as writer:
            digesting = _DigestingWriter(writer)
            yield digesting
            for key, value in (custom_data or {}).items():
                writer.set_custom_data(key, value)
            writer.set_custom_data(DIGEST_KEY, digesting.record())
        for file in (work / path.name).glob("*.mcap"):  # rosbags writes chunks without CRCs
            storage_mod.write_chunk_crcs(file)
        _flush_bag(work / path.name, path)
        try:
            os.rename(work / path.name, path)  # the bag's files are named after its folder
        except OSError as exc:  # e.g. path made meanwhile by another writer
            raise ControlError(f"{path}: cannot write ({exc.strerror})") from exc
        _flush_parent(path, work)
    finally:
        shutil.rmtree(work, ignore_errors=True)


def _missing_folders(folder: Path) -> list[Path]:
    """``folder`` and its ancestors that do not exist yet, the deepest first: the folders a
    ``mkdir(parents=True)`` of it makes."""
    missing = []
    while not os.path.lexists(folder) and folder.parent != folder:
        missing.append(folder)
        folder = folder.parent
    return missing


def _flush_made(path: Path, made: Sequence[Path]) -> None:
    """Flush the parent of each folder in ``made`` (`_missing_folders`: those just made for the
    bag at ``path``, the deepest first) to disk, their names being entries of their parents:
    at once, before the bag is written, so that a second try after a failed write, which finds
    them made, does not leave them unflushed. Where an I/O error fails one, the folders are
    removed again (those still empty, so that a second try makes and flushes them) and
    `ControlError` names ``path`` and that parent."""
    for folder in made:
        try:
            flush_folder(folder.parent, ControlError)
        except ControlError as exc:
            _remove_made(made)
            raise ControlError(
                f"{path}: cannot write (the folder {folder.parent} could not be flushed to disk "
                f"after {folder.name!r} was made in it: {_flush_reason(exc)}; nothing was kept: "
                "check the disk and write it again)"
            ) from exc.__cause__


def _flush_reason(exc: ControlError) -> str:
    """What a failed `flush_folder` (``exc``) says went wrong: the OS error's text."""
    return getattr(exc.__cause__, "strerror", None) or str(exc.__cause__ or exc)


def _remove_made(made: Sequence[Path]) -> None:
    """Remove the folders in ``made`` (the deepest first) that exist and are empty."""
    for folder in made:
        try:
            os.rmdir(folder)
        except OSError:  # not made, or not empty (another writer's, meanwhile)
            pass


def _flush_parent(path: Path, work: Path) -> None:
    """Flush the folder of the bag just moved to ``path`` (`flush_folder`); where an I/O error
    fails it, the bag is moved back into ``work`` (removed with it) and `ControlError` names
    ``path``: a bag written with an error is not kept, so that a caller's cleanup and a second
    try (which a bag's existing folder refuses) hold. Where even that move fails, the error
    of `flush_folder` (the bag in place)."""
    try:
        flush_folder(path.parent, ControlError)
    except ControlError as exc:
        try:
            os.rename(path, work / path.name)
        except OSError:
            raise exc from exc.__cause__  # the bag stays: flush_folder says so
        raise ControlError(
            f"{path}: cannot write (its folder {path.parent} could not be flushed to disk after "
            f"the move: {_flush_reason(exc)}; the bag was not kept: check the disk and write it "
            "again)"
        ) from exc.__cause__


def _flush_bag(bag: Path, path: Path) -> None:
    """Flush a finished bag's files and folder (``bag``, before its move to ``path``) to disk,
    so that a power cut after the move leaves the whole bag at ``path``, not empty files
    (rosbags' writer flushes none). `ControlError` naming ``path`` for an OS error."""
    try:
        for file in bag.iterdir():
            fd = os.open(file, os.O_RDONLY)
            try:
                os.fsync(fd)
            finally:
                os.close(fd)
    except OSError as exc:
        raise ControlError(f"{path}: cannot write ({exc.strerror})") from exc
    flush_folder(bag, ControlError)


def merge_in_time(streams: Sequence[tuple[object, np.ndarray, Sequence[bytes]]]) -> Iterator:
    """(channel, time ns, data) of several streams in time order (stable: ties keep the order
    of the streams)."""
    chans = [c for c, t, _ in streams for _ in range(len(t))]
    times = np.concatenate([np.asarray(t, dtype=np.int64) for _, t, _ in streams])
    data = [d for _, _, ds in streams for d in ds]
    for i in np.argsort(times, kind="stable"):
        yield chans[i], int(times[i]), data[i]


def check_gravity(gravity) -> None:
    """`ControlError` unless ``gravity`` (the writers' option) is True or False."""
    if not isinstance(gravity, bool | np.bool_):
        raise ControlError(f"gravity must be True or False, got {gravity!r:.60}")


def sensor_messages(
    imu_time, accel, odom_time, position, speed, *, axis: str = "z",
    imu_frame: str = "imu_link", odom_frame: str = "odom", base_frame: str = "base_link",
    offset_ns: int = 0, gravity: bool = False,
) -> tuple[np.ndarray, list[bytes], np.ndarray, list[bytes]]:  # fmt: skip
    """(IMU stamps ns, CDR Imu messages, odometry stamps ns, CDR Odometry messages) of sampled
    signals (see `write_sensor_bag` for the arguments), every stamp ``offset_ns`` later;
    `ControlError` for a stamp outside a ROS 2 header's [0, 2**31) s."""
    if axis not in ("x", "y", "z"):
        raise ControlError(f"axis must be 'x', 'y' or 'z', got {axis!r}")
    check_gravity(gravity)
    t_imu = stamps_ns("imu_time", imu_time, offset_ns=offset_ns)
    t_odom = stamps_ns("odom_time", odom_time, offset_ns=offset_ns)
    acc = _vectors("accel", accel, t_imu.size, axis)
    if gravity:  # REP-145: the specific force, +g on the axis that points up at rest
        acc = acc.copy()
        acc[:, "xyz".index(axis)] += STANDARD_GRAVITY
    pos = _vectors("position", position, t_odom.size)
    vel = _vectors("speed", speed, t_odom.size)
    imu = [msgs.encode_imu(s, a, imu_frame) for s, a in zip(t_imu.tolist(), acc.tolist(),
                                                             strict=True)]  # fmt: skip
    odom = [
        msgs.encode_odometry(s, p, v, odom_frame, base_frame)
        for s, p, v in zip(t_odom.tolist(), pos.tolist(), vel.tolist(), strict=True)
    ]
    return t_imu, imu, t_odom, odom


def write_sensor_bag(
    path: str | os.PathLike,
    imu_time,
    accel,
    odom_time,
    position,
    speed,
    *,
    storage: str = "mcap",
    imu_topic: str = "/imu/data",
    odom_topic: str = "/odometry/filtered",
    axis: str = "z",
    log_time=None,
    model=None,
    noise_std: float | None = None,
    gravity: bool = False,
) -> Path:
    """Write sampled signals as a ROS 2 bag of standard messages (``sensor_msgs/msg/Imu``,
    ``nav_msgs/msg/Odometry``), e.g. a simulated drive to try the replay on.

    Args:
        path: the new bag folder.
        imu_time: (n,) IMU header stamps, s (rounded to ns; in [0, 2**31) s, a ROS 2 stamp).
        accel: (n,) accelerations along ``axis`` (m/s^2), or (n, 3).
        odom_time: (m,) odometry stamps, s.
        position: (m,) positions along the odometry frame's x axis (m), or (m, 3).
        speed: (m,) forward speeds (twist.linear.x, m/s), or (m, 3) linear velocities.
        storage: "mcap" (ROS 2's default) or "sqlite3".
        imu_topic, odom_topic: topic names (starting with "/", as `ReplaySettings` reads them).
        axis: the IMU axis that holds ``accel`` when it is 1-D.
        log_time: (n + m,) receive times in s, IMU messages first (default: the stamps); in
            [0, 2**63) ns.
        model, noise_std: for signals simulated, the vehicle model (`vehicle.Jackal`,
            `vehicle.HalfCar`) and the accelerometer noise sd (m/s^2) they were simulated
            with, recorded in the bag's metadata (`SIMULATION_KEYS`), each where given: the
            replay refuses an emulator made for another vehicle (`control.replay_bag`).
        gravity: write the accelerations as an IMU that reports gravity does (a
            sensor_msgs/Imu's specific force, REP-145): +9.80665 m/s^2 added to ``axis``, the
            axis that points up at rest, for ``accel`` free of gravity (the simulator's). False
            (default): as given. The replay's static-level check (``static_mps2``) needs it.

    Returns:
        the bag folder.
    """
    _check_topic_names(imu_topic, odom_topic, written=True)
    _check_distinct(imu_topic, odom_topic, ControlError)
    record = simulation_record(model, noise_std)
    custom = {SIMULATION_KEYS[name]: text for name, text in record.items()}
    if record:
        custom[SIMULATION_SHA256] = simulation_checksum(record)
    t_imu, imu, t_odom, odom = sensor_messages(
        imu_time, accel, odom_time, position, speed, axis=axis, gravity=gravity
    )
    if log_time is None:
        log = np.concatenate([t_imu, t_odom])
    else:
        log = stamps_ns("log_time", log_time, limit=MAX_LOG_NS)
    if log.size != t_imu.size + t_odom.size:
        raise ControlError(f"log_time must have length {t_imu.size + t_odom.size}, got {log.size}")
    store = msgs.typestore()
    with open_bag_writer(path, storage, custom) as writer:
        c_imu = writer.add_connection(imu_topic, msgs.IMU_TYPE, typestore=store)
        c_odom = writer.add_connection(odom_topic, msgs.ODOMETRY_TYPE, typestore=store)
        streams = [(c_imu, log[: t_imu.size], imu), (c_odom, log[t_imu.size :], odom)]
        for conn, stamp, data in merge_in_time(streams):
            writer.write(conn, stamp, data)
    return home_path(path)


def write_run_bag(
    result, path: str | os.PathLike, *, gravity: bool = False,
    faults: Sequence[SensorFault] = (), fault_seed: int = 0, **kw,
) -> Path:  # fmt: skip
    """Write the samples of a `control.ClosedLoopResult` (front-axle acceleration on the IMU's
    z axis, position and speed as odometry along x, both at the loop's rate) as a ROS 2 bag;
    keyword arguments as `write_sensor_bag`; ``model`` and ``noise_std`` default to the run's
    (its ``settings``), so that the bag records the vehicle simulated.

    ``gravity`` as `write_sensor_bag`'s. ``faults`` (`control.SensorFault`s, on the run's
    sample times) are applied to what is written, after gravity is added, as a failing IMU
    would record them (a "scale" fault scales gravity too, as a gain error does; a run's
    ``sample_accel`` holds no fault `control.run_closed_loop` injected); ``fault_seed`` seeds
    the "noise" faults. A "time_nan" fault is refused (a bag's stamps are numbers); a "drop"
    fault leaves out the odometry messages of its samples too (a run's samples are one stream).
    """
    t = result.sample_time
    settings = getattr(result, "settings", None) or {}
    for name in ("model", "noise_std"):
        kw.setdefault(name, settings.get(name))
    accel, position, speed = result.sample_accel, result.sample_position, result.sample_speed
    check_gravity(gravity)
    if not (is_integer(fault_seed) and fault_seed >= 0):
        raise ControlError(f"fault_seed must be an integer >= 0, got {fault_seed!r:.60}")
    inject = FaultInjector(faults, np.random.default_rng(fault_seed))
    if any(f.kind == "time_nan" for f in inject.faults):
        raise ControlError("a time_nan fault cannot be written to a bag (its stamps are numbers)")
    if inject.faults:
        up = STANDARD_GRAVITY if gravity else 0.0
        t, position, accel, speed = inject(t, position, np.asarray(accel) + up, speed)
        gravity = False  # (added before the faults)
    return write_sensor_bag(path, t, accel, t, position, speed, gravity=gravity, **kw)
