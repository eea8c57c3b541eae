"""Emulators a user fits with gpmsa.fit (not control.training) and hands to control: inputs,
feature records and unit labels that the BCR cannot read are refused when the emulator is
handed over, naming the difference and the remedy (session 82)."""

import copy
import warnings

import numpy as np
import pytest

import control
import gpmsa
import roadgen
import vehicle
from control import PAPER_WINDOW, EmulatorMismatchError
from control.bcr import BCRSettings
from control.compat import check_simplex
from control.feature import FeatureSpec

RNG = np.random.default_rng(0)
SPEED = RNG.uniform(0.5, 2.0, 14)
GD = RNG.uniform(200.0, 600.0, 14)
LOG_F = np.log(0.05 * GD * SPEED**1.3)  # the paper's window feature of a made-up robot
WINDOW_META = {"feature": PAPER_WINDOW.to_dict(), "noise_std": 0.0}


def own_fit(x, t, y, meta=WINDOW_META, **names):
    """A quick gpmsa.fit of the user's own (20 sweeps, no tuning: ~20 ms)."""
    data = gpmsa.SimData(x=x, t=t, y=y, **names)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.GPMSAWarning)
        return gpmsa.fit(data, n_iter=20, tune=False, seed=0, metadata=meta)


def refused_everywhere(emu, match: str) -> None:
    """BCR.from_emulator (the paper's window method: a gpmsa.Calibrator) and check_emulator
    refuse ``emu`` with a message matching ``match``."""
    with pytest.raises(EmulatorMismatchError, match=match):
        control.BCR.from_emulator(emu, method="window")
    with pytest.raises(EmulatorMismatchError, match=match):
        control.check_emulator(emu)


def test_a_further_input_or_a_categorical_one_is_refused_when_the_emulator_is_handed_over():
    """A window BCR took an emulator of two known inputs (speed and payload), two parameters
    (GD and waviness) or a categorical GD, and failed at its first full window inside the
    robot's loop with gpmsa's "x must have 2 columns" / "level ... never seen in training";
    check_emulator passed them."""
    mass = RNG.uniform(15.0, 30.0, SPEED.size)
    two_x = own_fit(np.c_[SPEED, mass], GD[:, None], LOG_F[:, None], x_names=["v", "mass"])
    refused_everywhere(two_x, r"one known input x, the speed .*x = \['v', 'mass'\]")
    two_t = own_fit(SPEED[:, None], np.c_[GD, mass], LOG_F[:, None], t_names=["GD", "wav"])
    refused_everywhere(two_t, r"t = \['GD', 'wav'\]: fit gpmsa.SimData\(x=speed")
    levels = np.round(GD / 100) * 100
    categorical = own_fit(SPEED[:, None], levels[:, None], LOG_F[:, None], t_names=["GD"],
                          t_categorical=["GD"])  # fmt: skip
    refused_everywhere(categorical, "'GD' is categorical .*fit them as continuous inputs")


def test_gd_fitted_as_x_and_speed_as_t_is_named_as_a_swap():
    """x = GD, t = speed: the BCR built, and every update was out_of_domain (speeds 1-2 m/s
    against a 'speed' domain of [200, 600]); the loop's refusal sent the user to retrain over
    the Simplex's speeds."""
    swapped = own_fit(GD[:, None], SPEED[:, None], LOG_F[:, None], x_names=["GD"], t_names=["v"])
    refused_everywhere(swapped, r"x = 'GD' spans \[2\d\d.*GD fitted as x and the speed as t")
    with pytest.raises(EmulatorMismatchError, match="GD fitted as x"):
        check_simplex(swapped, control.Simplex())  # (the replay's first check)


def test_a_recorded_feature_of_another_length_is_refused_by_every_entry_point(emulator_a):
    """The window feature's record on a band emulator (10 outputs) passed check_emulator and
    BCR.from_emulator (method "filter"), and every update was `implausible`: the robot held
    v_safe for good without a word of why."""
    emu = copy.deepcopy(emulator_a)
    emu.metadata = {**emulator_a.metadata, "feature": PAPER_WINDOW.to_dict()}
    match = r"records the feature 'log_var' of 1 output \(log_var\), but the emulator has 10"
    with pytest.raises(EmulatorMismatchError, match=match):
        control.BCR.from_emulator(emu)
    with pytest.raises(EmulatorMismatchError, match=match):
        control.check_emulator(emu, bcr=control.bcr_settings_for(emu))


def test_a_block_scatter_of_another_length_than_the_feature_is_refused_by_check_emulator():
    """An 8-band feature (no quantiles) with a 10-dimensional scatter: check_emulator passed."""
    bands = FeatureSpec(quantiles=())
    meta = {"feature": bands.to_dict(), "block_scatter": {"cov": np.eye(10)[None].tolist()}}
    emu = own_fit(SPEED[:, None], GD[:, None], np.tile(LOG_F[:, None], (1, 8)), meta=meta)
    with pytest.raises(EmulatorMismatchError, match="block_scatter is 10-dimensional but its"):
        control.check_emulator(emu, bcr=BCRSettings(feature=bands))


def test_unit_labels_that_name_another_unit_or_transform_are_refused():
    """A window emulator fitted on f itself, labelled so, with the feature recorded as log f,
    read GD 500 as 280-380 and GD 300 as 230 (the shipped one: 442 and 346) on the same drive,
    every update `ok`; a speed in km/h or band powers in cm/s^2 passed too."""
    f = own_fit(SPEED[:, None], GD[:, None], np.exp(LOG_F)[:, None], y_units=["(m/s^2)^2"])
    refused_everywhere(f, r"y_units\[0\] = '\(m/s\^2\)\^2' \(log_var\): a power itself")
    kmh = own_fit(3.6 * SPEED[:, None], GD[:, None], LOG_F[:, None], x_units=["km/h"])
    refused_everywhere(kmh, "x_units = 'km/h': the BCR reads the speed .* in m/s")
    cm = own_fit(SPEED[:, None], GD[:, None], LOG_F[:, None] + np.log(1e4),
                 y_units=["log((cm/s^2)^2)"])  # fmt: skip
    refused_everywhere(cm, "an acceleration in another unit than m/s\\^2")
    # the units the BCR reads, spelt otherwise, or none: taken
    for units in ({"y_units": ["log((m/s^2)^2)"], "x_units": ["m/s"]},
                  {"y_units": ["log(m^2 s^-4)"]},
                  {"x_units": ["M / S"], "t_units": ["1e-6 m^3"]}, {}):  # fmt: skip
        emu = own_fit(SPEED[:, None], GD[:, None], LOG_F[:, None], **units)
        control.check_emulator(emu, bcr=BCRSettings(feature=PAPER_WINDOW, method="window"))
        assert control.BCR.from_emulator(emu, method="window").settings.feature == PAPER_WINDOW


def test_the_shipped_emulators_pass_the_new_checks(emulator_a, emulator_b):
    for emu in (emulator_a, emulator_b):
        control.check_emulator(emu, bcr=control.bcr_settings_for(emu), simplex=control.Simplex())
    for case in ("A", "B"):
        window = control.shipped_emulator(case, "window")
        control.check_emulator(window, bcr=control.bcr_settings_for(window, method="window"))


def test_run_closed_loop_names_an_input_fault_without_blaming_the_default_model():
    """With model= left out and a vehicle recorded, the loop wrapped every emulator error of
    check_emulator as the vehicle's: "model= was not given, so ... but the the emulator's GD
    domain [0.0002, 0.0006] lies below 1"."""
    meta = {**WINDOW_META, "vehicle": vehicle.Jackal().describe()}
    in_m3 = own_fit(SPEED[:, None], GD[:, None] * 1e-6, LOG_F[:, None], meta=meta, t_names=["GD"])
    track = roadgen.track([(10, 300)], seed=1)
    with pytest.raises(EmulatorMismatchError, match=r"^the emulator's GD domain \[0.000"):
        control.run_closed_loop(track, in_m3)
