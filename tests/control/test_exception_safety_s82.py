"""Exception safety of control's running objects (session 82): a call that raises part way (an
error of the model's, a KeyboardInterrupt) leaves a BCR and a FaultInjector as they were, so
that the same samples fed again continue as a twin fed only the good calls, bit for bit; a bag
writer refuses a bad message before rosbags takes it in (the bag then stays closeable)."""

import numpy as np
import pytest
from control_doubles import bcr_of, stream

import control
from control.feature import STANDARD_GRAVITY
from control.robot import messages as msgs
from control.robot.bags import open_bag_writer, read_recording, sensor_messages

CHUNK = 50
PARTS = stream(lambda s: np.where(s < 15.0, 300.0, 600.0), 1.5, 22.0, seed=1)


class _Stop(KeyboardInterrupt):
    """The interrupt of a test: raised once by `_raise_once`."""


def _raise_once(monkeypatch, owner, name: str) -> None:
    """``owner.name`` raises `_Stop` at its first call, then works as before."""
    original = getattr(owner, name)
    calls = []

    def once(*args, **kwargs):
        if not calls:
            calls.append(1)
            raise _Stop
        return original(*args, **kwargs)

    monkeypatch.setattr(owner, name, once)


def _numbers(e: control.Estimate) -> tuple:
    return (e.status, e.reason, e.gd_mean, e.gd_sd, e.interval, e.prob_change, e.time,
            e.position, e.data_time)  # fmt: skip


def _chunks(kind: str):
    t, p, a, v = PARTS
    a = a + STANDARD_GRAVITY if kind == "static span" else a
    return [(t[k : k + CHUNK], p[k : k + CHUNK], a[k : k + CHUNK], v[k : k + CHUNK])
            for k in range(0, t.size, CHUNK)]  # fmt: skip


CASES = [
    ("changepoint", "loglik", 9),  # the filter's likelihood: the ring buffers grew before it
    ("changepoint", "plausibility", 9),
    ("changepoint", "level_score", 20),  # after the distance moved, before the filter steps
    ("static span", "loglik", 9),
    ("window", "log_likelihood_grid", 21),  # the window's first estimate
    ("filter", "log_likelihood_grid", 26),  # a tracker predicted before it
    ("tempered", "log_likelihood_grid", 26),
]


@pytest.mark.parametrize(("kind", "where", "at"), CASES, ids=[f"{k}-{w}" for k, w, _ in CASES])
def test_an_update_that_raises_part_way_leaves_the_bcr_as_it_was(monkeypatch, kind, where, at):
    """Before: the samples stayed in the buffers, the distance and counters moved, so that the
    same chunk fed again read as repeated stamps ("sensor_fault") and the estimates after it
    differed from the twin's (changepoint: GD 293.39 -> a fault at the window's first estimate;
    filter: its tracker predicted twice)."""
    bcr, twin = bcr_of(kind), bcr_of(kind)
    chunks = _chunks(kind)
    for part in chunks[:at]:
        assert _numbers(bcr.update(*part)) == _numbers(twin.update(*part))
    with monkeypatch.context() as patch:
        _raise_once(patch, bcr.model, where)
        while True:  # the first call from ``at`` on that reaches ``where``
            try:
                bcr.update(*chunks[at])
            except _Stop:
                break
            twin.update(*chunks[at])
            at += 1
    if kind == "static span":  # its ring holds the samples before the call (the span's, had
        # fewer samples come next), not the call's
        for got, want in zip(bcr._span.state(), twin._span.state(), strict=True):
            np.testing.assert_array_equal(got, want)
    got = [_numbers(bcr.update(*part)) for part in chunks[at:]]
    want = [_numbers(twin.update(*part)) for part in chunks[at:]]
    assert got == want
    assert sum(g[0] == "ok" for g in got) >= 5  # estimates to compare, not faults alone
    assert bcr._n_updates == twin._n_updates


def test_an_interrupted_resume_leaves_the_bcr_as_it_was(monkeypatch):
    bcr, twin = bcr_of("changepoint"), bcr_of("changepoint")
    chunks = _chunks("changepoint")
    for part in chunks[:12]:
        bcr.update(*part), twin.update(*part)
    with monkeypatch.context() as patch:
        _raise_once(patch, bcr._phases[2].filter, "relocate")  # the last phase's
        with pytest.raises(_Stop):
            bcr.resume(3.0)
    bcr.resume(3.0), twin.resume(3.0)
    assert [_numbers(bcr.update(*p)) for p in chunks[12:]] == [
        _numbers(twin.update(*p)) for p in chunks[12:]
    ]


REFUSED = {
    "lengths": lambda t, p, a, v: (t, p, a[:-3], v),
    "2-D": lambda t, p, a, v: (t[:, None], p, a, v),
    "later half text": lambda t, p, a, v: (t, p, [*a[:25], *["x"] * (a.size - 25)], v),
    "float32 stamps": lambda t, p, a, v: ((t + 1e7).astype(np.float32), p, a, v),
}


@pytest.mark.parametrize("bad", REFUSED)
@pytest.mark.parametrize("kind", ["changepoint", "window"])
def test_a_refused_update_changes_nothing(kind, bad):
    bcr, twin = bcr_of(kind), bcr_of(kind)
    chunks = _chunks(kind)
    for part in chunks[:21]:
        bcr.update(*part), twin.update(*part)
    with pytest.raises(control.ControlError):
        bcr.update(*REFUSED[bad](*chunks[21]))
    with pytest.raises(control.ControlError, match="now must be a finite time"):
        bcr.update(*chunks[21], now=float("nan"))
    assert [_numbers(bcr.update(*p)) for p in chunks[21:30]] == [
        _numbers(twin.update(*p)) for p in chunks[21:30]
    ]


def test_an_interrupted_batch_leaves_the_fault_injector_as_it_was(monkeypatch):
    """Before: the spike count had moved on and the noise drawn (the generator advanced), so
    that the batch fed again spiked other samples and drew other noise than the twin's."""
    faults = [control.SensorFault(0.0, 10.0, "spike", 7.0),
              control.SensorFault(0.0, 10.0, "noise", 0.5),
              control.SensorFault(0.5, 0.3, "stuck")]  # fmt: skip
    t = np.arange(1, 241) / 120.0
    batches = [(t[k : k + 40], 0.5 * t[k : k + 40], np.sin(t[k : k + 40]), np.full(40, 0.5))
               for k in range(0, 240, 40)]  # fmt: skip
    injector = control.FaultInjector(faults, np.random.default_rng(3))
    twin = control.FaultInjector(faults, np.random.default_rng(3))
    injector(*batches[0]), twin(*batches[0])
    with monkeypatch.context() as patch:
        _raise_once(patch, control.FaultInjector, "_before")  # the stuck fault, after the others
        with pytest.raises(_Stop):
            injector(*batches[1])
    for batch in batches[1:]:
        for got, want in zip(injector(*batch), twin(*batch), strict=True):
            np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize(
    ("timestamp", "data", "match"),
    [(-5, None, "timestamp must be an integer receive time in \\[0, 2\\*\\*63\\) ns, got -5"),
     (2**70, None, "timestamp must be an integer"),
     (True, None, "timestamp must be an integer"),
     (None, "text", "data must be a message's serialized bytes \\(CDR\\), got str")],
)  # fmt: skip
def test_a_message_refused_mid_write_leaves_the_bag_closeable(tmp_path, timestamp, data, match):
    """Before: rosbags' MCAP writer took a negative or too large time into its chunk's records,
    refused it (OverflowError), then raised again on closing: no bag, every message lost."""
    pytest.importorskip("rosbags")
    t = 1.0 + np.arange(60) / 120.0
    t_imu, imu, t_odom, odom = sensor_messages(t, np.sin(t), t, 0.5 * t, np.full(60, 0.5))
    store = msgs.typestore()
    with open_bag_writer(tmp_path / "bag") as writer:
        c_imu = writer.add_connection("/imu/data", msgs.IMU_TYPE, typestore=store)
        c_odom = writer.add_connection("/odometry/filtered", msgs.ODOMETRY_TYPE, typestore=store)
        for k in range(60):
            if k == 30:
                bad = (int(t_imu[k]) if timestamp is None else timestamp, imu[k] if data is None
                       else data)  # fmt: skip
                with pytest.raises(control.ControlError, match=match):
                    writer.write(c_imu, *bad)
            writer.write(c_imu, int(t_imu[k]), imu[k])
            writer.write(c_odom, int(t_odom[k]), odom[k])
    recording = read_recording(tmp_path / "bag")  # its digests match what was written
    assert recording.imu.stamp_ns.tolist() == t_imu.tolist()
