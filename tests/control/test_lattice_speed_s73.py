"""The sensor checks' faster paths (session 73) give what the long way gives, bit for bit: the
lattice check's hits (flights as NaN, the (values, steps, stretches) layout, small-integer
counts, flat candidates), the clip check's count of near-equal gaps before it forms groups, and
`longest_repeat`'s shortcut for a block without repeats."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.special import bdtrc

from control.sensor_checks import (
    FREE_FALL_MPS2,
    NEAR_EQUAL,
    SensorLimits,
    _in_flight,
    _lattice_stretch,
    _resolution,
    _sorted_runs,
    longest_repeat,
    most_lattice_like,
    signal_fault,
)


def _lattice_long_way(a, stretch, free_fall, resolution):
    """The lattice check as session 72 wrote it: a mask of the flight values, a (steps,
    values, stretches) array, int64 counts, 2-D candidates."""
    if resolution is None or a.size < stretch:
        return 1.0, -1, float("nan")
    ordered = np.sort(a[np.arange(stretch)[:, None] + np.arange(a.size - stretch + 1)], axis=0)
    low = ordered[:-1]
    step = ordered[1:] - low
    usable = step > resolution
    if free_fall is not None:
        flying = _in_flight(ordered, free_fall)
        usable &= ~(flying[:-1] | flying[1:])
    if not usable.any():
        return 1.0, -1, float("nan")
    g = np.where(usable, step, 1.0)
    x = np.subtract(ordered[None], low[:, None])
    x /= g[:, None]
    x -= np.rint(x)
    np.abs(x, out=x)
    x *= g[:, None]
    on = x <= 0.5 * resolution
    if free_fall is not None:
        on &= ~flying[None]
    hits = on.sum(axis=1) - 2
    row, col = np.nonzero(usable & (hits > 0))
    if row.size == 0:
        return 1.0, -1, float("nan")
    chance = np.minimum(1.0, 2.0 * resolution / g[row, col])
    p = bdtrc(hits[row, col] - 1, stretch - 2, chance)
    k = int(np.argmin(p))
    return float(p[k] * (stretch - 1)), int(col[k]), float(step[row[k], col[k]])


def _blocks(rng, count):
    """Blocks that exercise the lattice check: healthy, rounded to ADC steps, short coarse
    quantisations, flights (exact, near and between lattice values), repeats and signed zeros."""
    for k in range(count):
        a = rng.normal(0.0, rng.choice([0.3, 2.0, 6.0]), int(rng.integers(6, 130)))
        kind = k % 6
        if kind == 1:
            a = np.round(a / rng.choice([0.001, 0.02, 0.1])) * 0.02
        elif kind == 2:
            s, n = int(rng.integers(0, max(1, a.size - 8))), int(rng.integers(5, 11))
            step = rng.choice([1.0, 2.6, 4.0])
            a[s : s + n] = np.round(a[s : s + n] / step) * step
        elif kind == 3:
            s = int(rng.integers(0, a.size))
            a[s : s + int(rng.integers(1, 12))] = FREE_FALL_MPS2 + rng.choice([0.0, 1e-8, 0.3])
        elif kind == 4:
            a = np.round(a * 2.0) / 2.0
            a[rng.integers(0, a.size, 3)] = FREE_FALL_MPS2
        elif kind == 5:
            a[rng.integers(0, a.size, 4)] = rng.choice([0.0, -0.0])
        yield a


def _same(x, y) -> bool:
    return repr(x) == repr(y)  # (nan == nan, and 0.0 against -0.0 told apart)


def test_lattice_stretch_gives_the_long_way_answer_bit_for_bit():
    rng = np.random.default_rng(73)
    for a in _blocks(rng, 240):
        r = _resolution(a)
        for stretch in (2, 3, 6, 8):
            for free_fall in (None, FREE_FALL_MPS2):
                want = _lattice_long_way(a, stretch, free_fall, r)
                assert _same(_lattice_stretch(a, stretch, free_fall, r), want), (stretch, a)
                runs = _sorted_runs(a, stretch)  # (the dead check's, shared)
                assert _same(_lattice_stretch(a, stretch, free_fall, r, runs), want)


def test_most_lattice_like_gives_the_long_way_answer_and_flags_what_it_flagged():
    rng = np.random.default_rng(74)
    flagged = 0
    for a in _blocks(rng, 120):
        r = _resolution(a)
        for free_fall in (None, FREE_FALL_MPS2):
            found = [(*_lattice_long_way(a, n, free_fall, r), n) for n in (6, 8)]
            p, start, step, stretch = min(found, key=lambda f: f[0])
            got = most_lattice_like(a, free_fall)
            assert _same(got, (p * 2, start, stretch, step))
            flagged += got[0] < SensorLimits().lattice_p
    assert flagged > 20  # (the quantised blocks)


def test_lattice_counts_hold_a_stretch_beyond_a_small_integer_type():
    a = np.round(np.random.default_rng(5).normal(0.0, 2.0, 300))
    r = _resolution(a)
    assert _same(_lattice_stretch(a, 130, None, r), _lattice_long_way(a, 130, None, r))


def _clip_reason_long_way(a: np.ndarray, max_same: int) -> str:
    """The clip check's reason as session 72 computed it: every group formed."""
    ordered = np.sort(a)
    gaps = ordered[1:] - ordered[:-1]
    tol = NEAR_EQUAL * (float(np.abs(a).max()) or 1.0)
    starts = np.concatenate([[0], np.flatnonzero(gaps > tol) + 1])
    values, counts = ordered[starts], np.diff(np.concatenate([starts, [ordered.size]]))
    if np.count_nonzero(counts > max_same) < 2:
        return ""
    top = np.argsort(counts, kind="stable")[::-1][:2]
    lo, hi = sorted(top, key=lambda i: values[i])
    return (
        f"clipped signal: {counts[lo]} samples at {values[lo]:.4g} m/s^2 and {counts[hi]} at "
        f"{values[hi]:.4g} m/s^2 (allowed {max_same} at two values)"
    )


@pytest.mark.parametrize("max_same", [1, 2, 4])
def test_clip_check_flags_what_every_group_formed_flags(max_same):
    rng = np.random.default_rng(max_same)
    limits = SensorLimits(max_same=max_same, free_fall_mps2=None)
    flagged = passed = 0
    for _ in range(150):
        a = rng.normal(0.0, 3.0, 125)
        for value in rng.normal(0.0, 3.0, int(rng.integers(1, 4))):  # piles, spread out
            at = rng.choice(a.size, int(rng.integers(max_same - 1, max_same + 3)), replace=False)
            a[at] = value + rng.choice([0.0, 1e-7]) * rng.random(at.size)  # near-equal too
        if longest_repeat(a) > limits.max_repeats:
            continue
        want = _clip_reason_long_way(a, max_same)
        got = signal_fault(a, limits)
        if want:
            assert got == want
            flagged += 1
        else:
            assert not got.startswith("clipped signal"), got
            passed += 1
    assert flagged > 10 and passed > 10


def test_longest_repeat_with_and_without_repeats():
    rng = np.random.default_rng(9)
    for _ in range(300):
        a = rng.integers(0, int(rng.integers(2, 50)), int(rng.integers(1, 30))).astype(float)
        want = max(len(list(run)) for _, run in itertools.groupby(a))
        assert longest_repeat(a) == want
    assert longest_repeat(np.arange(10.0)) == 1
    assert longest_repeat(np.array([3.0])) == 1
    assert longest_repeat(np.zeros(0)) == 0
