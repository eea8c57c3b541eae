"""A Simplex with risk=alpha: a GD_max out of the (1 - alpha) quantile's reach at the top of the
emulator's GD domain, or below that quantile at its bottom (safety mode for good)."""

import warnings

import numpy as np
import pytest
from _reach_cases import block_emulator
from scipy import stats

import control
from control.compat import _warn_if_out_of_reach, bottom_quantile, top_quantile_reach


def check(emu, **simplex) -> list[str]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        control.check_emulator(emu, simplex=control.Simplex(**simplex))
    return [str(w.message) for w in caught if issubclass(w.category, control.ControlWarning)]


def test_the_levels_are_the_quantiles_of_one_observations_posterior_cut_at_the_ends():
    # a normal likelihood of sd 50 about 600 (200), cut there: half-normal quantiles
    emu = block_emulator()
    for risk in (0.01, 0.1, 0.5):
        top = 600 - 50 * stats.norm.ppf((1 + risk) / 2)
        assert top_quantile_reach(emu, [1.0, 2.0], risk) == pytest.approx(top, abs=0.2)
        bottom = 200 + 50 * stats.norm.ppf(1 - risk / 2)
        assert bottom_quantile(emu, 1.0, risk) == pytest.approx(bottom, abs=0.2)


def test_a_gd_max_out_of_the_quantiles_reach_warns_naming_the_level_and_the_risk_that_reaches():
    """Simplex(gd_max=599, risk=0.1) passed silently: the 0.9 quantile of a posterior cut at 600
    reads 593.7 on ground there (shipped emulator A: 580.8; on GD 600 and 650 no estimate's 0.9
    quantile exceeded 599)."""
    risk_599 = 2 * stats.norm.cdf(1 / 50) - 1  # P(GD > 599): 0.016
    assert f"{np.floor(risk_599 * 1000) / 1000:.3f}" == "0.015"
    (message,) = check(block_emulator(), gd_max=599, risk=0.1)
    assert message.startswith(
        "Simplex gd_max = 599 lies above 593, the highest GD_max the 0.9 posterior quantile "
        "(risk = 0.1) reliably reaches"
    )
    assert "that quantile of one observation's posterior reads 593.7" in message
    assert message.endswith("use gd_max <= 593, or risk <= 0.015")
    assert check(block_emulator(), gd_max=590, risk=0.1) == []  # within reach
    assert check(block_emulator(), gd_max=599, risk=0.01) == []  # 599.4: a smaller risk reaches


def one_window(emu, **simplex) -> list[str]:
    """The reach check's ControlWarnings for a BCR that estimates from each window alone
    (method "window": the bottom is checked too)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        _warn_if_out_of_reach(emu, control.Simplex(**simplex), one_observation=True)
    return [str(w.message) for w in caught if issubclass(w.category, control.ControlWarning)]


def test_a_gd_max_below_the_quantile_on_the_smoothest_ground_warns():
    """Simplex(gd_max=300, risk=0.01) passed silently: on ground at the domain's lowest GD 200
    one observation's 0.99 quantile reads 328.8, so every estimate there calls for safety mode
    (the shipped window emulators' estimates on GD 200 at 1 m/s: 100% with gd_max 350)."""
    (message,) = one_window(block_emulator(), gd_min=210, gd_max=300, risk=0.01)
    assert message.startswith(
        "Simplex gd_max = 300 lies below 328.8, the 0.99 posterior quantile (risk = 0.01) of "
        "one observation on ground at the emulator's lowest GD 200 at v_safe = 1 m/s"
    )
    assert "the robot may spend much of its drive in safety mode" in message
    # P(GD > 300) = 2 (1 - Phi(2)) = 0.0455: a risk from 0.046 lets the robot go
    assert message.endswith("use gd_max >= 329, or risk >= 0.046")
    assert one_window(block_emulator(), gd_min=210, gd_max=300, risk=0.05) == []
    assert one_window(block_emulator(), gd_max=350, risk=0.01) == []  # the paper's band
    # a BCR that pools (the default methods): the bottom is not checked
    assert check(block_emulator(), gd_min=210, gd_max=300, risk=0.01) == []


def test_both_ends_share_one_prediction_per_speed():
    calls: list = []
    check(block_emulator(calls=calls), gd_max=350, risk=0.1)
    assert calls == [121, 121, 121]  # v_safe, the middle, v_max: each end read from the same
