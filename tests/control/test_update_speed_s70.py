"""The shortcuts that make BCR.update faster keep its answers to the last bit (session 70).

Two shortcuts: the level-jump check first bounds every segment's ratio in O(n) and computes
the O(n^2) ratios only where the bound may reach the limit (`sensor_checks._level_within`);
the block likelihood remembers the last speed's mean table row, inverse factor and
log-determinant (`ObservationModel._speed_terms`), which a steady speed command reuses.
"""

import copy
import pickle

import numpy as np
import pytest

from control import sensor_checks
from control.observation_model import ObservationModel
from control.sensor_checks import SensorLimits, _centred_sums, _level_jump, _level_within


def _blocks(n_blocks: int, seed: int = 70):
    """Blocks of noise with gains that drop (by up to 300x, anywhere), flights, offsets and
    scales from 1e-6 to 1e4."""
    rng = np.random.default_rng(seed)
    for k in range(n_blocks):
        n = int(rng.choice([64, 125, 200]))
        a = rng.standard_normal(n) * 10 ** rng.uniform(-6, 4)
        start = int(rng.integers(0, n - 32))
        if k % 4 == 1:
            a[start : start + int(rng.integers(32, n - start + 1))] *= 10 ** rng.uniform(-2.5, 0)
        elif k % 4 == 2:
            a[start : start + 40] = -9.81 + 1e-9 * rng.standard_normal(a[start : start + 40].size)
        elif k % 4 == 3:
            a[start:] *= 10 ** rng.uniform(-2.5, 0.5)
            a += 1e3 * rng.standard_normal()
        yield a


def test_the_level_bound_never_hides_a_jump():
    held = 0
    for a in _blocks(600):
        s1, s2, _ = _centred_sums(a)
        ratio, _ = _level_jump(s1, s2, 32)
        for limit in (2.0, 50.0, 400.0, 1e4):
            if _level_within(s1, s2, 32, limit):
                held += 1
                assert ratio <= limit, (a.size, limit, ratio)
    assert held > 600  # the shortcut takes most blocks at the usual limits


def test_signal_fault_reads_as_without_the_bound(monkeypatch):
    limits = [SensorLimits(max_level_jump=x, lattice_p=0.0) for x in (3.0, 20.0, 400.0)]
    blocks = list(_blocks(150, seed=71))
    fast = [sensor_checks.signal_fault(a, lim) for a in blocks for lim in limits]
    monkeypatch.setattr(sensor_checks, "_level_within", lambda *args: False)
    exact = [sensor_checks.signal_fault(a, lim) for a in blocks for lim in limits]
    assert fast == exact
    assert sum("level jumps" in r for r in exact) > 20  # some blocks do jump


def _fresh(model: ObservationModel) -> ObservationModel:
    out = copy.copy(model)
    out._last, out._last_speed = None, None
    return out


@pytest.mark.parametrize("case", ["A", "B"])
def test_the_last_speed_is_reused_to_the_last_bit(case, likelihood_a, likelihood_b):
    model = copy.copy(likelihood_a if case == "A" else likelihood_b)
    rng = np.random.default_rng(5)
    lo, hi = model.speed_range
    y0 = model._mean[10, 60]  # a feature the emulator explains
    direction = np.full(model.dim, 2.0)
    for v in (1.0, 1.0, 1.5, 1.5, 1.0, lo, hi, hi):
        y = y0 + 0.1 * rng.standard_normal(model.dim)
        ref = _fresh(model)
        assert np.array_equal(model.loglik(y, v), ref.loglik(y, v))
        assert model.plausibility(y, v) == ref.plausibility(y, v)
        assert model.level_score(y, v, direction) == ref.level_score(y, v, direction)
        assert model._last_speed[0] == v


def test_a_model_pickled_without_the_speed_cache_restores(likelihood_a):
    state = dict(likelihood_a.__dict__)
    state.pop("_last_speed", None)  # as pickled before session 70
    old = object.__new__(ObservationModel)
    old.__dict__.update(state)
    restored = pickle.loads(pickle.dumps(old))
    y = likelihood_a._mean[3, 40]
    assert np.array_equal(restored.loglik(y, 1.2), _fresh(likelihood_a).loglik(y, 1.2))
