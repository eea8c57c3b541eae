"""The end-matched periodogram (psd_slope, estimate_gd's fit) detrends along the last axis:
scipy < 1.16 passes ``periodogram``'s detrend the segments as a 2-D array, whose rows the
straight line took as its ends (a road of 25,001 heights drew a 25,001 x 25,001 array)."""

from __future__ import annotations

import numpy as np

import roadgen
from roadgen.psd import _end_match


def test_each_row_of_a_2d_array_is_end_matched_as_one_road():
    rows = np.random.default_rng(81).normal(size=(3, 40))
    got = _end_match(rows)
    assert got.shape == rows.shape
    for row, one in zip(rows, got, strict=True):
        assert np.array_equal(one, _end_match(row))
        assert one[0] == 0.0 and abs(one[-1]) < 1e-15


def test_a_periodogram_that_passes_rows_gives_the_psd_of_one_road(monkeypatch):
    """scipy < 1.16's call, imitated: the detrend sees the (1, N) segment array (on scipy
    < 1.16 the segment comes as (1, N) already, and the result keeps its shape)."""
    road = roadgen.iso8608_profile(30.0, gd=450, seed=0)
    want = roadgen.psd_slope(road)
    import scipy.signal

    periodogram = scipy.signal.periodogram

    def rows_to_detrend(x, *args, detrend, **kwargs):
        def as_rows(segment):
            return detrend(np.atleast_2d(segment)).reshape(np.shape(segment))

        return periodogram(x, *args, detrend=as_rows, **kwargs)

    monkeypatch.setattr(scipy.signal, "periodogram", rows_to_detrend)
    assert roadgen.psd_slope(road) == want
