"""A robot user's unit slips (session 82 sweep, docs/robot.md "Units"): an emulator whose GD
axis is in m^3 is refused before it drives (it made the default Simplex command its top speed
on rough ground, every estimate ``ok``); the faults that odometry and acceleration in the wrong
unit raise name the likely slip."""

import numpy as np
import pytest
from control_doubles import FakeBlockModel, stream

import control
import gpmsa
import roadgen
import vehicle
from control import BCR, PAPER_WINDOW, EmulatorMismatchError, ObservationModel
from control.observation_model import BlockScatter

EVERY = 42


def _emulator(gd_scale: float):
    """A small emulator of (v, GD) whose GD axis is GD x ``gd_scale`` (1e-6: GDs in m^3)."""
    rng = np.random.default_rng(0)
    v, gd = rng.uniform(0.5, 2.0, 30), rng.uniform(200.0, 600.0, 30)
    data = gpmsa.SimData(x=v, t=gd * gd_scale, y=1e-3 * gd * v, x_names=["v"], t_names=["GD"])
    params = {"betaU": [[2.0], [0.2]], "lamUz": [1.0], "lamWs": [1e5], "lamWOs": [1e5]}
    return gpmsa.Emulator.from_params(data, params)


SCATTER = BlockScatter(speed=np.array([0.5, 2.0]), cov=np.full((2, 1, 1), 0.01))


def test_an_emulator_whose_gd_is_in_m3_is_refused_by_the_bcr_and_check_emulator():
    """Before, the shipped emulator B with its GD axis in m^3 (2e-4 to 6e-4) made a live BCR
    read a 60 m drive (GD 300 then 500) as GD 3e-4 to 5e-4, 152 of 155 updates ``ok``, and the
    default Simplex (band 250-350) commanded 2.0 m/s over the GD-500 half, where the same drive
    read in 1e-6 m^3 commanded 1.0. Now refused, naming the unit, by either method's BCR and by
    check_emulator (the replay's and the closed loop's check)."""
    emu = _emulator(1e-6)
    with pytest.raises(EmulatorMismatchError, match=r"GD domain \[0\.0002.*m\^3.*x 1e6"):
        BCR(ObservationModel(emu, scatter=SCATTER))
    with pytest.raises(EmulatorMismatchError, match=r"GD domain .* lies below 1"):
        BCR(gpmsa.Calibrator(emu), method="window", feature=PAPER_WINDOW)
    with pytest.raises(EmulatorMismatchError, match=r"trained on GDs in m\^3"):
        control.check_emulator(emu)


def test_the_same_emulator_in_1e_6_m3_builds():
    emu = _emulator(1.0)
    assert BCR(ObservationModel(emu, scatter=SCATTER)).gd_range[1] > 500.0
    control.check_emulator(emu)


def _reasons(t, p, a, v):
    bcr = BCR(FakeBlockModel())
    out = []
    for k in range(0, t.size - EVERY + 1, EVERY):
        s = slice(k, k + EVERY)
        est = bcr.update(t[s], p[s], a[s], v[s], now=float(t[k + EVERY - 1]))
        out.append((est.status, est.reason))
    return out


@pytest.mark.parametrize(
    "slip, expected",
    [
        (lambda t, p, a, v: (t, p, a, v * 3.6), "speed in km/h?"),
        (lambda t, p, a, v: (t, p * 1e3, a, v), "position in mm?"),
        (lambda t, p, a, v: (t, p / 1e3, a, v), "position in km, or speed in mm/s?"),
        (lambda t, p, a, v: (t, 60.0 - p, a, v), "a distance remaining (counting down)"),
        (lambda t, p, a, v: (t, p, a, v * 1e3), "speed in mm/s?"),
    ],
)
def test_odometry_in_the_wrong_unit_is_a_fault_that_names_the_slip(slip, expected):
    """Each was a ``sensor_fault`` before too ("odometry disagrees with the speeds", or a speed
    beyond MAX_SPEED_MPS), which named the numbers but not the likely unit."""
    reasons = _reasons(*slip(*stream(lambda x: 400.0 + 0 * x, 1.2, 6.0, seed=3)))
    faults = [r for s, r in reasons if s == "sensor_fault"]
    assert len(faults) >= len(reasons) - 3, reasons
    assert all(expected in r for r in faults), faults


def test_correct_odometry_names_no_slip():
    reasons = _reasons(*stream(lambda x: 400.0 + 0 * x, 1.2, 6.0, seed=3))
    assert {s for s, _ in reasons} <= {"filling", "ok"}, reasons


@pytest.fixture(scope="module")
def drive():
    """6 m of GD 400 at 1.2 m/s, N(0, 1) noise (case B's)."""
    track = roadgen.track([(6.0, 400.0)], seed=2)
    return vehicle.simulate(vehicle.Jackal(), track, 1.2, noise_std=1.0, seed=2)


@pytest.mark.parametrize(
    "gain, expected",
    [(1 / 9.80665, "acceleration in g?"), (100.0, "in cm/s^2?"), (1e3, "in mm/s^2?")],
)
def test_acceleration_in_the_wrong_unit_is_implausible_naming_the_slip(new_bcr, drive, gain,
                                                                       expected):  # fmt: skip
    """In g, cm/s^2 or mm/s^2 the blocks were ``implausible`` before too ("no GD in [200, 600]
    explains the block": latched, the safe side); the reason now says what gain their band
    powers read as and which unit that suggests."""
    bcr = new_bcr("B")
    reasons = []
    for k in range(0, drive.t.size - EVERY + 1, EVERY):
        s = slice(k, k + EVERY)
        est = bcr.update(drive.t[s], drive.position[s], gain * drive.accel_front_measured[s],
                         drive.speed[s])  # fmt: skip
        reasons.append((est.status, est.reason))
    implausible = [r for s, r in reasons if s == "implausible"]
    assert implausible, reasons
    assert all(expected in r for r in implausible), implausible
    assert "ok" not in {s for s, _ in reasons}


def test_a_correct_acceleration_gets_no_unit_clause(new_bcr, drive):
    bcr = new_bcr("B")
    for k in range(0, drive.t.size - EVERY + 1, EVERY):
        s = slice(k, k + EVERY)
        est = bcr.update(drive.t[s], drive.position[s], drive.accel_front_measured[s],
                         drive.speed[s])  # fmt: skip
        assert "band powers read as" not in est.reason
        assert est.status in ("filling", "ok", "out_of_domain"), est.reason
