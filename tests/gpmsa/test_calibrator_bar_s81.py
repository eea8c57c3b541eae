"""``Calibrator(progress=True)``: the bar counts every step of the grid's preparation, the
predictors on the grid and on the refined grid included (they took 87 % of a window
emulator's preparation over 20 draws while the bar stood at 100 %), and ends full."""

import numpy as np
from _calib_cases import sine_sum_emulator

import gpmsa
from gpmsa.calibration import calibrator


def _emulator(q: int):
    """25 runs of one scalar output, q calibration parameters, 40 retained draws."""
    return sine_sum_emulator(q, runs=25, n_iter=40)


def _watch(monkeypatch):
    """The bars the Calibrator makes, and (n, total) of its bar as each predictor is built."""
    bars, seen = [], []
    make_bar, make_predictor = calibrator.progress_bar, calibrator.GridPredictor

    def bar(*args, **kwargs):
        bars.append(make_bar(*args, **kwargs))
        return bars[-1]

    def predictor(gp, nodes, plan):
        seen.append((bars[-1].n, bars[-1].total))
        return make_predictor(gp, nodes, plan)

    monkeypatch.setattr(calibrator, "progress_bar", bar)
    monkeypatch.setattr(calibrator, "GridPredictor", predictor)
    return bars, seen


def test_the_bar_counts_the_predictors_on_both_grids(monkeypatch, capsys):
    bars, seen = _watch(monkeypatch)
    cal = gpmsa.Calibrator(_emulator(1), emulator_params="draws", n_emulator_draws=3, n_grid=33,
                           progress=True)  # fmt: skip
    assert cal._refined is not None  # every set has its Chebyshev plan: a refined grid too
    assert len(bars) == 1 and len(seen) == 6  # 3 sets: the grid's and the refined grid's
    assert all(n < total for n, total in seen), seen  # each built while the bar runs
    assert [n for n, _ in seen] == [3, 4, 5, 6, 7, 8]  # each set's plan counted first
    assert bars[0].n == bars[0].total == 9
    assert "Calibrator: 100%" in capsys.readouterr().err


def test_without_a_refined_grid_the_bar_ends_full(monkeypatch, capsys):
    bars, seen = _watch(monkeypatch)
    cal = gpmsa.Calibrator(_emulator(2), emulator_params="draws", n_emulator_draws=2, n_grid=9,
                           progress=True)  # fmt: skip
    assert cal._refined is None  # two parameters: no refined grid is prepared
    assert seen == [(2, 4), (3, 4)]
    assert bars[0].n == bars[0].total == 4
    assert "Calibrator: 100%" in capsys.readouterr().err


def test_the_bar_changes_no_bit_of_the_calibrator(capsys):
    emu = _emulator(1)
    x = np.array([0.3, 0.7])
    y = emu.predict_mean(x, np.array([0.4, 0.4]))
    got = []
    for progress in (False, True):
        cal = gpmsa.Calibrator(emu, emulator_params="draws", n_emulator_draws=3, n_grid=33,
                               seed=0, progress=progress)  # fmt: skip
        post = cal.update(x, y)
        got.append((post.grids["t0"].density, post.samples["t0"], post.samples["lamOs"]))
    for a, b in zip(*got, strict=True):
        assert np.array_equal(a, b)
