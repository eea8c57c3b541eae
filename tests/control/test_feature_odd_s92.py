"""control.feature's settings pinned where a mutation run of the module's odd sites (session 92)
changed behaviour without a test failing: the shipped emulators' feature is the default one, a
FeatureSpec is frozen, a rate below 1 Hz is a rate, and the Nyquist tolerance's closed end."""

import dataclasses

import pytest

from control import FeatureSpec, emulator_feature, shipped_emulator
from control.feature import BAND_EDGES_HZ, BAND_QUANTILES


@pytest.mark.parametrize("case", ["A", "B"])
def test_the_shipped_band_emulators_record_the_default_feature(case):
    """FeatureSpec()'s defaults are the feature the shipped band emulators were trained on, field
    for field (a changed default band edge, quantile level, block length or NW would make the
    default BCR compute another feature than its emulator's)."""
    recorded = emulator_feature(shipped_emulator(case, "band"))
    assert (
        recorded.to_dict()
        == FeatureSpec().to_dict()
        == {
            "name": "log_band_power",
            "block_samples": 125,
            "rate_hz": 120.0,
            "bands_hz": [1.5, 4.5, 7.0, 10.0, 14.0, 20.0, 30.0, 45.0, 60.0],
            "taper_nw": 2.0,
            "n_tapers": 3,
            "quantiles": [0.9, 0.98],
        }
    )
    assert BAND_EDGES_HZ == (1.5, 4.5, 7.0, 10.0, 14.0, 20.0, 30.0, 45.0, 60.0)
    assert BAND_QUANTILES == (0.9, 0.98)


def test_a_feature_spec_is_frozen_and_hashable():
    spec = FeatureSpec()
    with pytest.raises(dataclasses.FrozenInstanceError):
        spec.block_samples = 250  # type: ignore[misc]
    assert hash(spec) == hash(FeatureSpec())


@pytest.mark.parametrize("rate", [1.0, 0.5])
def test_a_rate_of_at_most_1_hz_is_taken(rate):
    """rate_hz must be > 0, not > 1: a 1,000-sample window at 0.5 Hz lasts 2,000 s."""
    spec = FeatureSpec(name="log_var", block_samples=1000, rate_hz=rate)
    assert spec.rate_hz == rate
    assert spec.block_s == 1000 / rate


def test_the_top_edge_is_taken_up_to_nyquist_plus_the_tolerance_itself():
    """The top edge may pass Nyquist (60 Hz at 120 Hz) by 1e-9 Hz, that end included."""
    top = 60.0 + 1e-9
    assert FeatureSpec(bands_hz=(1.5, 4.5, top)).bands_hz == (1.5, 4.5, top)
