"""Predictions at many points go through in blocks of points (bounded (points, m) work arrays)
and give the values of one call at all points up to the BLAS's summation order; the draws' path
keeps one array of means and sums the variances as they come (session 81's memory sweep:
100,000 points of a 1,000-run emulator took 2.35 GB at once)."""

from __future__ import annotations

import numpy as np
import pytest
from _calib_cases import categorical_emulator, road_emulator, vector_emulator, with_draws

import gpmsa
import gpmsa.fitting.emulator as emulator_mod
from gpmsa.fitting.emulator import Emulator, _blocks, _spread_of_means, predict_block_rows


def _mean_basis_emulator() -> Emulator:
    rng = np.random.default_rng(5)
    x, t = rng.random(40), rng.random(40)
    sim = gpmsa.SimData(x[:, None], t[:, None], (2 * x + np.sin(3 * t))[:, None])
    params = {"betaU": [[1.0], [2.0]], "lamUz": [1.0], "lamWs": [1e3], "lamWOs": [1e3]}
    return Emulator.from_params(sim, params, mean_basis="linear")


CASES = {
    "road": lambda: road_emulator(),
    "vector": lambda: vector_emulator(),
    "mean basis": _mean_basis_emulator,
    "categorical": lambda: categorical_emulator(),
}


def _points(emu: Emulator, n: int, seed: int = 0, categorical: bool = False):
    """n points inside the emulator's domain (``categorical``: the last parameter at the
    categorical case's levels 0, 1, 2)."""
    rng = np.random.default_rng(seed)
    dom = emu.domain
    cols = [rng.uniform(*dom[name], n) for name in (*emu.x_names, *emu.t_names)]
    if categorical:
        cols[-1] = rng.integers(0, 3, n).astype(float)
    u = np.column_stack(cols)
    return u[:, : emu.p], u[:, emu.p :]


def _all_predictions(emu: Emulator, x, t) -> list[np.ndarray]:
    out = [*emu.predict(x, t), emu.predict_mean(x, t), *emu.predict(x, t, resid=False)]
    if emu.draws:
        out += [*emu.predict(x, t, draws=True), emu.predict_mean(x, t, draws=True)]
        out += [*emu.predict(x, t, draws=True, n_draws=3, resid=False)]
    return out


def _equal_to_rounding(whole: np.ndarray, blocked: np.ndarray) -> None:
    """Equal up to the BLAS's summation order: a BLAS need not sum a row's dot product in the
    same order in calls of other row counts (OpenBLAS groups rows, and splits them between its
    threads where a block boundary need not fall; MKL without its reproducibility mode), so a
    point's values may differ in the last bits, at the values' scale (equal on this host's
    OpenBLAS, one or more threads, at these sizes)."""
    scale = float(np.max(np.abs(whole))) if whole.size else 0.0
    np.testing.assert_allclose(blocked, whole, rtol=1e-13, atol=1e-13 * scale)


@pytest.mark.parametrize("case", sorted(CASES))
@pytest.mark.parametrize("n", [2, 3, 129, 130, 131])
def test_blocks_give_the_whole_calls_values(monkeypatch, case, n):
    emu = with_draws(CASES[case](), n=4)
    x, t = _points(emu, n, categorical=case == "categorical")
    monkeypatch.setattr(emulator_mod, "PREDICT_BLOCK_VALUES", 10**15)  # one block
    whole = _all_predictions(emu, x, t)
    monkeypatch.setattr(emulator_mod, "PREDICT_BLOCK_VALUES", 1)  # 64 points a block
    assert predict_block_rows(emu.m) == 64
    blocked = _all_predictions(emu, x, t)
    assert len(whole) == len(blocked)
    for a, b in zip(whole, blocked, strict=True):
        _equal_to_rounding(a, b)


def test_many_points_are_predicted_in_blocks(monkeypatch):
    emu = road_emulator()
    seen = []
    block = Emulator._predict_block

    def spy(self, z, *args, **kw):
        seen.append(z.shape[0])
        return block(self, z, *args, **kw)

    monkeypatch.setattr(Emulator, "_predict_block", spy)
    rows = predict_block_rows(emu.m)
    assert rows == emulator_mod.PREDICT_BLOCK_VALUES // emu.m // 64 * 64 == 10_560
    x, t = _points(emu, 2 * rows + 1)
    emu.predict_mean(x, t)
    assert seen == [rows, rows + 1]  # a last block of one point joins the one before
    seen.clear()
    emu.predict(x[:rows], t[:rows])
    assert seen == [rows]


def test_block_rows_are_multiples_of_64_and_at_least_64():
    for m in (1, 5, 198, 1000, 3000, 40_000, 10**7):
        rows = predict_block_rows(m)
        assert rows >= 64 and rows % 64 == 0
        assert rows * m <= emulator_mod.PREDICT_BLOCK_VALUES or rows == 64


def test_blocks_cover_every_point_once_and_never_leave_one_alone():
    for n in range(1, 40):
        for rows in (2, 3, 5, 64):
            parts = list(_blocks(n, rows))
            assert np.array_equal(np.concatenate([np.arange(n)[p] for p in parts]), np.arange(n))
            assert all(p.stop - p.start >= 2 for p in parts) or n == 1


@pytest.mark.parametrize("shape", [(1, 1, 1), (7, 1, 1), (50, 9, 1), (30, 11, 3), (200, 5, 2)])
def test_spread_of_means_is_numpys_var_to_the_last_bit(monkeypatch, shape):
    # numpy alone (no BLAS): its sum over an outer axis adds the draws one after another
    rng = np.random.default_rng(1)
    means = rng.standard_normal(shape) * 10.0 ** rng.integers(-6, 6, shape)
    monkeypatch.setattr(emulator_mod, "PREDICT_BLOCK_VALUES", 1)  # blocks of 2-3 points
    np.testing.assert_array_equal(_spread_of_means(means), means.var(axis=0))


def test_the_memory_check_counts_one_block_and_the_draws_means(monkeypatch):
    emu = with_draws(road_emulator(), n=4)
    block_bytes = 8.0 * 4 * predict_block_rows(emu.m) * emu.m  # one block's work arrays
    monkeypatch.setattr(gpmsa.limits, "MAX_MEMORY_BYTES", 1.5 * block_bytes)
    n = 20 * predict_block_rows(emu.m)  # 20 blocks: the whole at once would be refused
    emu._check_predict_memory(np.zeros((n, 1)), np.zeros((n, 1)))
    with pytest.raises(gpmsa.ResourceLimitError, match=r"predict\(\) at .* points .*, 4000 draws"):
        emu._check_predict_memory(np.zeros((n, 1)), np.zeros((n, 1)), 4000)
