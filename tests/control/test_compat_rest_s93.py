"""Mutation testing of `control.compat` (session 93, the rest): the reach warnings at the lines
they draw, each read from stand-in posteriors whose sd and quantiles are given exactly."""

from __future__ import annotations

import warnings
from types import SimpleNamespace

import numpy as np
import pytest
from test_compat_mutation_s88 import Post, emulator, predictor, track

from control import EmulatorMismatchError, Simplex
from control.compat import (
    _risk_text,
    _track_road_mismatch,
    _warn_if_out_of_reach,
    check_likelihood,
)


def _warnings(monkeypatch, posts, simplex, one_observation=False) -> list[str]:
    """The messages `_warn_if_out_of_reach` warns with, reading ``posts`` as the posteriors."""
    monkeypatch.setattr("control.compat.one_observation_posteriors",
                        lambda emu, speeds, ends=("top",): posts)  # fmt: skip
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        _warn_if_out_of_reach(emulator(predict=predictor()), simplex, one_observation)
    return [str(w.message) for w in seen]


def test_a_gd_max_at_the_mean_reach_is_within_reach_and_one_above_is_not(monkeypatch):
    # risk=None: the reach is the top 600 less the largest sd 20, 580; the warning starts above
    posts = {"top": [Post(10.0, 0.0), Post(20.0, 0.0), Post(5.0, 0.0)]}
    assert _warnings(monkeypatch, posts, Simplex(gd_min=300, gd_max=580.0)) == []
    (text,) = _warnings(monkeypatch, posts, Simplex(gd_min=300, gd_max=580.5))
    assert text.startswith("Simplex gd_max = 580.5 lies above 580, the highest GD_max")


def test_a_gd_max_at_the_bottom_quantile_is_named_as_the_remedy(monkeypatch):
    # method "window", risk 0.05: the top quantiles' least 540.5 reads as reach 540, and the
    # bottom quantile at v_safe is 540 itself: gd_max = 540 serves both ends
    top = [Post(1, 540.5, 0.2)] * 3
    bottom = [Post(1, 540.0, 0.4), Post(1, 590.0, 0.4), Post(1, 590.0, 0.4)]
    simplex = Simplex(gd_min=300, gd_max=550.0, risk=0.05)
    (text,) = _warnings(monkeypatch, {"top": top, "bottom": bottom}, simplex, True)
    assert "lies above 540, the highest GD_max" in text
    assert text.endswith("; use gd_max <= 540")  # risks: at least 0.4 and at most 0.2: none


def test_a_bottom_quantile_above_the_top_reach_names_no_gd_max(monkeypatch):
    # bottom quantile 520.3 at v_safe, rounded up 521: below the top 600 but above the top
    # quantile 500, so no GD_max serves both ends; the bottom's P(GD > gd_max) 0.2 exceeds the
    # top's 0.1, so no risk either
    top = [Post(1, 500.0, 0.1)] * 3
    bottom = [Post(1, 520.3, 0.2), Post(1, 590.0, 0.2), Post(1, 590.0, 0.2)]
    simplex = Simplex(gd_min=300, gd_max=450.0, risk=0.05)
    (text,) = _warnings(monkeypatch, {"top": top, "bottom": bottom}, simplex, True)
    assert text.startswith("Simplex gd_max = 450 lies below 520.3, the ")
    assert text.endswith("; no GD_max or risk serves both ends of this emulator's domain")


def test_the_reach_is_read_at_v_safe_the_middle_speed_and_v_max(monkeypatch):
    # the posteriors at v_safe 0.5, (0.5 + 1.5) / 2 = 1 and v_max 1.5 m/s, in that order
    asked = []

    def posteriors(emu, speeds, ends=("top",)):
        asked.append((tuple(speeds), ends))
        return {end: [Post(1.0, 590.0 if end == "top" else 400.0, 0.5)] * 3 for end in ends}

    monkeypatch.setattr("control.compat.one_observation_posteriors", posteriors)
    emu = emulator(predict=predictor())
    silent = {"gd_min": 300, "gd_max": 500.0, "v_safe": 0.5, "v_max": 1.5}
    _warn_if_out_of_reach(emu, Simplex(**silent))
    _warn_if_out_of_reach(emu, Simplex(**silent, risk=0.05), one_observation=True)
    assert asked == [((0.5, 1.0, 1.5), ("top",)), ((0.5, 1.0, 1.5), ("bottom", "top"))]


def test_a_bottom_quantile_rounding_up_to_the_domains_top_names_no_gd_max(monkeypatch):
    # bottom quantile 599.5 rounds up to 600, the emulator's highest GD: a gd_max there is
    # refused (it must lie below it), so none is named, though the top quantile reads 600
    top = [Post(1, 600.0, 0.1)] * 3
    bottom = [Post(1, 599.5, 0.2)] * 3
    simplex = Simplex(gd_min=300, gd_max=550.0, risk=0.05)
    (text,) = _warnings(monkeypatch, {"top": top, "bottom": bottom}, simplex, True)
    assert text.startswith("Simplex gd_max = 550 lies below 599.5, the ")
    assert text.endswith("; no GD_max or risk serves both ends of this emulator's domain")


def test_a_bottom_quantile_rounding_up_to_the_top_quantile_names_that_gd_max(monkeypatch):
    # bottom quantile 559.2 rounds up to 560, the least top quantile: gd_max = 560 serves both
    top = [Post(1, 560.0, 0.1), Post(1, 575.0, 0.1), Post(1, 580.0, 0.1)]
    bottom = [Post(1, 559.2, 0.2)] * 3
    simplex = Simplex(gd_min=300, gd_max=500.0, risk=0.05)
    (text,) = _warnings(monkeypatch, {"top": top, "bottom": bottom}, simplex, True)
    assert text.startswith("Simplex gd_max = 500 lies below 559.2, the ")
    assert text.endswith("; use gd_max >= 560")


def test_a_risk_that_needs_seven_significant_digits_is_not_offered():
    # low 0.12345661 up: 0.13, 0.124, 0.1235, 0.12346, 0.123457 all exceed high 0.12345679;
    # 0.1234567 (seven digits) would not, but six are the most tried
    assert _risk_text(0.12345661, 0.12345679, True) is None
    assert _risk_text(0.12345661, 0.1234571, True) == "0.123457"  # six serve a wider range


def test_a_likelihood_whose_emulator_predicts_1_5e_12_apart_relative_is_refused():
    # the predictions' relative tolerance is 1e-12: 1.5e-12 apart is another emulator
    emu = emulator(predict=lambda v, gd: np.asarray(gd, dtype=float) / 100.0)
    off = emulator(predict=lambda v, gd: np.asarray(gd, dtype=float) / 100.0 * (1 + 1.5e-12))
    with pytest.raises(EmulatorMismatchError, match="domains or predictions differ"):
        check_likelihood(emu, SimpleNamespace(emulator=off))


@pytest.mark.parametrize(("top", "named"), [(1001.0, False), (999.0, False), (1001.5, True)])
def test_a_band_top_exactly_a_thousandth_off_is_the_same_road(top, named):
    # |1001 - 1000| = 1e-3 * 1000 exactly in floats: within; 1.5 beyond it
    road = {"dx_m": 0.006, "band": [0.01, 1000.0]}
    why = _track_road_mismatch({"road": road}, track(band=(0.01, top)))
    assert why == (f"band up to {top:g} cycles/m against 1000 cycles/m" if named else "")
