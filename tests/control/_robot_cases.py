"""Small inputs shared by the robot I/O tests: a short drive's messages, a start from rest, a
closed-loop result that needs no simulation and a ROS 1 bag writer."""

import numpy as np

from control.closed_loop import ClosedLoopResult


def short_drive(n: int = 60):
    """(imu time s, accel m/s^2, odometry time s, position m, speed m/s) of n samples at 120 Hz."""
    t = 1.0 + np.arange(n) / 120.0
    return t, np.random.default_rng(0).normal(size=n), t, 0.5 * (t - 1.0), np.full(n, 0.5)


def start_from_rest(n: int, seed: int = 0) -> tuple[np.ndarray, ...]:
    """(t, position, accel, speed) of ``n`` samples at 120 Hz of a robot getting under way at
    20 m/s^2 to 1 m/s over a road that starts flat (roadgen's lead-in): its first samples read
    an all but constant acceleration (noise-free, case A), then ~4 m/s^2 of ground."""
    t = np.arange(1, n + 1) / 120.0
    speed = np.minimum(20.0 * t, 1.0)
    position = np.cumsum(speed) / 120.0
    accel = np.random.default_rng(seed).normal(0.0, 4.0, n)
    accel[:6] = [1.6e-4, 5.1e-4, 1.07e-3, 2.85e-3, 3.9e-3, 2.63e-3]  # a closed-loop run's start
    return t, position, accel, speed


def small_result(n: int = 240, settings: dict | None = None) -> ClosedLoopResult:
    """A small closed-loop result of n samples (no drive needed to record one)."""
    t = np.arange(n) / 120.0
    te = t[41::42]
    k = te.size
    return ClosedLoopResult(
        time=te, position=0.5 * te, gd_mean=np.full(k, 300.0), gd_lo=np.full(k, 250.0),
        gd_hi=np.full(k, 350.0), gd_true=np.full(k, 300.0), status=np.array(["ok"] * k),
        reason=np.array([""] * k), domain_edge=np.array([""] * k), prob_change=np.zeros(k),
        command=np.ones(k), mode=np.array(["performance"] * k), latency_s=np.zeros(k),
        sample_time=t, sample_position=0.5 * t, sample_speed=np.full(n, 0.5),
        sample_accel=np.random.default_rng(0).normal(size=n), metrics={},
        settings={} if settings is None else settings,
    )  # fmt: skip


def ros1_bag(path, t_ns, accel, position, speed):
    """A ROS 1 bag (rosbags' serialiser, Noetic's messages) stamped at ``t_ns``; a header's
    seconds are a uint32, written as the int32 of the same bits (rosbags' Time is int32)."""
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC)
    T = store.types
    vec, zeros9, zeros36 = T["geometry_msgs/msg/Vector3"], np.zeros(9), np.zeros(36)
    quat = T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0)

    def header(ns, frame):
        sec = ns // 10**9
        sec -= 2**32 if sec >= 2**31 else 0  # uint32 bits as int32
        stamp = T["builtin_interfaces/msg/Time"](sec=sec, nanosec=ns % 10**9)
        return T["std_msgs/msg/Header"](seq=0, stamp=stamp, frame_id=frame)

    with Writer(path) as writer:
        c_imu = writer.add_connection("/imu/data", "sensor_msgs/msg/Imu", typestore=store)
        c_odom = writer.add_connection("/odometry/filtered", "nav_msgs/msg/Odometry",
                                       typestore=store)  # fmt: skip
        for k, ns in enumerate(t_ns.tolist()):
            imu = T["sensor_msgs/msg/Imu"](
                header=header(ns, "imu_link"), orientation=quat, orientation_covariance=zeros9,
                angular_velocity=vec(x=0.0, y=0.0, z=0.0), angular_velocity_covariance=zeros9,
                linear_acceleration=vec(x=0.0, y=0.0, z=float(accel[k])),
                linear_acceleration_covariance=zeros9,
            )  # fmt: skip
            writer.write(c_imu, ns, store.serialize_ros1(imu, "sensor_msgs/msg/Imu"))
            pose = T["geometry_msgs/msg/Pose"](
                position=T["geometry_msgs/msg/Point"](x=float(position[k]), y=0.0, z=0.0),
                orientation=quat,
            )
            twist = T["geometry_msgs/msg/Twist"](
                linear=vec(x=float(speed[k]), y=0.0, z=0.0), angular=vec(x=0.0, y=0.0, z=0.0)
            )
            odom = T["nav_msgs/msg/Odometry"](
                header=header(ns, "odom"), child_frame_id="base_link",
                pose=T["geometry_msgs/msg/PoseWithCovariance"](pose=pose, covariance=zeros36),
                twist=T["geometry_msgs/msg/TwistWithCovariance"](twist=twist, covariance=zeros36),
            )  # fmt: skip
            writer.write(c_odom, ns, store.serialize_ros1(odom, "nav_msgs/msg/Odometry"))
    return path
