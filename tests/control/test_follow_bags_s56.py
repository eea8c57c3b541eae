"""Damaged ROS 2 bags: a metadata.yaml listing a file twice, receive times at int64's ends."""

import sqlite3

import numpy as np
import pytest

pytest.importorskip("rosbags")
pytest.importorskip("mcap")

from test_bag_digest_s60 import _set_record  # noqa: E402

from control.errors import BagError  # noqa: E402
from control.robot import read_recording, replay_bag, write_sensor_bag  # noqa: E402


def _drive(n: int = 2000):
    t = 1.0 + np.arange(n) / 120.0
    return t, np.random.default_rng(1).normal(size=n), t, t - 1.0, np.ones(n)


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_a_file_listed_twice_in_the_metadata_is_a_bag_error_naming_it(tmp_path, storage):
    """Before: every message was read twice (800 IMU messages of 400)."""
    bag = write_sensor_bag(tmp_path / "twice", *_drive(400), storage=storage)
    meta = bag / "metadata.yaml"
    lines = meta.read_text().splitlines()
    i = next(k for k, line in enumerate(lines) if "relative_file_paths" in line)
    lines.insert(i + 2, lines[i + 1])
    meta.write_text("\n".join(lines) + "\n")
    name = lines[i + 1].strip().lstrip("- ")
    with pytest.raises(BagError, match=rf"metadata.yaml is damaged.*{name!r} more than once"):
        read_recording(bag)


@pytest.mark.parametrize("which", ["min", "max"])
def test_a_receive_time_of_minus_2_63_is_a_bag_error_not_wrapped_times(tmp_path, which):
    """Before: imu_ns - t0 wrapped around in int64 and the report counted 1999 backwards
    stamps and a gap of 9.2e9 s."""
    bag = write_sensor_bag(tmp_path / "wrap", *_drive(), storage="sqlite3")
    _set_record(bag, None)  # as another writer's bag: no record of its messages' SHA-256
    con = sqlite3.connect(next(bag.glob("*.db3")))
    imu = next(i for i, name in con.execute("select id, name from topics") if "imu" in name)
    con.execute(
        f"update messages set timestamp = ? where id = (select {which}(id) from messages "
        "where topic_id = ?)",
        (-(2**63), imu),
    )
    con.commit()
    con.close()
    with pytest.raises(BagError, match=r"damaged: the first IMU receive time is "
                       r"-9223372036854775808 ns.*'/imu/data'.*wrap around"):  # fmt: skip
        replay_bag(bag, "A", time_base="log")
