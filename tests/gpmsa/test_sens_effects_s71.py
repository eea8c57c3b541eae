"""Session 71: main-effect and joint-effect functions and two-factor (interaction and closed
joint) indices of ``gpmsa.sensitivity`` (SEPIA's ``mef``, ``jef``, ``sie``, ``sje``).

Checked against brute-force Monte Carlo on the emulator's own mean surface (the closed forms
must agree to Monte-Carlo error), exact identities (a pair of all varied inputs; a pair whose
complement is one input), and analytic references within the emulator's error: Ishigami,
a linear additive function and a product x1 x2.
"""

from __future__ import annotations

import warnings

import matplotlib

matplotlib.use("Agg")

import numpy as np  # noqa: E402
import pytest  # noqa: E402
from scipy.stats import qmc  # noqa: E402

import gpmsa  # noqa: E402
from gpmsa import GPMSAError  # noqa: E402
from gpmsa.errors import ResourceLimitError  # noqa: E402
from gpmsa.predictive.sobol import _memory_estimate  # noqa: E402
from tests.gpmsa._predict_cases import three_input_emulator  # noqa: E402


def _mean_function(emu):
    """The emulator's mean surface at native inputs Z (N, p + q), native units."""
    p = emu.p
    return lambda Z: emu.predict_mean(Z[:, :p], Z[:, p:])


@pytest.fixture(scope="module")
def functional():
    """A functional output (6 outputs, 3 components), 3 inputs with units, at fixed
    parameters: the emulator's mean is a deterministic function to check against."""
    rng = np.random.default_rng(3)
    m, s = 40, np.linspace(0, 1, 6)
    x, t = rng.uniform(0, 2, (m, 1)), rng.uniform(-1, 1, (m, 2))
    y = (np.sin(2 * x) * (1 + s) + np.outer(t[:, 0] ** 2, s)
         + 0.5 * np.outer(t[:, 1] * x[:, 0], 1 - s))  # fmt: skip
    data = gpmsa.SimData(x=x, t=t, y=y, index=s, x_names=["x"], t_names=["a", "b"],
                         x_units=["m"], t_units=["s", ""], y_units=["N"] * 6)  # fmt: skip
    params = {"betaU": 2.0 + np.arange(3)[None, :] * np.ones((3, 1)), "lamUz": [1, 2, 3],
              "lamWs": [1e4] * 3, "lamWOs": [1e4]}  # fmt: skip
    return gpmsa.Emulator.from_params(data, params, n_pc=3)


def test_effects_and_pair_indices_equal_monte_carlo_on_the_emulator_mean(functional):
    """Main-effect curves (7 points x 3 inputs x 6 outputs) and the (x, b) joint-effect surface
    (3 x 3 x 6) against the mean of 2,000 points of the emulator's mean each: within 4.5
    standard errors (measured: at most 3.2 of 180); the joint and interaction indices of every
    pair against pick-freeze Monte Carlo (20,000 points per matrix): within 0.02 (measured:
    0.007 and 0.003)."""
    emu = functional
    lo, hi = np.array([0.1, -0.9, -0.8]), np.array([1.9, 0.8, 0.9])
    box = {"x": (0.1, 1.9), "a": (-0.9, 0.8), "b": (-0.8, 0.9)}
    sens = gpmsa.sensitivity(emu, draws=False, bounds=box, pairs="all", main_effect_grid=7,
                             joint_effect_grid=3)  # fmt: skip
    f, rng, n = _mean_function(emu), np.random.default_rng(0), 2000
    np.testing.assert_allclose(sens.effect_grid, np.linspace(lo, hi, 7))
    worst = 0.0
    for k in range(3):
        for i, g in enumerate(sens.effect_grid[:, k]):
            Z = lo + (hi - lo) * rng.uniform(size=(n, 3))
            Z[:, k] = g
            fz = f(Z)
            err = np.abs(fz.mean(axis=0) - sens.main_effect[0, i, :, k])
            worst = max(worst, np.max(err / (fz.std(axis=0) / np.sqrt(n))))
    for i, ga in enumerate(sens.joint_grid[:, 0]):
        for j, gb in enumerate(sens.joint_grid[:, 2]):
            Z = lo + (hi - lo) * rng.uniform(size=(n, 3))
            Z[:, 0], Z[:, 2] = ga, gb
            fz = f(Z)
            err = np.abs(fz.mean(axis=0) - sens.joint_effect[0, i, j, :, 1])
            worst = max(worst, np.max(err / (fz.std(axis=0) / np.sqrt(n))))
    assert worst < 4.5
    n = 20_000
    A, B = lo + (hi - lo) * rng.uniform(size=(2, n, 3))
    fA, fB = f(A), f(B)
    V = np.var(np.vstack([fA, fB]), axis=0)
    # pick-freeze (Saltelli 2010): B with the inputs u taken from A, V_u = E[f(A) (f(B_A^u) -
    # f(B))]; main: (l_sim, 3)
    main = np.array([np.mean(fA * (f(np.where(np.arange(3) == k, A, B)) - fB), axis=0) / V
                     for k in range(3)]).T  # fmt: skip
    for p, (a, b) in enumerate([(0, 1), (0, 2), (1, 2)]):
        C = B.copy()
        C[:, [a, b]] = A[:, [a, b]]
        joint = np.mean(fA * (f(C) - fB), axis=0) / V
        np.testing.assert_allclose(sens.joint[0, :, p], joint, atol=0.02)
        np.testing.assert_allclose(sens.interaction[0, :, p], joint - main[:, a] - main[:, b],
                                   atol=0.02)  # fmt: skip
    assert sens.pairs == (("x", "a"), ("x", "b"), ("a", "b"))
    assert sens.joint_effect.shape == (1, 3, 3, 6, 3) and sens.main_effect.shape == (1, 7, 6, 3)


def test_identities_of_pairs_and_effect_functions(functional):
    """Exact (to rounding) consequences of the definitions: with 3 varied inputs the closed
    index of a pair is 1 - the total index of the third; with 2 varied inputs (the third
    fixed) a pair's joint index is 1 and its joint-effect surface is the emulator's mean itself;
    a main-effect curve averages to the mean over the box, and its variance over the grid is
    the main effect's V_k (quadrature on 401 points)."""
    emu = functional
    sens = gpmsa.sensitivity(emu, draws=False, pairs=[("x", "a"), ("b", "x")],
                             main_effect_grid=401)  # fmt: skip
    np.testing.assert_allclose(sens.joint[0, :, 0], 1 - sens.total[0, :, 2], atol=1e-9)
    np.testing.assert_allclose(sens.joint[0, :, 1], 1 - sens.total[0, :, 1], atol=1e-9)
    assert sens.pairs == (("x", "a"), ("b", "x"))
    curves = sens.main_effect[0]  # (G, l_sim, d)
    mean = np.trapezoid(curves, axis=0) / 400
    np.testing.assert_allclose(mean, np.repeat(sens.mean[0][:, None], 3, axis=1), atol=1e-4)
    var_k = np.trapezoid((curves - sens.mean[0][None, :, None]) ** 2, axis=0) / 400
    np.testing.assert_allclose(var_k, sens.main[0] * sens.variance[0][:, None], atol=1e-4)
    two = gpmsa.sensitivity(emu, draws=False, fixed={"a": 0.2}, pairs="all",
                            joint_effect_grid=4)  # fmt: skip
    np.testing.assert_allclose(two.joint[0, :, 0], 1.0, atol=1e-9)
    gx, gb = np.meshgrid(two.joint_grid[:, 0], two.joint_grid[:, 1], indexing="ij")
    t = np.column_stack([np.full(gx.size, 0.2), gb.ravel()])
    direct = emu.predict_mean(gx.reshape(-1, 1), t)
    np.testing.assert_allclose(two.joint_effect[0, :, :, :, 0].reshape(16, 6), direct,
                               atol=1e-10)  # fmt: skip
    assert two.main_effect is None and two.effect_grid is None


@pytest.fixture(scope="module")
def ishigami():
    """Ishigami (a = 7, b = 0.1) on [-pi, pi]^3, 256 Sobol-sequence runs, at the point estimate
    of a 600-sweep fit (seed 0; rounded, so that no fit runs here). Its mean's RMSE against
    the function over the box is 0.30 (sqrt(V) = 3.72)."""
    z = qmc.scale(qmc.Sobol(3, seed=1).random(256), [-np.pi] * 3, [np.pi] * 3)
    y = np.sin(z[:, 0]) + 7 * np.sin(z[:, 1]) ** 2 + 0.1 * z[:, 2] ** 4 * np.sin(z[:, 0])
    data = gpmsa.SimData(x=z[:, :1], t=z[:, 1:], y=y[:, None], x_names=["x1"],
                         t_names=["x2", "x3"])  # fmt: skip
    params = {"betaU": [[5.2], [9.9], [6.4]], "lamUz": [0.31], "lamWs": [3400.0],
              "lamWOs": [2740.0]}  # fmt: skip
    emu = gpmsa.Emulator.from_params(data, params)
    box = {k: (-np.pi, np.pi) for k in ("x1", "x2", "x3")}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the box's edges lie just outside the design
        return gpmsa.sensitivity(emu, bounds=box, draws=False, pairs="all", main_effect_grid=13,
                                 joint_effect_grid=5)  # fmt: skip


def test_ishigami_indices_and_effect_functions(ishigami):
    """Ishigami: V1 = (1 + b pi^4 / 5)^2 / 2, V2 = a^2 / 8, V3 = 0, V13 = 8 b^2 pi^8 / 225,
    V12 = V23 = 0, so interaction indices (0, 0.2437, 0) and closed joint indices (V1 + V2,
    V1 + V13, V2) / V = (0.7563, 0.5576, 0.4424): within 0.02 (measured: 0.012). Main effects
    E[f | x1] = a/2 + (1 + b pi^4 / 5) sin x1, E[f | x2] = a sin^2 x2, E[f | x3] = a/2: within
    0.2 inside the box (measured 0.17; the emulator's RMSE is 0.30) and 0.65 on its edges
    (measured 0.60 at x2 = -pi, where the design ends). Joint effect E[f | x1, x3] = a/2 +
    sin x1 (1 + b x3^4) within 0.35 off x3's edges (measured 0.33; at x3 = +-pi, where f
    reaches +-10.7, up to 2.1)."""
    sens, a, b = ishigami, 7.0, 0.1
    V1, V2, V13 = (1 + b * np.pi**4 / 5) ** 2 / 2, a**2 / 8, 8 * b**2 * np.pi**8 / 225
    V = V1 + V2 + V13
    assert sens.pairs == (("x1", "x2"), ("x1", "x3"), ("x2", "x3"))
    np.testing.assert_allclose(sens.interaction[0, 0], [0, V13 / V, 0], atol=0.02)
    np.testing.assert_allclose(sens.joint[0, 0], [(V1 + V2) / V, (V1 + V13) / V, V2 / V],
                               atol=0.02)  # fmt: skip
    np.testing.assert_array_equal(sens.joint[:, 0], sens.joint_aggregated)
    g = sens.effect_grid
    truth = np.column_stack([a / 2 + (1 + b * np.pi**4 / 5) * np.sin(g[:, 0]),
                             a * np.sin(g[:, 1]) ** 2, np.full(len(g), a / 2)])  # fmt: skip
    err = np.abs(sens.main_effect[0, :, 0, :] - truth)
    assert err[1:-1].max() < 0.2 and err.max() < 0.65
    jg = sens.joint_grid
    joint = a / 2 + np.sin(jg[:, 0])[:, None] * (1 + b * jg[:, 2][None, :] ** 4)
    assert np.abs(sens.joint_effect[0, :, 1:-1, 0, 1] - joint[:, 1:-1]).max() < 0.35


@pytest.fixture(scope="module")
def linear():
    """y = 2 x1 - 0.3 x2 + 0.5 x3 over x1 in [0, 1] (m), x2 in [10, 20] (s), x3 in [0, 1],
    40 Latin-hypercube runs, a short fit (20 draws kept)."""
    lo, hi = np.array([0.0, 10.0, 0.0]), np.array([1.0, 20.0, 1.0])
    z = qmc.scale(qmc.LatinHypercube(3, seed=4).random(40), lo, hi)
    y = 2 * z[:, 0] - 0.3 * z[:, 1] + 0.5 * z[:, 2]
    data = gpmsa.SimData(x=z[:, :1], t=z[:, 1:], y=y[:, None], x_names=["x1"],
                         t_names=["x2", "x3"], x_units=["m"], t_units=["s", ""], y_names=["f"],
                         y_units=["N"])  # fmt: skip
    return gpmsa.fit(data, n_iter=100, tune=False, seed=0, n_keep=20)


def test_linear_additive_function_has_no_interactions_and_straight_main_effects(linear):
    """No interaction (each index below 0.005; measured: 1.3e-4) and closed joint indices the sums
    of the main ones; main effects E[y | x_k = g] = E[y] + c_k (g - mid_k) with slopes (2, -0.3,
    0.5) within 0.05 sqrt(V) (sqrt(V) = 1.02; measured: 0.032, the short fit's error at the
    box's ends; the band over draws is 0.016 wide), for every draw."""
    sens = gpmsa.sensitivity(linear, n_draws=5, pairs="all", main_effect_grid=9)
    assert np.all(sens.interaction < 0.005)
    a, b = np.array([0, 0, 1]), np.array([1, 2, 2])
    np.testing.assert_allclose(sens.joint, sens.main[..., a] + sens.main[..., b], atol=0.005)
    g, slope = sens.effect_grid, np.array([2.0, -0.3, 0.5])
    mid = g.mean(axis=0)
    truth = sens.mean[:, None, :, None] + (slope * (g - mid))[None, :, None, :]
    V = np.sum(slope**2 * np.ptp(g, axis=0) ** 2 / 12)
    assert np.abs(sens.main_effect - truth).max() < 0.05 * np.sqrt(V)
    summ = sens.main_effect_summary(0.9)
    assert list(summ) == ["x1", "x2", "x3"] and summ["x2"]["mean"].shape == (9, 1)
    np.testing.assert_array_equal(summ["x2"]["grid"], g[:, 1])
    assert np.all(summ["x1"]["lo"] <= summ["x1"]["mean"] + 1e-12)
    pair = sens.pair_summary(0.9)[("x1", "x3")]
    assert pair["interaction"] < 0.005 and pair["joint_lo"] <= pair["joint"] <= pair["joint_hi"]


def test_product_has_the_known_interaction_index():
    """y = x1 x2 with x1, x2 uniform on [0, 1] and an inert x3: V1 = V2 = 1/48, V12 = 1/144,
    V = 7/144, so S1 = S2 = 3/7, interaction S12 = 1/7, joint S_{12} = 1, S_{13} = S1 and no
    interaction with x3; E[y | x1 = g] = g / 2. Within 0.01 (measured: 0.002) and the curve
    within 0.01 (measured: 0.003)."""
    z = qmc.LatinHypercube(3, seed=5).random(40)
    data = gpmsa.SimData(x=z[:, :1], t=z[:, 1:], y=(z[:, 0] * z[:, 1])[:, None],
                         x_names=["x1"], t_names=["x2", "x3"])  # fmt: skip
    params = {"betaU": [[1.0], [1.0], [0.001]], "lamUz": [0.5], "lamWs": [1e5], "lamWOs": [1e5]}
    emu = gpmsa.Emulator.from_params(data, params)
    box = {k: (0.0, 1.0) for k in ("x1", "x2", "x3")}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the box's edges lie just outside the design
        sens = gpmsa.sensitivity(emu, bounds=box, draws=False, pairs="all", main_effect_grid=5)
    np.testing.assert_allclose(sens.main[0, 0], [3 / 7, 3 / 7, 0], atol=0.01)
    np.testing.assert_allclose(sens.interaction[0, 0], [1 / 7, 0, 0], atol=0.01)
    np.testing.assert_allclose(sens.joint[0, 0], [1, 3 / 7, 3 / 7], atol=0.01)
    np.testing.assert_allclose(sens.main_effect[0, :, 0, 0], np.linspace(0, 1, 5) / 2,
                               atol=0.01)  # fmt: skip


def test_without_the_new_arguments_nothing_changes(functional):
    """The opt-in fields stay None (pairs ()) and the existing ones are the same numbers."""
    plain = gpmsa.sensitivity(functional, draws=False)
    more = gpmsa.sensitivity(functional, draws=False, pairs="all", main_effect_grid=3)
    for name in ("main", "total", "main_pc", "total_pc", "main_aggregated", "variance", "mean"):
        np.testing.assert_array_equal(getattr(plain, name), getattr(more, name))
    assert plain.pairs == () and plain.joint is None and plain.main_effect is None
    assert plain.units == {"x": "m", "a": "s", "b": ""} and plain.y_units == ("N",) * 6
    with pytest.raises(GPMSAError, match=r"no pairs: call sensitivity\(\.\.\., pairs="):
        plain.pair_summary()
    with pytest.raises(GPMSAError, match="no main-effect functions"):
        plain.main_effect_summary()
    with pytest.raises(GPMSAError, match="no main-effect functions"):
        gpmsa.plots.main_effect_curves(plain)


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"pairs": [("x", "z")]}, r"pairs names an unknown input 'z'; the varied inputs are"),
        ({"pairs": [("x", "a")], "fixed": {"a": 0.0}}, r"pairs names 'a', an input held fixed"),
        ({"pairs": [("x", "x")]}, r"pairs names one input twice in \('x', 'x'\)"),
        ({"pairs": [("x", "a"), ("a", "x")]}, r"pairs lists the pair \('a', 'x'\) twice"),
        ({"pairs": ("x", "a")}, r"each of pairs must be a pair of input names \(a, b\), got 'x'"),
        ({"pairs": [("x", "a", "b")]}, r"each of pairs must be a pair"),
        ({"pairs": "some"}, r"pairs must be 'all' or a list of pairs of input names, got 'some'"),
        ({"pairs": []}, r"pairs must be 'all' or a non-empty list"),
        ({"pairs": "all", "fixed": {"x": 1.0, "a": 0.0}}, r"pairs='all' needs at least 2 varied"),
        ({"main_effect_grid": 1}, r"main_effect_grid must be an integer >= 2, got 1"),
        ({"main_effect_grid": 5.0}, r"main_effect_grid must be an integer >= 2, got 5.0"),
        ({"main_effect_grid": True}, r"main_effect_grid must be an integer >= 2, got True"),
        ({"joint_effect_grid": 1, "pairs": "all"}, r"joint_effect_grid must be an integer >= 2"),
        ({"joint_effect_grid": 5}, r"joint_effect_grid needs pairs"),
    ],
)
def test_bad_arguments_name_the_problem(functional, kw, match):
    with pytest.raises(GPMSAError, match=match):
        gpmsa.sensitivity(functional, draws=False, **kw)


def test_memory_is_checked_before_allocating(monkeypatch):
    """The estimate with pairs and both grids bounds the memory taken (tracemalloc) and a limit
    below it is refused, naming what asked for it."""
    import tracemalloc

    emu = three_input_emulator()
    kw = {"draws": False, "pairs": "all", "main_effect_grid": 400, "joint_effect_grid": 60}
    need = _memory_estimate(150, 3, 1, 1, 1, 3, 400, 60)
    monkeypatch.setattr(gpmsa.limits, "MAX_MEMORY_BYTES", need - 1)
    match = r"over 3 varied inputs, 3 pairs, main effects on 400 points, joint effects on 60\^2"
    with pytest.raises(ResourceLimitError, match=match):
        gpmsa.sensitivity(emu, **kw)
    monkeypatch.setattr(gpmsa.limits, "MAX_MEMORY_BYTES", need)
    tracemalloc.start()
    try:
        gpmsa.sensitivity(emu, **kw)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < need


def test_main_effect_curves_figure(linear, functional):
    """One panel per input labelled "name (unit)", the output's "E[name | input] (unit)", a band
    over draws (none for the point estimate); a functional output's element by ``output``."""
    sens = gpmsa.sensitivity(linear, n_draws=5, main_effect_grid=9)
    fig = gpmsa.plots.main_effect_curves(sens, level=0.8)
    axes = fig.axes
    assert [ax.get_xlabel() for ax in axes] == ["x1 (m)", "x2 (s)", "x3"]
    assert axes[0].get_ylabel() == "E[f | input] (N)"
    assert all(len(ax.collections) == 1 for ax in axes)  # the band
    lo, hi = np.quantile(sens.main_effect[:, :, 0, 1], [0.1, 0.9], axis=0)
    band = axes[1].collections[0].get_paths()[0].vertices[:, 1]
    np.testing.assert_allclose([band.min(), band.max()], [lo.min(), hi.max()])
    np.testing.assert_allclose(axes[1].lines[0].get_ydata(), sens.main_effect[:, :, 0, 1].mean(0))
    point = gpmsa.sensitivity(functional, draws=False, main_effect_grid=5)
    fig = gpmsa.plots.main_effect_curves(point, output=5)
    assert all(len(ax.collections) == 0 for ax in fig.axes)
    assert fig.axes[0].get_xlabel() == "x (m)" and fig.axes[0].get_ylabel() == "E[y5 | input] (N)"
    np.testing.assert_allclose(fig.axes[2].lines[0].get_ydata(), point.main_effect[0, :, 5, 2])
    with pytest.raises(GPMSAError, match=r"output must be an integer in \[0, 5\], got 6"):
        gpmsa.plots.main_effect_curves(point, output=6)
