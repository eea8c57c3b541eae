"""A value just past its bound, or a bound computed an ulp from a round number, reads apart
from the bound in roadgen's messages (``roadgen.errors.distinct_texts``); ordinary messages
keep their six significant digits."""

import math

import numpy as np
import pytest
from hypothesis import example, given
from hypothesis import strategies as st

import roadgen
from roadgen import checks
from roadgen.errors import distinct_texts
from roadgen.profile import ProfileSettings, check_settings

PAST = 20.0 + 1e-9  # 1e-9 past a bound of 20 m
BELOW_09 = 3 * 0.3  # 0.8999999999999999: the length of a 0.9 m road at dx_m = 0.3
SHORT_DX = 0.499999999  # 10 heights span 4.99999999 m, under the periodogram's 5 m
SETTINGS = {"band": (0.1, 1.0), "amplitudes": "deterministic", "waviness": 2.0, "seed": None}


def _settings_lead(lead: float) -> None:
    check_settings(ProfileSettings(**SETTINGS, lead_in_m=lead), 0.5, BELOW_09)


def _short_band() -> None:
    dn = 1.0 / (41 * 0.5)  # harmonic spacing of a 20 m road at 0.5 m
    roadgen.iso8608_profile(20.0, 10.0, 0.5, seed=0, band=(dn * (1 - 2e-9), 1.0))


def _periodogram_reach() -> None:
    road = roadgen.iso8608_profile(9 * SHORT_DX, 10.0, SHORT_DX, seed=0)
    roadgen.estimate_gd(road, method="periodogram")


CASES = {
    "profile lead_in_m": (
        lambda: roadgen.iso8608_profile(0.9, 10.0, 0.3, seed=0, lead_in_m=0.9),
        "lead_in_m=0.9 is out of range: allowed [0, 0.8999999999999999] m",
    ),
    "profile settings.lead_in_m": (
        lambda: _settings_lead(0.9),
        "settings.lead_in_m=0.9 is out of range: allowed [0, 0.8999999999999999] m",
    ),
    "profile length for band": (
        _short_band,
        "needs length_m >= 20.5 m (or use n_min >= 0.04878048780487805 cycles/m)",
    ),
    "track lead_in_m, one segment": (
        lambda: roadgen.track([(20.0, 10.0)], seed=0, dx_m=0.5, lead_in_m=PAST),
        "lead_in_m=20.000000001 is out of range: allowed [0, 20.0] m",
    ),
    "track lead_in_m, rounded length": (
        lambda: roadgen.track([(20.2, 10.0)], seed=0, dx_m=0.5, lead_in_m=PAST),
        "lead_in_m=20.000000001 is out of range: allowed [0, 20.0] m",
    ),
    "track lead_in_m, first blend": (
        lambda: roadgen.track([(20.5, 10.0), (20.0, 10.0)], seed=0, dx_m=0.5, lead_in_m=PAST),
        "lead_in_m=20.000000001 is out of range: allowed [0, 20.0] m",
    ),
    "track blend_m": (
        lambda: roadgen.track([(20.0, 10.0), (20.0, 10.0)], seed=0, dx_m=0.5, blend_m=PAST),
        "blend_m=20.000000001 is out of range: allowed [1.0, 20.0] m",
    ),
    "track segment shorter than 2 dx_m": (
        lambda: roadgen.track([(20.0, 10.0), (1.0 - 1e-9, 10.0)], seed=0, dx_m=0.5),
        "segment 1 is 0.999999999 m long, too short for any blend: shorter than two grid steps "
        "(2 dx_m = 1.0 m)",
    ),
    "band above Nyquist": (
        lambda: checks.band("band", (0.1, 10.0), 0.5 / np.nextafter(0.05, 1.0)),
        "n_max <= 9.999999999999998 cycles/m",
    ),
    "positions": (
        lambda: checks.positions("s", [20.0], 19.9999999),
        "s contains 20.0: allowed positions are [0, 19.9999999] m",
    ),
    "wheel_envelope radius_m": (
        lambda: roadgen.wheel_envelope(roadgen.iso8608_profile(0.9, 10.0, 0.3, seed=0), 0.9),
        "radius_m=0.9 is out of range: allowed (0, 0.8999999999999999] m",
    ),
    "welch waviness": (
        lambda: roadgen.estimate_gd(
            roadgen.iso8608_profile(20.0, 10.0, 0.05, seed=0), method="welch", waviness=3.5 + 1e-9
        ),
        "WELCH_MAX_WAVINESS=3.5, got w=3.500000001:",
    ),
    "periodogram road length": (
        _periodogram_reach,
        "this road (4.99999999 m: harmonics every 0.2000000004 cycles/m) is "
        "0.20000000040000004 cycles/m, more than a factor 2 from n0; scaling it to n0 along the "
        "slope would extrapolate. Use a road of at least 5.0 m",
    ),
    "default fit band, grid too coarse": (
        lambda: roadgen.estimate_gd(roadgen.iso8608_profile(20.0, 10.0, np.nextafter(0.5, 1))),
        "dx_m=0.5000000000000001 m (Nyquist frequency 0.9999999999999998 cycles/m)",
    ),
}


@pytest.mark.parametrize("name", CASES)
def test_value_reads_apart_from_its_bound(name: str) -> None:
    call, text = CASES[name]
    with pytest.raises(roadgen.RoadgenError) as info:
        call()
    assert text in str(info.value)


def test_ordinary_messages_keep_six_digits() -> None:
    with pytest.raises(roadgen.RoadgenError) as info:
        roadgen.iso8608_profile(20.0, 10.0, 0.006, seed=0, lead_in_m=25.0)
    assert "lead_in_m=25.0 is out of range: allowed [0, 19.998] m" in str(info.value)
    with pytest.raises(roadgen.RoadgenError) as info:
        roadgen.track([(20.0, 10.0), (20.0, 10.0)], seed=0, dx_m=0.5, blend_m=25.0)
    assert "blend_m=25 is out of range: allowed [1, 20] m" in str(info.value)


finite = st.floats(allow_nan=False, allow_infinity=False)


@given(finite, finite)
@example(0.0, -0.0)  # equal, yet "0" and "-0": the texts tell the signed zeros apart
def test_distinct_values_read_apart(a: float, b: float) -> None:
    texts = distinct_texts(a, b)
    assert (texts[0] == texts[1]) == (repr(a) == repr(b))
    if f"{a:.6g}" != f"{b:.6g}" or a == b:  # the usual case: six digits, as before
        assert texts == (f"{a:.6g}", f"{b:.6g}")
    else:  # exact: each text reads back as its value
        assert tuple(map(float, texts)) == (a, b)


def test_non_finite_values_print_as_before() -> None:
    assert distinct_texts(math.inf, math.nan, 1.0) == ("inf", "nan", "1")
