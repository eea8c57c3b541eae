"""A robot that is not a Jackal: its own drives at known speed and GD trained into emulators
(`control.training.fit_band_emulator`, `fit_window_emulator`) that the BCR and the loop read,
and the messages that send such a user somewhere they can go (session 80)."""

from types import SimpleNamespace

import numpy as np
import pytest
from scipy import signal

import control
import gpmsa
import roadgen
import vehicle
from control.training import fit_band_emulator, fit_window_emulator
from tests._examples import load_example

SPEEDS = np.repeat([0.6, 0.9, 1.2, 1.5, 1.8], 3)
GDS = np.tile([200.0, 400.0, 600.0], 5)
SAMPLES = 2_000  # two batches of 8 blocks of 125, and the paper's 1,000-sample window
NOISE = 0.3
pytestmark = pytest.mark.filterwarnings("ignore::gpmsa.ConvergenceWarning")  # 40-sweep fits


def drives(seed: int = 0) -> np.ndarray:
    """(15, 2000) stand-ins for a robot's vertical accelerations, gravity removed: road-driven
    resonance whose level grows with GD and speed, plus the IMU's white noise."""
    rng = np.random.default_rng(seed)
    b, a = signal.butter(2, [8.0, 14.0], btype="bandpass", fs=120.0)
    road = signal.lfilter(b, a, rng.standard_normal((SPEEDS.size, SAMPLES)), axis=1)
    level = np.sqrt(GDS * SPEEDS)[:, None] / 5.0
    return level * road + NOISE * rng.standard_normal(road.shape)


def hand_campaign(accel: np.ndarray) -> vehicle.Campaign:
    """The runs as a hand-built `vehicle.Campaign` (what examples/train_emulator.py fits)."""
    f = np.var(accel[:, -1000:], axis=1)
    m = SPEEDS.size
    return vehicle.Campaign(
        v=SPEEDS, gd=GDS, seed=np.arange(m), f_full=f, f_window=f, f_full_noisy=f,
        f_window_noisy=f, status=np.full(m, "ok"), settings={}, accel=accel, accel_measured=accel,
    )  # fmt: skip


def script_args(n_iter: int) -> SimpleNamespace:
    """The example's options, case B, over the runs' speed and GD ranges."""
    return SimpleNamespace(
        n_iter=n_iter, seed=0, n_pc=8, speed_range=(0.6, 1.8), gd_range=(200.0, 600.0),
        block_samples=125, quantiles=[0.9, 0.98], anchor_speeds=[], anchor_runs=0,
        keep_s=SAMPLES / 120.0, n_runs=SPEEDS.size, speed_spacing="uniform", noise_std=NOISE,
    )  # fmt: skip


@pytest.fixture(scope="module")
def band():
    return fit_band_emulator(SPEEDS, GDS, drives(), noise_std=NOISE, n_iter=40, seed=0)


@pytest.fixture(scope="module")
def band_file(band, tmp_path_factory):
    path = tmp_path_factory.mktemp("own") / "own.gpmsa"
    band.save(path)
    return path


def test_the_band_emulator_of_own_runs_is_the_training_scripts_and_the_bcr_reads_it(band):
    """A user with recorded drives had no public way from them to an emulator: the script's
    fit_band takes its argparse namespace and a simulated vehicle; by hand, the metadata the BCR
    needs ('feature', 'block_scatter') were named nowhere in docs/robot.md."""
    accel = drives()
    script = load_example("train_emulator")
    ref = script.fit_band("B", hand_campaign(accel), vehicle.HalfCar(), script_args(40))
    v, gd = np.array([0.7, 1.3, 1.8]), np.array([250.0, 410.0, 590.0])
    assert np.array_equal(band.predict_mean(v, gd), ref.predict_mean(v, gd))
    for key in ("feature", "block_scatter", "noise_std"):
        assert band.metadata[key] == ref.metadata[key]
    assert "vehicle" not in band.metadata  # a real robot has no model to record
    bcr = control.BCR.from_emulator(band)
    assert bcr.settings.method == "changepoint" and bcr.settings.sensor.noise_sd_mps2 == NOISE


def test_the_window_emulator_of_own_runs_is_the_training_scripts():
    accel = drives()
    script = load_example("train_emulator")
    ref = script.fit_window("B", hand_campaign(accel), vehicle.HalfCar(), script_args(40))
    emu = fit_window_emulator(SPEEDS, GDS, accel, noise_std=NOISE, n_iter=40, seed=0)
    v, gd = np.array([0.7, 1.3]), np.array([250.0, 590.0])
    assert np.array_equal(emu.predict_mean(v, gd), ref.predict_mean(v, gd))
    assert emu.metadata["feature"] == ref.metadata["feature"] == control.PAPER_WINDOW.to_dict()
    assert control.BCR.from_emulator(emu, method="window").settings.method == "window"


def test_a_simulated_robot_is_recorded_and_bad_runs_are_named():
    model = vehicle.HalfCar(wheel_radius_m=0.12, max_speed_mps=2.0)
    emu = fit_window_emulator(SPEEDS, GDS, drives(), noise_std=0.0, vehicle=model, n_iter=4)
    assert control.emulator_vehicle(emu) == model and emu.metadata["noise_std"] == 0.0
    with pytest.raises(control.ControlError, match=r"accel must be \(runs, samples\).*shortest"):
        fit_band_emulator(SPEEDS, GDS, drives()[0], noise_std=NOISE)
    with pytest.raises(control.ControlError, match="gd must hold one finite value > 0 per run"):
        fit_band_emulator(SPEEDS, GDS * 0, drives(), noise_std=NOISE)
    with pytest.raises(control.ControlError, match="noise_std must be the accelerometer's"):
        fit_window_emulator(SPEEDS, GDS, drives(), noise_std=None)
    with pytest.raises(control.ControlError, match="vehicle must be None"):
        fit_window_emulator(SPEEDS, GDS, drives(), noise_std=NOISE, vehicle="MyRobot")


def test_missing_records_name_the_public_way_to_write_them(band, band_file):
    """Both messages sent the user to examples/train_emulator.py alone, which drives a
    simulated Jackal: no way for a robot's own drives."""
    bare = gpmsa.load(band_file)
    bare.metadata = {}
    with pytest.raises(control.EmulatorMismatchError, match=r"has no 'feature'.*FeatureSpec"):
        control.BCR.from_emulator(bare)
    bare.metadata = {"feature": band.metadata["feature"]}
    with pytest.raises(control.EmulatorMismatchError, match="no 'block_scatter'.*fit_band_emul"):
        control.BCR.from_emulator(bare)


def test_a_default_model_against_a_recorded_other_vehicle_says_to_pass_model(band, band_file):
    """run_closed_loop(track, emu) for an emulator of a HalfCar listed 16 parameters of the
    default Jackal against it, and never said that model= was left out."""
    emu = gpmsa.load(band_file)
    emu.metadata = {**band.metadata, "vehicle": vehicle.HalfCar().describe()}
    track = roadgen.track([(10, 300)], seed=1)
    with pytest.raises(
        control.EmulatorMismatchError, match=r"^model= was not given.*emulator_vehicle"
    ):
        control.run_closed_loop(track, emu)


def test_a_default_model_without_a_recorded_vehicle_warns_that_a_jackal_drives(band):
    track = roadgen.track([(10, 300)], seed=1)
    with (
        pytest.warns(control.ControlWarning, match="model= was not given.*vehicle.Jackal"),
        pytest.raises(control.ControlError, match="top speed"),
    ):
        control.run_closed_loop(track, band, simplex=control.Simplex(v_max=2.5))
