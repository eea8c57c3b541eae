"""A closed-loop run as an MCAP file to watch in Foxglove (examples/foxglove_layout.json).

The file holds ROS 2 messages (CDR, with their ``ros2msg`` definitions inside), on the topics a
real Jackal's recording and the replay use, so one Foxglove layout serves a simulated run, a
robot's bag and the replay's output, and `control.replay_bag` reads the file back:

| topic | type | rate | holds |
|---|---|---|---|
| ``/imu/data`` | ``sensor_msgs/msg/Imu`` | the loop's (120 Hz) | ``linear_acceleration.z``: the measured front-axle acceleration, m/s^2 |
| ``/odometry/filtered`` | ``nav_msgs/msg/Odometry`` | the loop's | ``pose.pose.position.x``: position along the track, m; ``twist.twist.linear.x``: actual speed, m/s |
| ``/bcr/estimate`` | ``terrain_gpmsa_msgs/msg/GDEstimate`` | one per BCR update | status, reason, the GD domain's edge the data favour, GD mean and credible interval, P(change), the speed command and mode |
| ``/sim/gd_true`` | ``std_msgs/msg/Float64`` | one per BCR update | the GD prescribed at the vehicle's position |

The loop's result keeps no posterior sd nor P(GD > GD_max): those fields are NaN here (the
replay fills them). A Metadata record named ``terrain_gpmsa.simulation``
(`control.robot.bags.SIMULATION_RECORD`) holds the simulated vehicle's ``model.describe()``
(JSON, key "vehicle") and the accelerometer noise sd (m/s^2, key "noise_std"), as the run's
``settings`` give them, so that the replay refuses an emulator made for another vehicle; a
record ``terrain_gpmsa.simulation_sha256`` (`SIMULATION_SHA256`, key "sha256") its SHA-256, so
that a digit changed in it is refused rather than read as another vehicle.
"""  # noqa: E501

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from control.errors import ControlError
from control.robot import messages as msgs
from control.robot.bags import (
    SIMULATION_RECORD,
    SIMULATION_SHA256,
    merge_in_time,
    sensor_messages,
    simulation_checksum,
    simulation_record,
    stamps_ns,
)
from control.robot.extra import require
from control.robot.storage import LIBRARY, check_mcap_target
from control.validation import check_instance, path_argument
from gpmsa.io.atomic import atomic_write

TOPICS = {
    "imu": "/imu/data",
    "odometry": "/odometry/filtered",
    "estimate": "/bcr/estimate",
    "gd_true": "/sim/gd_true",
}


def _estimate_rows(result) -> list[dict]:
    n = result.time.size
    return [
        {
            "stamp_ns": 0,
            "status": str(result.status[i]),
            "reason": str(result.reason[i]),
            "domain_edge": str(result.domain_edge[i]),
            "position_m": float(result.position[i]),
            "speed_mps": float(_speed_at(result, result.time[i])),
            "gd_mean": float(result.gd_mean[i]),
            "gd_sd": np.nan,
            "gd_lo": float(result.gd_lo[i]),
            "gd_hi": float(result.gd_hi[i]),
            "prob_gd_above_max": np.nan,
            "prob_change": float(result.prob_change[i]),
            "command_mps": float(result.command[i]),
            "mode": str(result.mode[i]),
        }
        for i in range(n)
    ]


def _speed_at(result, t: float) -> float:
    if result.sample_time.size == 0:
        return np.nan
    return float(np.interp(t, result.sample_time, result.sample_speed))


def check_can_record() -> None:
    """Raise `MissingExtraError` unless the packages `record_run` needs are installed."""
    require("mcap.writer", "recording a run as MCAP")
    require("rosbags.typesys", "recording a run as MCAP")


def record_run(
    result, path: str | os.PathLike, *, start_ns: int = 0, gravity: bool = False
) -> Path:
    """Write a `control.ClosedLoopResult` as an MCAP file for Foxglove (topics in the module
    docstring).

    Args:
        result: the closed loop's result (`control.run_closed_loop`).
        path: the ``*.mcap`` file to write (an earlier recording of this function there is
            replaced; any other file, an MCAP file another program wrote included, is refused,
            `storage.check_mcap_target`; its folder is made).
        start_ns: the time stamp of the run's time 0, ns, in [0, 2**31 s) (0: the epoch;
            Foxglove shows seconds from the start either way); every header stamp and receive
            time is that much later.
        gravity: write the IMU as one that reports gravity (+9.80665 m/s^2 on its z axis,
            REP-145's specific force; `control.robot.write_sensor_bag`); False (default):
            the simulator's gravity-free acceleration.

    The file records the vehicle model and noise sd the run's ``settings`` hold (``"model"``,
    ``"noise_std"``; `control.run_closed_loop` sets both), each where it is there.

    Returns:
        the path written. Raises `MissingExtraError` without the ``robot`` extra.
    """
    from control.closed_loop import ClosedLoopResult
    from control.robot.replay import estimate_message

    check_instance(result, "result", ClosedLoopResult)
    path = path_argument(path, "path", " of the .mcap file to write")
    check_mcap_target(path, "path")
    writer_mod = require("mcap.writer", "recording a run as MCAP")
    if (isinstance(start_ns, bool) or not isinstance(start_ns, int | np.integer)
            or not 0 <= start_ns <= msgs.MAX_STAMP_NS):  # fmt: skip
        raise ControlError(
            f"start_ns must be an integer in [0, 2**31 s) (a ROS 2 stamp), got {start_ns!r}"
        )
    start_ns = int(start_ns)
    store = msgs.typestore()
    t = result.sample_time
    t_imu, imu, t_odom, odom = sensor_messages(
        t, result.sample_accel, t, result.sample_position, result.sample_speed,
        offset_ns=start_ns, gravity=gravity,
    )  # fmt: skip
    stamps = stamps_ns("the run's update times", result.time, offset_ns=start_ns)
    rows = _estimate_rows(result)
    settings = getattr(result, "settings", None) or {}
    simulated = simulation_record(settings.get("model"), settings.get("noise_std"))
    level = getattr(settings.get("bcr"), "interval_level", np.nan)
    gd_max = getattr(settings.get("simplex"), "gd_max", np.nan)
    estimates = []
    for row, stamp in zip(rows, stamps.tolist(), strict=True):
        row["stamp_ns"] = stamp
        estimates.append(estimate_message(store, row, level, gd_max))
    f64 = store.types[msgs.FLOAT64_TYPE]
    truth = [bytes(store.serialize_cdr(f64(data=float(g)), msgs.FLOAT64_TYPE))
             for g in result.gd_true]  # fmt: skip

    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:  # e.g. a file where a folder of the path should be
        raise ControlError(f"path={str(path)!r}: cannot make its folder ({exc.strerror})") from exc
    with atomic_write(path, error=ControlError) as f:
        writer = writer_mod.Writer(f)
        writer.start(profile="ros2", library=LIBRARY)
        if simulated:
            writer.add_metadata(SIMULATION_RECORD, simulated)
            writer.add_metadata(SIMULATION_SHA256, {"sha256": simulation_checksum(simulated)})
        channels = {}
        for key, msgtype in (
            ("imu", msgs.IMU_TYPE), ("odometry", msgs.ODOMETRY_TYPE),
            ("estimate", msgs.GD_ESTIMATE_TYPE), ("gd_true", msgs.FLOAT64_TYPE),
        ):  # fmt: skip
            definition, _ = msgs.definition(store, msgtype)
            schema = writer.register_schema(msgtype, "ros2msg", definition.encode())
            channels[key] = writer.register_channel(TOPICS[key], "cdr", schema)
        streams = [
            (channels["imu"], t_imu, imu),
            (channels["odometry"], t_odom, odom),
            (channels["estimate"], stamps, estimates),
            (channels["gd_true"], stamps, truth),
        ]
        for seq, (channel, stamp, data) in enumerate(merge_in_time(streams)):
            writer.add_message(channel, log_time=stamp, data=data, publish_time=stamp,
                               sequence=seq)  # fmt: skip
        writer.finish()
    return path
