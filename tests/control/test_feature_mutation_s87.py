"""control.feature's documented edges, pinned where a mutation run of the module (session 87)
changed behaviour without a test failing: the ranges FeatureSpec accepts at their ends, the
Nyquist check on the top edge, and the read-only quantile ranks that calls share."""

import numpy as np
import pytest

from control import ControlError, FeatureSpec, block_features, window_feature
from control.feature import MAX_BLOCK_SAMPLES, _quantile_ranks, feature_of_variance


def test_block_samples_are_taken_at_both_ends_of_their_range():
    """[16, MAX_BLOCK_SAMPLES] is a closed range (the error message names it so)."""
    assert FeatureSpec(name="log_var", block_samples=16).block_samples == 16
    longest = FeatureSpec(block_samples=MAX_BLOCK_SAMPLES)
    assert longest.block_samples == MAX_BLOCK_SAMPLES == 4096
    a = np.random.default_rng(0).standard_normal(MAX_BLOCK_SAMPLES)
    assert block_features(a, longest).shape == (1, 10)
    with pytest.raises(ControlError, match=r"block_samples must lie in \[16, 4096\]"):
        FeatureSpec(name="log_var", block_samples=MAX_BLOCK_SAMPLES + 1)
    with pytest.raises(ControlError, match=r"block_samples must lie in \[16, 4096\]"):
        FeatureSpec(name="log_var", block_samples=15)


def test_a_top_band_edge_above_nyquist_is_refused_and_named():
    """Only the last edge passes Nyquist (60 Hz at 120 Hz): the band [4.5, 70) still holds bins,
    so the Nyquist check alone refuses it, and its message names that edge."""
    with pytest.raises(ControlError, match=r"bands_hz reach 70 Hz, above the Nyquist frequency 60"):
        FeatureSpec(bands_hz=(1.5, 4.5, 70.0))
    assert FeatureSpec(bands_hz=(1.5, 4.5, 60.0)).dim == 4  # at Nyquist: taken


def test_a_repeated_band_edge_is_refused_as_not_increasing():
    with pytest.raises(ControlError, match="bands_hz must be >= 2 increasing edges"):
        FeatureSpec(bands_hz=(1.5, 4.5, 4.5, 60.0))


def test_taper_nw_lies_in_the_open_range_zero_to_half_the_block():
    for nw in (0.0, 62.5, 100.0):  # 125 / 2 = 62.5 is the open end
        with pytest.raises(ControlError, match=r"taper_nw must lie in \(0, block_samples / 2\)"):
            FeatureSpec(taper_nw=nw, n_tapers=1)
    assert FeatureSpec(taper_nw=62.0, n_tapers=3).taper_nw == 62.0


def test_one_taper_is_taken_whatever_nw():
    """n_tapers lies in [1, max(1, int(2 NW) - 1)]: one taper always, 2 NW - 1 at most."""
    a = np.random.default_rng(1).standard_normal((3, 125))
    for nw in (0.5, 2.0):
        spec = FeatureSpec(taper_nw=nw, n_tapers=1)
        assert spec.n_tapers == 1 and np.all(np.isfinite(block_features(a, spec)))
    assert FeatureSpec(taper_nw=2.0, n_tapers=3).n_tapers == 3
    for nw, k in ((0.5, 2), (2.0, 4), (2.0, 0)):
        with pytest.raises(ControlError, match="n_tapers must lie in"):
            FeatureSpec(taper_nw=nw, n_tapers=k)


def test_a_window_of_two_samples_has_a_feature():
    """window_feature takes a window of >= 2 samples: var normalised by T (eq. 5)."""
    assert window_feature(np.array([0.0, 2.0]), "var") == 1.0
    assert window_feature([0.0, 2.0], "log_var") == 0.0
    with pytest.raises(ControlError, match="accel must be 1-D with >= 2 samples"):
        window_feature([1.0], "var")


def test_log_var_is_the_log_of_any_positive_variance_and_nan_of_none():
    """log f for f in (0, 1] too (a smooth road's window), NaN for f <= 0."""
    f = np.array([0.25, 1.0, 4.0, 0.0, -1.0])
    y = feature_of_variance(f, "log_var")
    assert np.array_equal(y[:3], np.log(f[:3])) and np.all(np.isnan(y[3:]))
    assert feature_of_variance(0.25) == np.log(0.25)


def test_the_shared_quantile_ranks_are_read_only():
    """The cached ranks are shared by every call (lru_cache): none of them can be written."""
    for arr in _quantile_ranks(125, (0.9, 0.98)):
        assert not arr.flags.writeable
        with pytest.raises(ValueError, match="read-only"):
            arr[...] = 0
