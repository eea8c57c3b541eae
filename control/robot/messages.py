"""The message types of robot recordings: the two the replay reads, the one it writes.

Read: ``sensor_msgs/msg/Imu`` (``linear_acceleration``, m/s^2) and ``nav_msgs/msg/Odometry``
(``pose.pose.position``, m; ``twist.twist.linear``, m/s). Written: ``GD_ESTIMATE_TYPE``, one BCR
estimate with the Simplex's command, a message type of our own whose definition travels inside
every bag and MCAP file we write, comments (units) included (`definition`; Foxglove and rosbags
read it from there; no ROS package needed).

The CDR (ROS 2) forms of Imu and Odometry are decoded and encoded here with numpy, ~50x faster
than a generic deserializer: their numeric fields sit at fixed offsets once the length of the
header's ``frame_id`` (and the odometry's ``child_frame_id``) is known. Anything else (big-endian
data, ROS 1 bags, a layout that does not check out) goes through rosbags' generic deserializer.
"""

from __future__ import annotations

import struct
from collections.abc import Sequence

import numpy as np

from control.errors import ControlError
from control.robot.extra import require

IMU_TYPE = "sensor_msgs/msg/Imu"
ODOMETRY_TYPE = "nav_msgs/msg/Odometry"
FLOAT64_TYPE = "std_msgs/msg/Float64"
GD_ESTIMATE_TYPE = "terrain_gpmsa_msgs/msg/GDEstimate"

#: The definition of GD_ESTIMATE_TYPE (ROS 2 .msg syntax). NaN marks a number the estimate does
#: not have (every number but position, speed and the command unless status is "ok").
GD_ESTIMATE_MSG = """\
# One estimate of the BCR (terrain roughness GD, 1e-6 m^3) and the Simplex's speed command.
std_msgs/Header header   # stamp: time of the newest IMU sample the estimate has seen
string status            # ok, filling, out_of_domain, sensor_fault, implausible, ...
string reason            # why there is no estimate (on an ok one: a note, or "")
string domain_edge       # upper, lower: the data favour that edge of the emulator's GD domain
                         # (the road may lie beyond it); "" for none
float64 position         # m along the path (odometry)
float64 speed            # m/s, the measured (odometry) speed at the header stamp
float64 gd_mean          # posterior mean of GD
float64 gd_sd            # posterior standard deviation of GD
float64 gd_lo            # credible interval of GD (the BCR's interval_kind), lower end
float64 gd_hi            # credible interval of GD, upper end
float64 interval_level   # level of [gd_lo, gd_hi], e.g. 0.9
float64 gd_max           # the Simplex's GD_max
float64 prob_above_gd_max  # P(GD > GD_max)
float64 prob_change      # P(the roughness changed within the BCR's recent_change_m)
float64 command_speed    # m/s, the Simplex's speed command
string mode              # performance or safety
bool safety              # mode == "safety" (a number for plots)
"""

_CDR_LE = b"\x00\x01\x00\x00"
_IMU_TAIL = 8 * (4 + 9 + 3 + 9 + 3 + 9)  # orientation .. linear_acceleration_covariance
_ODOM_TAIL = 8 * (3 + 4 + 36 + 3 + 3 + 36)  # pose with covariance, twist with covariance
UNKNOWN_COVARIANCE = -1.0
"""A covariance's element 0 that marks "no estimate of this quantity" (sensor_msgs/Imu, REP 145)."""
_UNKNOWN = (UNKNOWN_COVARIANCE,) + (0.0,) * 8


class CdrLayoutError(ValueError):
    """Raw data that the fast decoder does not recognise (the caller falls back)."""


def typestore():
    """A rosbags typestore with the ROS 2 standard messages (Humble) and GD_ESTIMATE_TYPE."""
    stores = require("rosbags.typesys", "writing robot bags")
    store = stores.get_typestore(stores.Stores.ROS2_HUMBLE)
    store.register(stores.get_types_from_msg(GD_ESTIMATE_MSG, GD_ESTIMATE_TYPE))
    return store


_MSGDEF_SEPARATOR = "=" * 80 + "\n"


def definition(store, msgtype: str) -> tuple[str, str]:
    """(ros2msg definition text, RIHS01 hash) of ``msgtype`` as a file stores it: rosbags'
    ``generate_msgdef`` (the type's fields, then for each dependency a line of 80 '=' and
    ``MSG: <type>`` with its fields), but GD_ESTIMATE_TYPE's own text keeps the comments of
    GD_ESTIMATE_MSG (its units), as ROS 2's bag writers store a .msg file; comments change
    neither the fields nor the hash."""
    text, _ = store.generate_msgdef(msgtype, ros_version=2)
    if msgtype == GD_ESTIMATE_TYPE:
        _, sep, deps = text.partition(_MSGDEF_SEPARATOR)
        text = GD_ESTIMATE_MSG + sep + deps
    return text, store.hash_rihs01(msgtype)


def _align(n: np.ndarray | int, to: int):
    return (n + to - 1) // to * to


def _groups(raws: Sequence[bytes]):
    """(indices, (m, L) uint8 array) per distinct message length L."""
    lengths = np.fromiter(map(len, raws), dtype=np.int64, count=len(raws))
    sizes = np.unique(lengths)
    for size in sizes:
        idx = np.flatnonzero(lengths == size)
        buf = b"".join(raws if sizes.size == 1 else [raws[i] for i in idx.tolist()])
        yield idx, np.frombuffer(buf, dtype=np.uint8).reshape(idx.size, int(size))


def _u32(rows: np.ndarray, at: int) -> np.ndarray:
    return np.ascontiguousarray(rows[:, at : at + 4]).view("<u4")[:, 0].astype(np.int64)


def _f64(rows: np.ndarray, at: int, n: int) -> np.ndarray:
    return np.ascontiguousarray(rows[:, at : at + 8 * n]).view("<f8")


def _header(rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(stamp ns, end of frame_id within the data) of little-endian CDR rows."""
    if rows.shape[1] < 16 or np.any(rows[:, 0] != 0) or np.any(rows[:, 1] != 1):
        raise CdrLayoutError("not little-endian CDR")
    sec = np.ascontiguousarray(rows[:, 4:8]).view("<i4")[:, 0].astype(np.int64)
    nsec = _u32(rows, 8)
    if np.any(nsec >= 1_000_000_000):
        raise CdrLayoutError("nanosec out of range")
    return sec * 1_000_000_000 + nsec, 12 + _u32(rows, 12)


def decode_imu(raws: Sequence[bytes]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(header stamps (n,) int ns, linear accelerations (n, 3) m/s^2, and (n,) bool: whether
    each message marks its linear acceleration unknown (``linear_acceleration_covariance[0] ==
    -1``, the Imu message's convention for "no estimate of this quantity", REP 145)) of CDR Imu
    messages. Raises `CdrLayoutError` where the data are not little-endian CDR Imu messages."""
    stamp = np.empty(len(raws), dtype=np.int64)
    accel = np.empty((len(raws), 3))
    unknown = np.empty(len(raws), dtype=bool)
    for idx, rows in _groups(raws):
        stamp[idx], end = _header(rows)
        base = 4 + _align(end, 8)
        if np.any(base + _IMU_TAIL != rows.shape[1]):
            raise CdrLayoutError("length does not match an Imu message")
        accel[idx] = _f64(rows, rows.shape[1] - 8 * 12, 3)
        unknown[idx] = _f64(rows, rows.shape[1] - 8 * 9, 1)[:, 0] == UNKNOWN_COVARIANCE
    return stamp, accel, unknown


def decode_odometry(raws: Sequence[bytes]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(header stamps (n,) int ns, positions (n, 3) m, linear velocities (n, 3) m/s) of CDR
    Odometry messages. Raises `CdrLayoutError` where they are not little-endian CDR."""
    n = len(raws)
    stamp, position, velocity = np.empty(n, dtype=np.int64), np.empty((n, 3)), np.empty((n, 3))
    for idx, rows in _groups(raws):
        stamp[idx], end = _header(rows)
        child = _align(end, 4)
        if np.any(child + 4 > rows.shape[1] - 4):
            raise CdrLayoutError("length does not match an Odometry message")
        at = 4 + child[:, None] + np.arange(4)
        size2 = np.ascontiguousarray(np.take_along_axis(rows, at, axis=1)).view("<u4")[:, 0]
        end = child + 4 + size2.astype(np.int64)
        base = 4 + _align(end, 8)
        if np.any(base + _ODOM_TAIL != rows.shape[1]):
            raise CdrLayoutError("length does not match an Odometry message")
        size = rows.shape[1]
        position[idx] = _f64(rows, size - _ODOM_TAIL, 3)
        velocity[idx] = _f64(rows, size - 8 * (3 + 3 + 36), 3)
    return stamp, position, velocity


#: The latest stamp a ROS 2 ``builtin_interfaces/msg/Time`` holds (int32 seconds), ns.
MAX_STAMP_NS = (2**31 - 1) * 1_000_000_000 + 999_999_999


def _cdr_header(stamp_ns: int, frame_id: str) -> bytes:
    if not 0 <= int(stamp_ns) <= MAX_STAMP_NS:
        raise ControlError(
            f"stamp {stamp_ns} ns lies outside a ROS 2 time stamp's range [0, {MAX_STAMP_NS}] ns"
        )
    sec, nsec = divmod(int(stamp_ns), 1_000_000_000)
    name = frame_id.encode() + b"\x00"
    return _CDR_LE + struct.pack("<iII", sec, nsec, len(name)) + name


def _pad(buf: bytes, to: int) -> bytes:
    return buf + b"\x00" * (-(len(buf) - 4) % to)


def encode_imu(stamp_ns: int, accel: Sequence[float], frame_id: str = "imu_link") -> bytes:
    """A CDR ``sensor_msgs/msg/Imu`` holding only a linear acceleration (m/s^2): orientation and
    angular velocity are marked unknown (covariance element 0 = -1, REP 145)."""
    body = struct.pack(
        "<4d9d3d9d3d9d", 0.0, 0.0, 0.0, 1.0, *_UNKNOWN, 0.0, 0.0, 0.0, *_UNKNOWN,
        *map(float, accel), *(0.0,) * 9,
    )  # fmt: skip
    return _pad(_cdr_header(stamp_ns, frame_id), 8) + body


def encode_odometry(
    stamp_ns: int, position: Sequence[float], velocity: Sequence[float],
    frame_id: str = "odom", child_frame_id: str = "base_link",
) -> bytes:  # fmt: skip
    """A CDR ``nav_msgs/msg/Odometry`` with a position (m, in ``frame_id``), an identity
    orientation and a linear velocity (m/s, in ``child_frame_id``); covariances zero."""
    head = _pad(_cdr_header(stamp_ns, frame_id), 4)
    child = child_frame_id.encode() + b"\x00"
    head = _pad(head + struct.pack("<I", len(child)) + child, 8)
    body = struct.pack(
        "<3d4d36d3d3d36d", *map(float, position), 0.0, 0.0, 0.0, 1.0, *(0.0,) * 36,
        *map(float, velocity), 0.0, 0.0, 0.0, *(0.0,) * 36,
    )  # fmt: skip
    return head + body
