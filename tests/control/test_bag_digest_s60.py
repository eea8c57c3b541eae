"""A ROS 2 bag this package writes records the SHA-256 of each topic's messages in its
metadata (``custom_data``), and `read_recording` checks it: a message changed inside a sqlite3
bag, which has no checksums of its own, was read without a word (the replay refused only what
no longer parsed)."""

import sqlite3

import numpy as np
import pytest

pytest.importorskip("rosbags")

from control.errors import BagError  # noqa: E402
from control.robot import read_recording, write_sensor_bag  # noqa: E402
from control.robot.bags import DIGEST_KEY, messages_digest  # noqa: E402

N = 40


def _bag(tmp_path, storage: str):
    t = 1.0 + np.arange(N) / 120.0
    accel = np.random.default_rng(0).normal(size=N)
    return write_sensor_bag(tmp_path / f"bag-{storage}", t, accel, t, 0.5 * (t - 1.0),
                            np.full(N, 0.5), storage=storage)  # fmt: skip


def _db(folder):
    return next(folder.glob("*.db3"))


def _metadata(folder) -> str:
    return (folder / "metadata.yaml").read_text()


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_a_written_bag_records_its_messages_and_reads_back(storage, tmp_path):
    folder = _bag(tmp_path, storage)
    assert DIGEST_KEY in _metadata(folder)
    rec = read_recording(folder)
    assert rec.imu.accel.shape == (N, 3)


def test_a_changed_message_in_a_sqlite3_bag_is_refused(tmp_path):
    """One byte of one IMU message's acceleration changed (it still parses, to another
    number), or one message's receive time: a BagError naming the topic."""
    folder = _bag(tmp_path, "sqlite3")
    clean = read_recording(folder).imu.accel[:, 2].copy()
    con = sqlite3.connect(_db(folder))
    data = con.execute("SELECT data FROM messages WHERE id = 5").fetchone()[0]
    changed = data[:-3] + bytes([data[-3] ^ 0x01]) + data[-2:]
    con.execute("UPDATE messages SET data = ? WHERE id = 5", (changed,))
    con.commit()
    con.close()
    with pytest.raises(BagError, match=r"topic '/imu/data' are not those written"):
        read_recording(folder)
    folder = _bag(tmp_path / "again", "sqlite3")
    con = sqlite3.connect(_db(folder))
    con.execute("UPDATE messages SET timestamp = timestamp + 1 WHERE id = 50")
    con.commit()
    con.close()
    with pytest.raises(BagError, match=r"topic '/odometry/filtered' are not those written"):
        read_recording(folder)
    assert np.array_equal(read_recording(_bag(tmp_path / "third", "sqlite3")).imu.accel[:, 2],
                          clean)  # fmt: skip


def _set_record(folder, value) -> None:
    """Replace (None: remove) the bag's digest record in its metadata.yaml."""
    from ruamel.yaml import YAML

    yaml = YAML(typ="safe")
    meta = yaml.load((folder / "metadata.yaml").read_text())
    custom = meta["rosbag2_bagfile_information"]["custom_data"]
    if value is None:
        del custom[DIGEST_KEY]
    else:
        custom[DIGEST_KEY] = value
    with (folder / "metadata.yaml").open("w") as f:
        yaml.dump(meta, f)


def test_a_bag_without_the_record_reads_and_a_malformed_record_is_refused(tmp_path):
    """Another writer's bag (no record) reads as before; a record that is not the mapping
    this package writes is a damaged metadata.yaml."""
    folder = _bag(tmp_path, "sqlite3")
    _set_record(folder, None)
    assert read_recording(folder).imu.accel.shape == (N, 3)
    for bad in ("not json", '{"/imu/data": "abc"}', "[1, 2]"):
        folder = _bag(tmp_path / bad.replace("/", "_"), "sqlite3")
        _set_record(folder, bad)
        with pytest.raises(BagError, match="custom_data .* is not the record"):
            read_recording(folder)


def test_the_digest_does_not_depend_on_the_order_messages_come_in():
    log, data = [3, 1, 2, 2], [b"c", b"a", b"b2", b"b1"]
    order = [2, 0, 3, 1]
    assert messages_digest(log, data) == messages_digest([log[i] for i in order],
                                                         [data[i] for i in order])  # fmt: skip
    assert messages_digest(log, data) != messages_digest(log, [b"c", b"a", b"b2", b"b0"])


def test_the_array_digest_is_the_pairwise_definition_bit_for_bit():
    """Session 65: `_sorted_digest` hashes one sorted array; the same digest as its definition,
    pair by pair, for ordered, shuffled, tied (time) and repeated messages, empty and one, and
    a time beyond int64 (the definition's own error)."""
    import hashlib
    import struct

    from control.robot.bags import _sorted_digest, _sorted_digest_pairs

    rng = np.random.default_rng(0)
    for n in (0, 1, 2, 50, 4000):
        log = np.sort(rng.integers(-(2**40), 2**62, n)).tolist()
        digests = [hashlib.sha256(rng.bytes(int(k))).digest() for k in rng.integers(0, 9, n)]
        tied = [t // 2**58 for t in log]  # few distinct times: ties broken by the digest
        shuffled = rng.permutation(n)
        for times, data in ((log, digests), (tied, digests),
                            ([log[i] for i in shuffled], [digests[i] for i in shuffled]),
                            (tied + tied, digests + digests)):  # fmt: skip
            assert _sorted_digest(times, data) == _sorted_digest_pairs(times, data)
    with pytest.raises(struct.error):
        _sorted_digest([2**63], [hashlib.sha256(b"").digest()])
