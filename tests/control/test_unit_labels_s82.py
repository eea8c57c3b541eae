"""Unit labels of a user's own gpmsa.fit emulator (``y_units``, ``x_units``) as control reads
them (session 82 review of 68910f0): a label is refused only where it is a known spelling of
another unit or transform than the channel's; a label it does not know is taken.

Before: the labels were matched by substring, so right-unit labels were refused ("g (9.81
m/s^2)" on a quantile in g: "a quantile in an acceleration unit"; "m^2/s^4 (ln)" on log f: "a
power itself"; "analog (m/s^2)^2" and "(m/s^2)^2, not log" on f: "a log power"; "log^2" on
log f: "another unit than m/s^2", from "g^2"), while log10 and dB labels on the natural log feature,
and "km h^-1" as the speed's unit, were taken."""

import re
import warnings

import numpy as np
import pytest

import control
import gpmsa
from control import PAPER_WINDOW, EmulatorMismatchError
from control.observation_model import check_emulator_inputs, output_unit_slip

LOG, POWER, G = "log((m/s^2)^2)", "(m/s^2)^2", "g"  # FeatureSpec.units()' three channels


@pytest.mark.parametrize(
    ("label", "unit"),
    [
        *((lab, LOG) for lab in ("log((m/s^2)^2)", "ln((m/s^2)^2)", "log(m^2/s^4)", "LOG(M^2 S^-4)",
                                 "log (m/s²)²", "ln(m²/s⁴)", "log[(m·s⁻²)²]", "m^2/s^4 (ln)",
                                 "log power", "log var", "log^2", "")),
        *((lab, POWER) for lab in ("(m/s^2)^2", "m^2/s^4", "(m/s²)²", "m²/s⁴", "m² s⁻⁴", "m2/s4",
                                   "(m/s^2)^2, not log", "analog (m/s^2)^2", "variance")),
        *((lab, G) for lab in ("g", "G", "g (9.81 m/s^2)", "g (9.80665 m/s²)", "g0", "signal")),
    ],
)  # fmt: skip
def test_a_label_of_the_channels_own_unit_or_one_not_known_is_taken(label, unit):
    assert output_unit_slip(label, unit) == ""


@pytest.mark.parametrize(
    ("label", "unit", "why"),
    [
        ("(m/s^2)^2", LOG, "a power itself"),
        ("m²/s⁴", LOG, "a power itself"),
        ("m/s^2", LOG, "an acceleration, where the feature is the log of its power"),
        ("log10((m/s^2)^2)", LOG, r"a log10 .*natural log"),
        ("10*log10((m/s^2)^2)", LOG, r"a log10 .*natural log"),
        ("dB", LOG, r"a log10 .*natural log"),
        ("log((cm/s^2)^2)", LOG, r"another unit than m/s\^2"),
        ("log(g^2)", LOG, r"another unit than m/s\^2"),
        ("(gal)^2", LOG, r"another unit than m/s\^2"),
        ("log((m/s^2)^2)", POWER, "a log power"),
        ("dB", POWER, "a log power"),
        ("log var", POWER, "a log power"),
        ("mm^2/s^4", POWER, r"another unit than m/s\^2"),
        ("m/s^2", POWER, "an acceleration, where the feature is its power"),
        ("m/s^2", G, "where the feature's are in g"),
        ("cm/s²", G, "where the feature's are in g"),
        ("log((m/s^2)^2)", G, "where the feature's are in g"),
    ],
)
def test_a_known_spelling_of_another_unit_or_transform_is_refused(label, unit, why):
    assert re.search(why, output_unit_slip(label, unit))


class _Records:
    """The records check_emulator_inputs reads of an emulator (x_units given)."""

    def __init__(self, x_units):
        self.x_names, self.t_names, self.x_units = ["v"], ["GD"], [x_units]
        self.domain = {"v": (0.5, 2.0), "GD": (200.0, 600.0)}


@pytest.mark.parametrize("label", ["km h^-1", "km·h⁻¹", "KM/H", "mph"])
def test_a_speed_label_in_another_unit_is_refused(label):
    with pytest.raises(EmulatorMismatchError, match="x_units = .*in m/s"):
        check_emulator_inputs(_Records(label))


@pytest.mark.parametrize("label", ["m/s", "m s^-1", "m·s⁻¹", "M/S", "meters per second", "mps"])
def test_a_speed_label_in_m_per_s_is_taken(label):
    check_emulator_inputs(_Records(label))


def test_a_right_unit_label_once_refused_is_taken_by_check_emulator_and_the_bcr():
    rng = np.random.default_rng(0)
    speed, gd = rng.uniform(0.5, 2.0, 14), rng.uniform(200.0, 600.0, 14)
    data = gpmsa.SimData(x=speed[:, None], t=gd[:, None], y=np.log(0.05 * gd * speed**1.3)[:, None],
                         y_units=["m^2/s^4 (ln)"])  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.GPMSAWarning)
        emu = gpmsa.fit(data, n_iter=20, tune=False, seed=0,
                        metadata={"feature": PAPER_WINDOW.to_dict(), "noise_std": 0.0})  # fmt: skip
    control.check_emulator(emu)
    assert control.BCR.from_emulator(emu, method="window").settings.feature == PAPER_WINDOW
