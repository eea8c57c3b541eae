"""Session 88: ``gpmsa.predictive.sobol`` pinned where mutation testing found the tests loose:
the summaries over draws (mean, sd, central interval) of a hand-built result against numpy,
and the quiet default (no progress bar)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.predictive.sobol import Sensitivity


def _result(S=7, l_sim=2, d=3, P=2, G=4, seed=0):
    """A Sensitivity of given random arrays (the summaries only read them)."""
    rng = np.random.default_rng(seed)
    u = rng.uniform
    return Sensitivity(
        names=("a", "b", "c"), bounds={}, fixed={}, draw_index=np.arange(S),
        grid=np.arange(l_sim), main=u(size=(S, l_sim, d)), total=u(size=(S, l_sim, d)),
        main_pc=u(size=(S, 1, d)), total_pc=u(size=(S, 1, d)),
        main_aggregated=u(size=(S, d)), total_aggregated=u(size=(S, d)),
        variance=u(size=(S, l_sim)), mean=u(size=(S, l_sim)),
        pairs=(("a", "b"), ("b", "c")), joint_aggregated=u(size=(S, P)),
        interaction_aggregated=u(size=(S, P)), groups=(("a", "b", "c"),),
        group_joint_aggregated=u(size=(S, 1)), effect_grid=u(size=(G, d)),
        main_effect=u(size=(S, G, l_sim, d)), main_effect_variance=u(size=(S, G, l_sim, d)),
    )  # fmt: skip


def _expected(col, level):
    lo, hi = np.quantile(col, [(1 - level) / 2, (1 + level) / 2])
    return col.mean(), np.std(col, ddof=1), lo, hi


@pytest.mark.parametrize("level", [0.9, 0.5])
def test_summaries_are_the_mean_sd_and_central_interval_over_draws(level):
    r = _result()
    for k, name in enumerate(r.names):
        row = r.summary(level)[name]
        for kind, arr in (("main", r.main_aggregated), ("total", r.total_aggregated)):
            got = [row[kind], row[f"{kind}_sd"], row[f"{kind}_lo"], row[f"{kind}_hi"]]
            np.testing.assert_allclose(got, _expected(arr[:, k], level), rtol=1e-14)
    for p, pair in enumerate(r.pairs):
        row = r.pair_summary(level)[pair]
        for kind, arr in (("joint", r.joint_aggregated),
                          ("interaction", r.interaction_aggregated)):  # fmt: skip
            got = [row[kind], row[f"{kind}_sd"], row[f"{kind}_lo"], row[f"{kind}_hi"]]
            np.testing.assert_allclose(got, _expected(arr[:, p], level), rtol=1e-14)
    row = r.group_summary(level)[("a", "b", "c")]
    got = [row["joint"], row["joint_sd"], row["joint_lo"], row["joint_hi"]]
    np.testing.assert_allclose(got, _expected(r.group_joint_aggregated[:, 0], level), rtol=1e-14)


def test_the_default_level_is_0_9_and_one_draw_has_sd_0():
    r = _result()
    assert r.summary() == r.summary(0.9)
    assert r.pair_summary() == r.pair_summary(0.9)
    assert r.group_summary() == r.group_summary(0.9)
    one = _result(S=1)
    row = one.summary()["b"]
    assert row["main_sd"] == 0.0 and row["main"] == row["main_lo"] == row["main_hi"]
    cur = one.main_effect_summary()["b"]
    np.testing.assert_array_equal(cur["sd"], np.zeros((4, 2)))


@pytest.mark.parametrize("level", [0.9, 0.6])
def test_main_effect_summary_over_draws_and_the_gp_band(level):
    r = _result()
    out = r.main_effect_summary(level)
    for k, name in enumerate(r.names):
        cur, gp = r.main_effect[..., k], r.main_effect_variance[..., k]
        lo, hi = np.quantile(cur, [(1 - level) / 2, (1 + level) / 2], axis=0)
        np.testing.assert_array_equal(out[name]["grid"], r.effect_grid[:, k])
        np.testing.assert_allclose(out[name]["mean"], cur.mean(axis=0), rtol=1e-14)
        np.testing.assert_allclose(out[name]["sd"], cur.std(axis=0, ddof=1), rtol=1e-14)
        np.testing.assert_allclose(out[name]["lo"], lo, rtol=1e-14)
        np.testing.assert_allclose(out[name]["hi"], hi, rtol=1e-14)
        np.testing.assert_allclose(out[name]["gp_sd"], np.sqrt(gp.mean(axis=0)), rtol=1e-14)
        total = np.sqrt(gp.mean(axis=0) + cur.var(axis=0))  # law of total variance, ddof 0
        np.testing.assert_allclose(out[name]["total_sd"], total, rtol=1e-14)
    default, at_90 = r.main_effect_summary(), r.main_effect_summary(0.9)
    for name in r.names:
        for key in ("lo", "hi"):
            np.testing.assert_array_equal(default[name][key], at_90[name][key])


def test_no_progress_bar_by_default(capsys):
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(12, 1)), rng.uniform(size=(12, 1))
    data = gpmsa.SimData(x=x, t=t, y=x + t, x_names=["x"], t_names=["a"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a deliberately short chain
        emu = gpmsa.fit(data, n_iter=10, tune=False, seed=0)
    capsys.readouterr()
    sens = gpmsa.sensitivity(emu, n_draws=3)
    assert sens.main.shape == (3, 1, 2) and capsys.readouterr().err == ""


@pytest.mark.parametrize("x", [5e-4, 2e-3, 0.3, 3.0])
def test_double_mean_of_the_kernel_on_both_sides_of_its_series(x):
    """Mean of exp(-beta (z - z')^2) over two independent U[0, w] points, x = sqrt(beta) w:
    2 int_0^1 (1 - u) exp(-x^2 u^2) du by quadrature (its series below x = 1e-3)."""
    from scipy.integrate import quad

    from gpmsa.predictive.sobol import _double_mean

    ref = 2.0 * quad(lambda u: (1.0 - u) * np.exp(-(x * u) ** 2), 0.0, 1.0, epsabs=0,
                     epsrel=1e-13)[0]  # fmt: skip
    assert _double_mean(x**2 / 4.0, 1.0, 3.0) == pytest.approx(ref, rel=1e-12)


def test_ratio_clips_and_leaves_an_undefined_index_nan_without_floating_point_errors():
    from gpmsa.predictive.sobol import _ratio

    with np.errstate(all="raise"):
        out = _ratio(np.array([1.0, 0.0, 2.5, -1e-13]), np.array([2.0, 0.0, 2.0, 2.0]), 2.0)
    np.testing.assert_array_equal(out, [0.5, np.nan, 1.0, 0.0])
