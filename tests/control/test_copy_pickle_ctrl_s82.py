"""copy.copy of the control's running objects (session 82): a shallow copy of a BCR shared its
phases' filters, trackers, buffers and static span, and one of a FaultInjector its generator
and held values, so that updating the copy moved the original; bags' message records compared
with ``==`` raised "truth value of an array is ambiguous" and hashing them raised."""

import copy
import pickle

import numpy as np
import pytest
from control_doubles import FakeBlockModel, FakeCalibrator, stream

import control
from control.robot.bags import ImuMessages, OdometryMessages, Recording

EVERY = 42


def _feed(bcr, parts):
    t, p, a, v = parts
    return [bcr.update(t[k : k + EVERY], p[k : k + EVERY], a[k : k + EVERY], v[k : k + EVERY])
            for k in range(0, t.size, EVERY)]  # fmt: skip


def _numbers(estimates):
    return [(e.status, e.gd_mean, e.gd_sd, e.interval, e.prob_change) for e in estimates]


@pytest.mark.parametrize("method", ["changepoint", "window"])
def test_a_shallow_copy_of_a_running_bcr_is_its_own_stream(method):
    """Before: the copy's updates moved the original's filters (changepoint: its next estimate
    after 585 read 300 -> 583) and trackers (window)."""
    parts = stream(lambda s: np.where(s < 15.0, 300.0, 600.0), 1.5, 20.0, seed=1)
    half = parts[0].size // 2
    first, rest = [x[:half] for x in parts], [x[half:] for x in parts]
    if method == "window":
        bcr = control.BCR(FakeCalibrator(), method="window", feature=control.PAPER_WINDOW)
    else:
        bcr = control.BCR(FakeBlockModel())
    _feed(bcr, first)
    untouched, shallow = copy.deepcopy(bcr), copy.copy(bcr)
    assert shallow.model is bcr.model and shallow.settings is bcr.settings  # read-only: shared
    moved = _numbers(_feed(shallow, rest))
    ahead = _numbers(_feed(bcr, rest))
    assert ahead == _numbers(_feed(untouched, rest))  # the original, as if never copied
    assert moved == ahead  # the copy continued as the original does, bit for bit
    if method == "window":
        assert not any(a is b for a, b in zip(shallow.trackers, bcr.trackers, strict=True))
    else:
        pairs = zip(shallow._phases, bcr._phases, strict=True)
        assert not any(a.filter is b.filter for a, b in pairs)


def test_a_shallow_copy_of_a_fault_injector_is_its_own():
    """Before: the copy drew the original's noise and advanced its spike count."""
    faults = [control.SensorFault(0.0, 10.0, "noise", 0.5),
              control.SensorFault(0.0, 10.0, "spike", 7.0),
              control.SensorFault(0.5, 0.2, "stuck")]  # fmt: skip
    t = np.arange(1, 241) / 120.0
    batch = (t, 0.5 * t, np.sin(t), np.full(t.size, 0.5))
    injector = control.FaultInjector(faults, np.random.default_rng(3))
    injector(*[x[:100] for x in batch])
    untouched, shallow = copy.deepcopy(injector), copy.copy(injector)
    rest = [x[100:] for x in batch]
    moved = shallow(*rest)[2]
    ahead = injector(*rest)[2]
    np.testing.assert_array_equal(ahead, untouched(*rest)[2])  # as if never copied
    np.testing.assert_array_equal(moved, ahead)  # the copy continued as the original does


def _recording() -> Recording:
    n = np.arange(4, dtype=np.int64)
    imu = ImuMessages("/imu", n, n, np.ones((4, 3)))
    odom = OdometryMessages("/odom", n, n, np.zeros((4, 3)), np.ones((4, 3)))
    return Recording("run.mcap", "mcap", "", {"/imu": "sensor_msgs/msg/Imu"}, imu, odom, 0.1)


def test_recordings_and_their_messages_compare_by_identity_and_hash():
    """Before: ``==`` on a pickled copy raised ValueError (ambiguous truth value), ``hash``
    TypeError (unhashable dict / ndarray): as the package's other records of arrays
    (ReplayResult, ClosedLoopResult), they compare by identity."""
    rec = _recording()
    back = pickle.loads(pickle.dumps(rec, pickle.HIGHEST_PROTOCOL))
    for a, b in ((rec, back), (rec.imu, back.imu), (rec.odometry, back.odometry)):
        assert a == a and a != b and len({a, b, a}) == 2
    np.testing.assert_array_equal(back.imu.accel, rec.imu.accel)
    assert back.topics == rec.topics
