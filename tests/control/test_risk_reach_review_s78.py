"""Review of the Simplex risk check at both ends of the GD domain (`check_emulator`).

The bottom check (the (1 - alpha) quantile of one observation's posterior at the lowest GD, at
v_safe) describes a BCR that estimates from one window alone (method "window"); the default
methods pool (change-point for the band emulators, the filter for the window emulators), and
with them the shipped emulators' closed loop on GD 200 at risk 0.05 spent 7-31% of its updates
in safety mode (A band 7-18%, B band 12-21%, A window 16-31%; risk 0.1, B band: 1-18%), not
"seldom leaving" it, as the warning said. The remedies a message names must silence it."""

import re
import warnings

import numpy as np
import pytest
from _reach_cases import block_emulator

import control
import roadgen
from control.compat import _warn_if_out_of_reach, bcr_settings_for
from control.shipped import shipped_emulator


def said(emu, one_observation: bool, **simplex) -> list[str]:
    """The ControlWarnings of the reach check of ``Simplex(**simplex)``."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        _warn_if_out_of_reach(emu, control.Simplex(**simplex), one_observation)
    return [str(w.message) for w in caught if issubclass(w.category, control.ControlWarning)]


def checked(emu, **kw) -> list[str]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        control.check_emulator(emu, **kw)
    return [str(w.message) for w in caught if issubclass(w.category, control.ControlWarning)]


@pytest.mark.parametrize("case", ["A", "B"])
def test_the_shipped_emulators_with_their_default_bcr_take_risk_005_and_01_silently(case):
    band, window = shipped_emulator(case), shipped_emulator(case, "window")
    for risk in (None, 0.1, 0.05):
        assert checked(band, simplex=control.Simplex(risk=risk)) == []
        assert checked(band, simplex=control.Simplex(risk=risk), bcr=bcr_settings_for(band)) == []
    assert checked(window, simplex=control.Simplex(risk=0.05)) == []


def test_the_bottom_check_stays_for_the_window_method_which_estimates_from_one_window():
    """Method "window", shipped A, risk 0.01, GD 200: 99-100% of the closed loop's updates in
    safety mode; the check warns there, also from run_closed_loop."""
    emu = shipped_emulator("A", "window")
    one = bcr_settings_for(emu, method="window")
    (message,) = checked(emu, simplex=control.Simplex(risk=0.01), bcr=one)
    assert message.startswith("Simplex gd_max = 350 lies below 446.1, the 0.99 posterior")
    track = roadgen.track([(2.0, 300.0)], seed=0)
    with pytest.warns(control.ControlWarning, match="lies below 446.1") as caught:
        control.run_closed_loop(track, emu, seed=0, bcr=one, simplex=control.Simplex(risk=0.01))
    assert all(w.filename == __file__ for w in caught)
    with warnings.catch_warnings():
        warnings.simplefilter("error", control.ControlWarning)  # the default method: silent
        control.run_closed_loop(track, emu, seed=0, simplex=control.Simplex(risk=0.01))


def test_a_tiny_risk_names_its_quantile():
    (message,) = said(block_emulator(), True, gd_max=350, risk=1e-9)
    assert "the 0.999999999 posterior quantile (risk = 1e-09)" in message  # not "the 1"


def remedies(message: str) -> list[tuple[str, float]]:
    """The (field, value) pairs of the message's "use ..." remedies."""
    tail = message.rsplit("; use ", 1)[1]
    found = [re.fullmatch(r"(gd_max|risk) [<>]= ([0-9.e-]+)", part) for part in tail.split(", or ")]
    assert all(found), tail
    return [(m.group(1), float(m.group(2))) for m in found]


@pytest.mark.parametrize(
    "feature_sd, gd_max, risk",
    [
        (3.0, 201.0, 0.01),  # P(GD > 201) at the bottom 0.998: "risk >= 1.00" before
        (10.0, 210.0, 0.1),  # bottom 0.9743, top 0.9763: "risk >= 0.98" tripped the top check
        (3.0, 599.9, 0.001),  # "gd_max <= 599": below the bottom quantile 599.3 at that risk
        (0.5, 300.0, 0.01),
        (0.5, 599.0, 0.1),
    ],
)
def test_each_remedy_named_silences_the_check(feature_sd, gd_max, risk):
    emu = block_emulator(feature_sd)
    settings = {"gd_min": 200.5, "gd_max": gd_max, "risk": risk}
    messages = said(emu, True, **settings)
    assert messages
    for message in messages:
        for field, value in remedies(message):
            assert 0 < value < 1 if field == "risk" else 200 < value < 600
            again = {**settings, field: value}
            assert said(emu, True, **again) == [], (message, field, value)


def test_where_no_gd_max_serves_both_ends_the_message_names_a_risk_only():
    """sd 3, risk 0.001: the bottom quantile 599.3 lies above the top level 599.0."""
    (message,) = said(block_emulator(3.0), True, gd_min=200.5, gd_max=599.9, risk=0.001)
    assert [field for field, _ in remedies(message)] == ["risk"]
    assert np.isfinite(remedies(message)[0][1])
