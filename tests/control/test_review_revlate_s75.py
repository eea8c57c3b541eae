"""Review of session 75's late odometry (`clock.into_gaps`): a clock step back over a stretch
where a message was lost put the stepped message into that gap (a pose from 0.5 s later in the
path: +1 m of path length, every estimate after it moved); the messages left behind one after
another move together or not at all."""

import numpy as np

from control.robot import clock
from control.robot.condition import increasing

P = 0.025  # 40 Hz odometry


def _stamps(n=400):
    return 1.0 + P * np.arange(n)


def test_a_clock_step_back_over_a_lost_message_stays_left_out():
    t = _stamps()
    got = np.where(np.arange(t.size) >= 200, t - 20.5 * P, t)  # 0.51 s back at message 200
    got = np.delete(got, 190)  # message 190 lost: a gap the step's messages overlap
    order = clock.stamp_order(got, 3 * P)
    assert clock.into_gaps(got, order, P) == (order, 0)  # before: 1 moved into the gap


def test_a_burst_and_a_late_message_whose_neighbour_was_lost_still_fill_their_gaps():
    t = _stamps()
    recv = t.copy()
    recv[50:56] = t[70] + 0.001  # six messages delivered together, 15-20 periods late
    recv[200] += 10 * P  # one 10 periods late ...
    arrived = np.argsort(recv, kind="stable")
    arrived = arrived[arrived != 201]  # ... and its neighbour lost
    got = t[arrived]
    order, moved = clock.into_gaps(got, clock.stamp_order(got, 3 * P), P)
    assert moved == 7
    ts = got[order]
    assert increasing(ts).all()
    np.testing.assert_array_equal(ts, np.delete(t, 201))
