"""Session 72: closed joint indices of groups of any size (SEPIA's ``jelist``) and the GP's own
variance about the main- and joint-effect functions (SEPIA's ``mef_v``, ``jef_v``) in
``gpmsa.sensitivity``.

Checked against exact identities (a group of every varied input but one is 1 - that input's
total index, a group of all of them 1, a group of two the pair's joint index), Jansen's
pick-freeze Monte Carlo on a fitted emulator's mean, the library's own joint posterior
covariance (``w_conditional``) integrated by a tensor rule, and realisations of the GP drawn
jointly (``emulator_prediction(joint=True)``) averaged over the other inputs.
"""

from __future__ import annotations

import itertools

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from _sens_cases import categorical_emulator  # noqa: E402

import gpmsa  # noqa: E402
from gpmsa import GPMSAError  # noqa: E402
from gpmsa.predictive._common import gp_factors, w_conditional  # noqa: E402
from gpmsa.predictive.sobol import _memory_estimate  # noqa: E402

OLD_FIELDS = ("main", "total", "main_pc", "total_pc", "main_aggregated", "total_aggregated",
              "variance", "mean", "joint", "interaction", "joint_pc", "interaction_pc",
              "joint_aggregated", "interaction_aggregated", "effect_grid", "main_effect",
              "joint_grid", "joint_effect")  # fmt: skip


def _functional(n_t: int = 3):
    """A functional output (5 outputs, 3 components) of x and n_t thetas at fixed parameters."""
    rng = np.random.default_rng(3)
    m, s = 45, np.linspace(0, 1, 5)
    x, t = rng.uniform(0, 2, (m, 1)), rng.uniform(-1, 1, (m, n_t))
    y = (np.sin(2 * x) * (1 + s) + np.outer(t[:, 0] ** 2, s)
         + 0.5 * np.outer(t[:, 1] * x[:, 0] * t[:, -1], 1 - s))  # fmt: skip
    data = gpmsa.SimData(x=x, t=t, y=y, index=s, x_names=["x"],
                         t_names=["a", "b", "c"][:n_t])  # fmt: skip
    params = {"betaU": 1.0 + np.arange(3)[None, :] * np.ones((1 + n_t, 1)), "lamUz": [1, 2, 3],
              "lamWs": [1e4] * 3, "lamWOs": [1e4]}  # fmt: skip
    return gpmsa.Emulator.from_params(data, params, n_pc=3)


@pytest.fixture(scope="module")
def fitted():
    """A scalar output of x and three thetas, fitted (150 sweeps, 120 retained draws)."""
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(60, 1)), rng.uniform(size=(60, 3))
    y = np.sin(3 * x[:, 0]) + t[:, 0] ** 2 + 1.5 * x[:, 0] * t[:, 1] * t[:, 2] + 0.3 * t[:, 2]
    data = gpmsa.SimData(x=x, t=t, y=y[:, None], x_names=["x"], t_names=["a", "b", "c"])
    return gpmsa.fit(data, n_iter=150, tune=False, seed=0)


def test_groups_identities_and_the_default_results_unchanged():
    """Every result of before equal bit for bit with groups and effect variances asked for; a
    group of two equals the pair's joint index bit for bit (the same order; 1e-12 reversed);
    a group of all inputs but one is 1 - its total index (measured 8e-12), all inputs 1."""
    emu = _functional()
    kw = {"draws": False, "pairs": "all", "main_effect_grid": 4, "joint_effect_grid": 3}
    base = gpmsa.sensitivity(emu, **kw)
    groups = [("x", "a"), ("x", "a", "b"), ("c", "x", "b"), ("a", "b", "c"), ("x", "a", "b", "c")]
    sens = gpmsa.sensitivity(emu, groups=groups, effect_variance=True, **kw)
    for name in OLD_FIELDS:
        np.testing.assert_array_equal(getattr(sens, name), getattr(base, name), err_msg=name)
    assert base.groups == () and base.group_joint is None and base.main_effect_variance is None
    assert sens.groups == tuple(groups) and sens.group_joint.shape == (1, 5, 5)
    assert sens.group_joint_pc.shape == (1, 3, 5) and sens.group_joint_aggregated.shape == (1, 5)
    for kind in ("", "_pc", "_aggregated"):
        np.testing.assert_array_equal(getattr(sens, "group_joint" + kind)[..., 0],
                                      getattr(sens, "joint" + kind)[..., 0])  # fmt: skip
    rev = gpmsa.sensitivity(emu, draws=False, groups=[("a", "x")])
    np.testing.assert_allclose(rev.group_joint[..., 0], sens.joint[..., 0], rtol=0, atol=1e-12)
    for g, left_out in ((1, 3), (2, 1), (3, 0)):
        for kind in ("", "_aggregated"):
            np.testing.assert_allclose(getattr(sens, "group_joint" + kind)[..., g],
                                       1 - getattr(sens, "total" + kind)[..., left_out],
                                       atol=1e-10)  # fmt: skip
    np.testing.assert_allclose(sens.group_joint[..., 4], 1.0, atol=1e-12)
    s = sens.group_summary()
    assert list(s) == groups and s[("x", "a", "b", "c")]["joint"] == pytest.approx(1.0)


@pytest.mark.parametrize("basis", [None, "linear"])
def test_groups_with_a_categorical_input_and_a_mean_basis(basis):
    """The identities hold with a categorical input and a linear mean basis (its trend terms
    summed over the group)."""
    sens = gpmsa.sensitivity(categorical_emulator(basis), draws=False, pairs=[("kind", "a")],
                             groups=[("a", "kind"), ("x", "a"), ("x", "kind", "a")])  # fmt: skip
    np.testing.assert_allclose(sens.group_joint[..., 0], sens.joint[..., 0], atol=1e-12)
    np.testing.assert_allclose(sens.group_joint[..., 1], 1 - sens.total[..., 1], atol=1e-10)
    np.testing.assert_allclose(sens.group_joint[..., 2], 1.0, atol=1e-12)


def test_groups_match_pick_freeze_on_a_fitted_emulator(fitted):
    """The point estimate's group indices against Jansen's estimate 1 - E[(f(A) - f(A_u B))^2]
    / 2V on 20,000 points: within 4 standard errors (measured: 0.008 at most, 2.5 se); per draw a
    group of all but one input is 1 - its total index (measured 1.4e-11)."""
    emu, names = fitted, ["x", "a", "b", "c"]
    groups = [("x", "b", "c"), ("a", "b", "c"), ("b", "c")]
    sens = gpmsa.sensitivity(emu, draws=False, groups=groups)
    st = emu.standardizer
    lo, hi = np.r_[st.x_min, st.t_min], np.r_[st.x_max, st.t_max]
    rng, n = np.random.default_rng(1), 20_000
    A, B = lo + (hi - lo) * rng.uniform(size=(2, n, 4))
    f = lambda Z: emu.predict_mean(Z[:, :1], Z[:, 1:])[:, 0]  # noqa: E731
    fA, fB = f(A), f(B)
    V = np.var(np.r_[fA, fB])
    for g, group in enumerate(groups):
        cols = [names.index(q) for q in group]
        C = B.copy()
        C[:, cols] = A[:, cols]
        half = 0.5 * (fA - f(C)) ** 2
        est, se = 1 - half.mean() / V, half.std() / np.sqrt(n) / V
        assert abs(sens.group_joint[0, 0, g] - est) < 4 * se + 1e-3, (group, est)
    draws = gpmsa.sensitivity(emu, n_draws=10, groups=groups)
    np.testing.assert_allclose(draws.group_joint_aggregated[:, 1],
                               1 - draws.total_aggregated[:, 0], atol=1e-9)  # fmt: skip
    assert np.ptp(draws.group_joint_aggregated[:, 2]) > 0  # the draws differ


def _tensor_variance(emu, sens, at: dict, nodes: int = 8):
    """The output variance (l_sim,) of the tensor-rule average over the inputs not in ``at``
    (native values) of the smooth GP given the runs: the library's joint posterior covariance
    (``w_conditional``) weighted twice. GL nodes for a continuous input, its levels for a
    categorical one."""
    names = list(emu.x_names) + list(emu.t_names)
    st = emu.standardizer
    lo, hi = np.r_[st.x_min, st.t_min], np.r_[st.x_max, st.t_max]
    nd, wt = [], []
    for k, name in enumerate(names):
        if name in at:
            nd.append([at[name]])
            wt.append([1.0])
        elif emu.levels[k] is not None:
            lev = np.asarray(sens.bounds[name], dtype=float)
            nd.append(lev)
            wt.append(np.full(lev.size, 1 / lev.size))
        else:
            (a, b), (g, w) = sens.bounds[name], np.polynomial.legendre.leggauss(nodes)
            nd.append(0.5 * (a + b) + 0.5 * (b - a) * g)
            wt.append(0.5 * w)
    Z = np.array(list(itertools.product(*nd)))
    W = np.prod(np.array(list(itertools.product(*wt))), axis=1)
    _, C = w_conditional(emu, emu.params, gp_factors(emu, emu.params), (Z - lo) / (hi - lo), True)
    return np.reshape(st.y_sd, -1) ** 2 * (emu.K**2 @ np.einsum("n,jnm,m->j", W, C, W))


@pytest.mark.parametrize("case", ["plain", "categorical", "linear", "fixed"])
def test_effect_variance_is_the_integrated_posterior_covariance(case):
    """main_effect_variance and joint_effect_variance equal the GP's joint posterior covariance
    integrated twice over the other inputs by a tensor rule (measured: within 2.1e-9 of the
    largest), with a categorical input, a linear mean basis and a categorical input fixed."""
    emu = (
        _functional(2)
        if case == "plain"
        else categorical_emulator("linear" if case == "linear" else None)
    )
    fixed = {"kind": 1} if case == "fixed" else {}
    sens = gpmsa.sensitivity(emu, draws=False, pairs="all", main_effect_grid=3,
                             joint_effect_grid=2, effect_variance=True, fixed=fixed)  # fmt: skip
    assert sens.main_effect_variance.shape == sens.main_effect.shape
    assert sens.joint_effect_variance.shape == sens.joint_effect.shape
    scale = np.nanmax(sens.main_effect_variance)
    for n, name in enumerate(sens.names):
        for i, g in enumerate(sens.effect_grid[:, n]):
            got = sens.main_effect_variance[0, i, :, n]
            if np.isnan(g):
                assert np.all(np.isnan(got))
                continue
            ref = _tensor_variance(emu, sens, dict(fixed, **{name: g}))
            np.testing.assert_allclose(got, ref, rtol=0, atol=1e-8 * scale)
    for p, (na, nb) in enumerate(sens.pairs):
        a, b = sens.names.index(na), sens.names.index(nb)
        for i, j in itertools.product(range(sens.joint_grid.shape[0]), repeat=2):
            ga, gb = sens.joint_grid[i, a], sens.joint_grid[j, b]
            if np.isnan(ga) or np.isnan(gb):
                continue
            ref = _tensor_variance(emu, sens, dict(fixed, **{na: ga, nb: gb}))
            np.testing.assert_allclose(sens.joint_effect_variance[0, i, j, :, p], ref, rtol=0,
                                       atol=1e-8 * scale)  # fmt: skip


def test_effect_variance_matches_averaged_gp_realisations():
    """3,000 joint realisations of the smooth GP on each grid point x 6 x 6 Gauss-Legendre
    nodes of the other inputs, averaged: their variance within 4.5 standard errors of
    main_effect_variance over 3 inputs x 3 points x 5 outputs, their mean within 4.5 of
    main_effect (measured: at most 2.5 standard errors of 90 values)."""
    emu = _functional(2)
    sens = gpmsa.sensitivity(emu, draws=False, main_effect_grid=3, effect_variance=True)
    R, nodes = 3000, 6
    g, w = np.polynomial.legendre.leggauss(nodes)
    worst = 0.0
    for n in range(3):
        Z = []
        for value in sens.effect_grid[:, n]:
            nd = [
                [value]
                if k == n
                else 0.5 * sum(sens.bounds[name]) + 0.5 * np.diff(sens.bounds[name]) * g
                for k, name in enumerate(sens.names)
            ]
            Z.append(np.array(list(itertools.product(*nd))))  # fmt: skip
        W = np.outer(0.5 * w, 0.5 * w).ravel()
        Z = np.vstack(Z)
        pred = gpmsa.emulator_prediction(emu, Z[:, :1], Z[:, 1:], draws=False, n_rlz=R,
                                         resid=False, joint=True, seed=n)  # fmt: skip
        avg = np.einsum("rgnl,n->rgl", pred.y.reshape(R, 3, nodes**2, -1), W)
        ref = sens.main_effect_variance[0, :, :, n]
        z_var = (avg.var(axis=0, ddof=1) - ref) / (ref * np.sqrt(2 / (R - 1)))
        z_mean = (avg.mean(axis=0) - sens.main_effect[0, :, :, n]) / np.sqrt(ref / R)
        worst = max(worst, np.abs(z_var).max(), np.abs(z_mean).max())
    assert worst < 4.5


def test_effect_variance_with_the_other_inputs_fixed_is_the_pointwise_variance(fitted):
    """With every other input fixed a main-effect curve is the emulator at a point: per draw
    its variance is the smooth GP's predictive variance there (emulator_prediction's var_w
    without the nugget, through the basis)."""
    emu = fitted
    fixed = {"x": 0.4, "b": 0.6, "c": 0.2}
    sens = gpmsa.sensitivity(emu, n_draws=3, fixed=fixed, main_effect_grid=5,
                             effect_variance=True)  # fmt: skip
    grid = sens.effect_grid[:, 0]
    t = np.column_stack([grid, np.full(5, 0.6), np.full(5, 0.2)])
    pred = gpmsa.emulator_prediction(emu, np.full((5, 1), 0.4), t, n_draws=3, resid=False)
    sd2 = np.reshape(emu.standardizer.y_sd, -1) ** 2
    ref = np.einsum("snj,lj->snl", pred.var_w, emu.K**2) * sd2
    np.testing.assert_allclose(sens.main_effect_variance[..., 0], ref, rtol=1e-9, atol=1e-14)
    s = sens.main_effect_summary()["a"]
    np.testing.assert_allclose(s["gp_sd"], np.sqrt(ref.mean(axis=0)))
    assert np.all(s["total_sd"] >= s["gp_sd"])


def test_main_effect_curves_draw_the_gp_band():
    """The figure adds a band per panel with the GP's variance, containing the curve."""
    emu = _functional(2)
    sens = gpmsa.sensitivity(emu, draws=False, main_effect_grid=5, effect_variance=True)
    plain = gpmsa.plots.main_effect_curves(gpmsa.sensitivity(emu, draws=False,
                                                             main_effect_grid=5))  # fmt: skip
    fig = gpmsa.plots.main_effect_curves(sens, output=2)
    for ax, ax0 in zip(fig.axes[:3], plain.axes[:3], strict=True):
        assert len(ax.collections) == len(ax0.collections) + 1
        band = ax.collections[-1].get_paths()[0].vertices[:, 1]
        curve = ax.lines[0].get_ydata()
        assert band.min() < curve.min() and band.max() > curve.max()


def test_refusals_and_memory():
    """Bad groups and effect_variance without a grid are refused by name; the memory estimate
    counts the new arrays."""
    emu = _functional(2)
    bad = [([("x",)], "at least 2"), ([("x", "zz")], "unknown input 'zz'"),
           ([("x", "x")], "an input twice"), ([("x", "a"), ("a", "x")], "twice"),
           ("x", "non-empty list"), (["xa"], "tuple of at least 2"), ([], "non-empty")]  # fmt: skip
    for groups, text in bad:
        with pytest.raises(GPMSAError, match=text):
            gpmsa.sensitivity(emu, draws=False, groups=groups)
    with pytest.raises(GPMSAError, match="held fixed"):
        gpmsa.sensitivity(emu, draws=False, fixed={"a": 0.0}, groups=[("x", "a")])
    with pytest.raises(GPMSAError, match="effect_variance=True needs main_effect_grid"):
        gpmsa.sensitivity(emu, draws=False, effect_variance=True, pairs="all")
    with pytest.raises(GPMSAError, match="effect_variance"):
        gpmsa.sensitivity(emu, draws=False, effect_variance="yes", main_effect_grid=3)
    with pytest.raises(GPMSAError, match="no groups"):
        gpmsa.sensitivity(emu, draws=False).group_summary()
    base = _memory_estimate(150, 3, 2, 10, 5, 3, 20, 10)
    assert _memory_estimate(150, 3, 2, 10, 5, 3, 20, 10, 4) > base
    assert _memory_estimate(150, 3, 2, 10, 5, 3, 20, 10, 0, True) > base + 8 * 10 * 20 * 5 * 3
