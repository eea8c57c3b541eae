"""A simulation run's value far beyond every other run's (a -999 missing-value code, a failed run)
is named by ``gpmsa.fit`` and ``gpmsa.fit_study`` before sampling (``OutlierRunWarning``); clean
designs, heavy-ish but ordinary outputs and small designs stay silent."""

import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.model.far_values import FAR_RUN_MIN_RUNS, far_run

GRID = np.linspace(0.0, 1.0, 12)


def _design(m: int = 40, seed: int = 0):
    rng = np.random.default_rng(seed)
    x, t = rng.uniform(size=(m, 1)), rng.uniform(size=(m, 1))
    return x, t, np.outer(x[:, 0], np.sin(3 * GRID)) + np.outer(t[:, 0], GRID**2)


def _sim(y, x, t, **kw):
    return gpmsa.SimData(x=x, t=t, y=y, **kw)


def _outlier_warnings(call) -> list[str]:
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        call()
    return [str(w.message) for w in got if issubclass(w.category, gpmsa.OutlierRunWarning)]


def test_one_missing_value_code_in_a_functional_output_is_named_before_sampling():
    x, t, y = _design()
    y[7, 5] = -999.0
    data = _sim(y, x, t, index=GRID, index_names="time", index_units="s")
    got = _outlier_warnings(lambda: gpmsa.fit(data, n_iter=10, seed=0, tune_rounds=2))
    assert len(got) == 1
    assert got[0].startswith(
        "simulation run 7 (y[7]) holds -999 at time 0.454545 s, 900 times the other runs' range "
        "there ([0.0449683, 1.15452]) below them: a missing-value code, a failed run or a units "
        "error?"
    )
    assert "drop or correct the run" in got[0] and "its log" in got[0]
    with warnings.catch_warnings():  # the user's filters reach it: an error stops the fit
        warnings.simplefilter("error", gpmsa.OutlierRunWarning)
        with pytest.raises(gpmsa.OutlierRunWarning, match="simulation run 7"):
            gpmsa.fit(data, n_iter=10, seed=0, tune_rounds=2)


def test_a_failed_run_is_named_once_with_its_count_of_points():
    x, t, y = _design()
    y[3] = -999.0  # every output point: y starts at 0 in every other run
    got = _outlier_warnings(lambda: gpmsa.fit(_sim(y, x, t, index=GRID), n_iter=10, seed=0,
                                              tune_rounds=2))  # fmt: skip
    assert len(got) == 1
    assert got[0].startswith(
        "simulation run 3 (y[3]) holds -999 at output index 0, 999 below every other run's value "
        "there ([0, 0]), whose range reaches 1.14 elsewhere; it lies that far at 11 more "
        "output point(s)"
    )


def test_a_scalar_output_and_named_outputs_without_an_index():
    x, t, y = _design()
    scalar = y[:, 5].copy()
    scalar[12] = 1e6  # a units error
    got = _outlier_warnings(lambda: gpmsa.fit(_sim(scalar, x, t), n_iter=10, seed=0,
                                              tune_rounds=2))  # fmt: skip
    assert len(got) == 1 and got[0].startswith(
        "simulation run 12 (y[12]) holds 1e+06, 9.01e+05 times "
    )
    two = y[:, [2, 5]].copy()
    two[9, 1] = -999.0
    found = far_run(_sim(two, x, t, y_names=["a", "b"]), np.arange(2.0))
    assert found is not None and found.run == 9 and found.point == "output 'b'"


def test_ordinary_designs_are_not_named():
    x, t, y = _design()
    assert far_run(_sim(y, x, t, index=GRID), GRID) is None  # y starts at 0 in every run
    rng = np.random.default_rng(1)
    steep = np.exp(5.0 * x[:, 0] + t[:, 0])  # over two orders of magnitude
    assert far_run(_sim(steep, x, t), [0.0]) is None
    for _ in range(20):  # normal outputs: never near the limit
        noisy = y + rng.standard_normal(y.shape)
        assert far_run(_sim(noisy, x, t, index=GRID), GRID) is None
    got = _outlier_warnings(lambda: gpmsa.fit(_sim(y, x, t, index=GRID), n_iter=10, seed=0,
                                              tune_rounds=2))  # fmt: skip
    assert got == []


def test_a_small_design_is_not_judged():
    x, t, y = _design(m=FAR_RUN_MIN_RUNS - 1)
    y[2, 4] = -999.0
    assert far_run(_sim(y, x, t, index=GRID), GRID) is None
    x, t, y = _design(m=FAR_RUN_MIN_RUNS)
    y[2, 4] = -999.0
    assert far_run(_sim(y, x, t, index=GRID), GRID).run == 2


def test_fit_study_names_the_model():
    x, t, y = _design()
    bad = y.copy()
    bad[20, 8] = 999.0
    obs = gpmsa.ObsData(x=[[0.5]], y=[np.sin(3 * GRID) * 0.5 + 0.25 * GRID**2], index=GRID)
    sims = [_sim(y, x, t, index=GRID, t_names=["t"]), _sim(bad, x, t, index=GRID, t_names=["t"])]
    got = _outlier_warnings(lambda: gpmsa.fit_study(sims, [obs, obs], labels=["good", "bad"],
                                                    shared=["t"], n_iter=10, seed=0,
                                                    tune_rounds=2))  # fmt: skip
    assert len(got) == 1 and got[0].startswith("model 'bad': simulation run 20 (y[20]) holds 999 ")
