"""A robotics engineer's recordings (session 70): an IMU that reads gravity tells the replay
which way is up. An axis that points down, gravity along another axis, a tilted mount, and
gravity kept with an emulator whose sensor checks expect it removed each changed the
estimates or the statuses without a word; now each is a `ControlWarning` (and a note in
the replay's summary) naming the remedy (docs/robot.md, "Which axis, and gravity")."""

import warnings

import numpy as np
import pytest

pytest.importorskip("rosbags")  # the robot extra: the bags are written and replayed
pytest.importorskip("mcap")

import control  # noqa: E402
import roadgen  # noqa: E402
import vehicle  # noqa: E402
from control.robot import replay_bag, write_sensor_bag  # noqa: E402

G = 9.81


@pytest.fixture(scope="module")
def drive():
    """7 s at 1.5 m/s over GD 400 with the emulator B's N(0, 1) noise: (t, a, p, s, a_clean)."""
    trace = vehicle.simulate(
        vehicle.Jackal(), roadgen.track([(12, 400)], seed=2), 1.5, noise_std=1.0, seed=2
    )
    return trace.t + 1.0, trace.accel_front_measured, trace.position, trace.speed, trace.accel_front


def _bag(tmp_path, drive, accel3):
    t, _, p, s, _ = drive
    return write_sensor_bag(tmp_path / "bag", t, accel3, t, p, s)


def _xyz(up, tilt_deg=0.0):
    """(n, 3) accelerations of an IMU with ``up`` along a z axis rolled by ``tilt_deg``."""
    th = np.deg2rad(tilt_deg)
    side = 0.2 * np.random.default_rng(0).normal(size=up.size)
    return np.stack([0.1 * side, np.cos(th) * side - np.sin(th) * up,
                     np.sin(th) * side + np.cos(th) * up], axis=1)  # fmt: skip


@pytest.fixture
def replay(emulator_a, likelihood_a, emulator_b, likelihood_b):
    """replay(bag, "A" or "B", **settings) -> (ReplayResult, the ControlWarnings' texts)."""
    prepared = {"A": (emulator_a, likelihood_a), "B": (emulator_b, likelihood_b)}

    def run(bag, case, **kw):
        emulator, likelihood = prepared[case]
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            r = replay_bag(bag, emulator, likelihood=likelihood, **kw)
        said = [str(w.message) for w in caught if issubclass(w.category, control.ControlWarning)]
        return r, said

    return run


def test_an_imu_with_gravity_along_the_axis_up_replays_without_a_warning(tmp_path, drive, replay):
    _, a, *_ = drive
    r, said = replay(_bag(tmp_path, drive, _xyz(a + G)), "B")
    assert said == []
    assert not any("gravity" in n for n in r.notes)


def test_an_axis_that_points_down_names_imu_sign(tmp_path, drive, replay):
    # Before: a z-down IMU (NED, or mounted upside down) replayed with imu_sign +1 gave on
    # 40 s of GD 300 / 500 7 `implausible` updates and estimates up to 112 off, no word.
    _, a, *_ = drive
    bag = _bag(tmp_path, drive, _xyz(-(a + G)))
    r, said = replay(bag, "B")
    assert len(said) == 1 and "points down" in said[0] and "imu_sign=-1" in said[0], said
    assert said[0] in r.notes and said[0] in r.describe()
    fixed, said = replay(bag, "B", imu_sign=-1)
    assert said == []


def test_gravity_along_another_axis_names_it(tmp_path, drive, replay):
    # Before: every update `sensor_fault` (the x axis holds no vertical motion), no hint
    _, a, *_ = drive
    r, said = replay(_bag(tmp_path, drive, _xyz(a + G)), "B", imu_axis="x")
    assert len(said) == 1 and "imu_axis='z'" in said[0], said


def test_a_tilted_mount_says_it_reads_the_ground_smoother(tmp_path, drive, replay):
    # Before: a 30 degree roll read 40 s of GD 300 / 500 as 285 on average (388 level), no word
    _, a, *_ = drive
    r, said = replay(_bag(tmp_path, drive, _xyz(a + G, tilt_deg=30.0)), "B")
    assert len(said) == 1 and "30 degrees" in said[0] and "smoother" in said[0], said
    _, said = replay(_bag(tmp_path / "5", drive, _xyz(a + G, tilt_deg=5.0)), "B")
    assert said == []  # within the few per cent of scale the docs allow


def test_gravity_kept_with_a_noise_free_emulator_names_highpass(tmp_path, drive, replay):
    # Before: 55 of 113 updates `sensor_fault` ("dead sensor", "quantised signal"), no word of
    # gravity; the docs' remedy is gravity="highpass"
    *_, clean = drive
    bag = _bag(tmp_path, drive, _xyz(clean + G))
    r, said = replay(bag, "A")
    assert len(said) == 1 and "gravity='highpass'" in said[0], said
    _, said = replay(bag, "A", gravity="highpass")
    assert said == []
