"""A Simplex GD_max above what the posterior mean reaches at the top of the emulator's domain."""

import warnings

import numpy as np
import pytest
from _reach_cases import block_emulator

import control
from control.compat import top_reach

FEATURE_SD = 0.5  # one block's feature GD / 100 has this sd: the likelihood's sd is 50 GD


def test_top_reach_is_the_top_less_the_sd_of_the_posterior_cut_there():
    # a normal likelihood of sd 50 about 600, cut at 600: the half-normal's sd 50 (1 - 2/pi)^0.5
    level, sd = top_reach(block_emulator(FEATURE_SD), [1.0, 2.0])
    assert sd == pytest.approx(50 * np.sqrt(1 - 2 / np.pi), rel=0.01)
    assert level == pytest.approx(600 - sd)


def test_a_gd_max_out_of_the_means_reach_warns_naming_the_margin_and_remedy():
    """Simplex(gd_max=599) passed silently: the mean of a posterior cut at 600 never exceeds it
    (on shipped emulator A, ground of GD 800 read 583 at the median, above 590 in 7%)."""
    emu = block_emulator(FEATURE_SD)  # reach: 600 - 30.2 = 569.8
    with pytest.warns(control.ControlWarning, match=r"gd_max = 599 lies above 569,.* about 30 "
                      r"below .* use gd_max <= 569, or risk=alpha"):  # fmt: skip
        control.check_emulator(emu, simplex=control.Simplex(gd_max=599))
    with pytest.warns(control.ControlWarning, match="gd_max = 575 lies above 569"):
        control.check_emulator(emu, simplex=control.Simplex(gd_max=575))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        control.check_emulator(emu, simplex=control.Simplex(gd_max=565))  # within reach
        control.check_emulator(emu, simplex=control.Simplex(gd_max=590, risk=0.1))  # quantile


def test_the_default_band_is_not_computed():
    calls: list = []
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        control.check_emulator(
            block_emulator(FEATURE_SD, calls), simplex=control.Simplex()
        )  # gd_max 350
        control.check_emulator(
            block_emulator(FEATURE_SD, calls), simplex=control.Simplex(gd_max=400)
        )
    assert calls == []  # at or below the domain's middle: no posterior sd can put it out of reach
