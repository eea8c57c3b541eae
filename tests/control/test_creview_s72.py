"""Review of BCR.update's shortcuts (session 72): the unbroken-stream fast path of
`stream_breaks` (`_unbroken`) answers as the full check does for time stamps of any dtype.

Its steps ``t[1:] - t[:-1]`` are taken in the stamps' own dtype, the full check's in float64
(``t - previous``, the previous stamps joined to the float ``t_prev``): integer stamps wrapped
around (int8 [127, -128] steps by +1) and float32 steps rounded into the allowed band read as
unbroken where the full check finds a repeated stamp or a gap.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from control import sensor_checks
from control.sensor_checks import stream_breaks


def _full(monkeypatch, t, rate_hz, t_prev=np.nan):
    """`stream_breaks` of stamps ``t`` (still positions, no accel, 1 m/s) the long way."""
    n = t.size
    with monkeypatch.context() as m:
        m.setattr(sensor_checks, "_unbroken", lambda *args: False)
        return stream_breaks(t, np.zeros(n), np.zeros(n), np.ones(n), t_prev, rate_hz)


def _fast(t, rate_hz, t_prev=np.nan):
    n = t.size
    return stream_breaks(t, np.zeros(n), np.zeros(n), np.ones(n), t_prev, rate_hz)


@pytest.mark.parametrize(
    "t",
    [
        np.array([127, -128], dtype=np.int8),  # wraps to a step of +1
        np.array([2**63 - 1, -(2**63)], dtype=np.int64),
        np.array([2**64 - 1, 0], dtype=np.uint64),
    ],
    ids=["int8", "int64", "uint64"],
)
def test_wrapped_integer_stamps_go_backwards_the_fast_way_too(monkeypatch, t):
    drop, _, found = _full(monkeypatch, t, 1.0)
    assert drop.tolist() == [False, True] and found.backwards == 1
    drop, _, found = _fast(t, 1.0)
    assert drop.tolist() == [False, True] and found.backwards == 1


def test_a_float32_step_rounded_into_the_band_is_a_gap_the_fast_way_too(monkeypatch):
    t = np.array([-1e-10, 1.0], dtype=np.float32)  # float32 step 1.0; exact 1.0000000001
    rate = 1.5 / ((1.0 + (float(t[1]) - float(t[0]))) / 2)  # 1.5 periods between the two
    _, restart, found = _full(monkeypatch, t, rate)
    assert restart.tolist() == [False, True] and found.worst_gap > 0
    _, restart, found = _fast(t, rate)
    assert restart.tolist() == [False, True] and found.worst_gap > 0


DTYPES = [np.int8, np.int16, np.int64, np.uint8, np.uint64, np.float16, np.float32]


@settings(max_examples=200, deadline=None)
@given(data=st.data(), dtype=st.sampled_from(DTYPES), n=st.integers(1, 6))
def test_fast_path_never_hides_what_the_full_check_finds(data, dtype, n):
    base = data.draw(hnp.from_dtype(np.dtype(dtype), allow_nan=False, allow_infinity=False))
    with np.errstate(all="ignore"):  # stamps one apart in their own dtype (wrapping around)
        t = np.array([base], dtype=dtype) + np.arange(n).astype(dtype)
    zeros, ones = np.zeros(n), np.ones(n)
    fast = stream_breaks(t, zeros, zeros, ones, np.nan, 1.0)
    orig = sensor_checks._unbroken
    sensor_checks._unbroken = lambda *args: False  # (no monkeypatch fixture under @given)
    try:
        with np.errstate(all="ignore"):
            full = stream_breaks(t, zeros, zeros, ones, np.nan, 1.0)
    finally:
        sensor_checks._unbroken = orig
    assert fast[2] == full[2], (t, full[2])
    assert np.array_equal(fast[0], full[0]) and np.array_equal(fast[1], full[1])
