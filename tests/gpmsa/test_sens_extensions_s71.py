"""Session 71: ``gpmsa.sensitivity`` of an emulator with categorical inputs and/or a named mean
basis ("constant", "linear").

A categorical input varies uniformly over its training levels (or the levels ``bounds`` lists),
so every integral over it is a finite average; a mean basis adds h(z)^T b_j to each component's
mean, whose moments against the GP part are closed forms too. Checked against the emulator's
own mean surface (``Emulator.predict_mean``) integrated by brute force: a tensor rule (the
levels, and 48-point Gauss-Legendre in each continuous input: exact to ~1e-12 here) and
Monte Carlo; and against analytic indices of an additive and a linear function.
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

NAMES = ("x", "kind", "a")


@pytest.fixture(scope="module", params=[None, "constant", "linear"])
def emu(request):
    return categorical_emulator(request.param)


class _Tensor:
    """The emulator's mean on a tensor rule over the box: per input its nodes and weights
    (levels with equal weights; Gauss-Legendre; one node for a fixed input)."""

    def __init__(self, emu, box: dict, fixed: dict, n: int = 48):
        nodes, self.w = [], []
        for name in NAMES:
            if name in fixed:
                nodes.append(np.array([fixed[name]]))
                self.w.append(np.ones(1))
            elif name == "kind":
                nodes.append(np.asarray(box[name], dtype=float))
                self.w.append(np.full(len(box[name]), 1.0 / len(box[name])))
            else:
                (a, b), (g, w) = box[name], np.polynomial.legendre.leggauss(n)
                nodes.append(0.5 * (a + b) + 0.5 * (b - a) * g)
                self.w.append(0.5 * w)
        Z = np.array(list(itertools.product(*nodes)))
        self.F = emu.predict_mean(Z[:, :2], Z[:, 2:]).reshape(*map(len, nodes), -1)
        self.mean = self.cond(())[0].reshape(-1)
        self.var = self.cond_var((0, 1, 2))

    def cond(self, keep):
        """E[f | inputs keep] on their nodes (other axes of length 1) and those nodes'
        weights."""
        out, wk = self.F, np.ones((1, 1, 1))
        for ax in range(3):
            shape = [1, 1, 1]
            shape[ax] = -1
            if ax in keep:
                wk = wk * self.w[ax].reshape(shape)
            else:
                out = np.sum(out * self.w[ax].reshape(shape + [1]), axis=ax, keepdims=True)
        return out, wk

    def cond_var(self, keep):
        """Var E[f | inputs keep] (l_sim,)."""
        Ec, wk = self.cond(keep)
        return np.sum((Ec - self.mean) ** 2 * wk[..., None], axis=(0, 1, 2))


def _varied(fixed):
    return [k for k, n in enumerate(NAMES) if n not in fixed]


def _check_against_tensor(emu, sens, box, fixed, tol):
    """Every index, the mean and variance, the main-effect curves and the joint surfaces of
    ``sens`` against the tensor rule."""
    T = _Tensor(emu, box, fixed)
    ax = _varied(fixed)  # axes of the tensor that vary, in sens.names' order
    assert sens.names == tuple(NAMES[k] for k in ax)
    np.testing.assert_allclose(sens.mean[0], T.mean, rtol=0, atol=tol)
    np.testing.assert_allclose(sens.variance[0], T.var, rtol=tol)
    for n, k in enumerate(ax):
        rest = tuple(a for a in ax if a != k)
        np.testing.assert_allclose(sens.main[0, :, n], T.cond_var((k,)) / T.var, atol=tol)
        np.testing.assert_allclose(sens.total[0, :, n], 1 - T.cond_var(rest) / T.var, atol=tol)
    for p, (na, nb) in enumerate(sens.pairs):
        ka, kb = NAMES.index(na), NAMES.index(nb)
        vab = T.cond_var((ka, kb))
        np.testing.assert_allclose(sens.joint[0, :, p], vab / T.var, atol=tol)
        inter = (vab - T.cond_var((ka,)) - T.cond_var((kb,))) / T.var
        np.testing.assert_allclose(sens.interaction[0, :, p], inter, atol=tol)
    # the curves at their grid points: predict_mean integrated over the other inputs
    for n, k in enumerate(ax):
        for i, g in enumerate(sens.effect_grid[:, n]):
            if np.isnan(g):
                assert np.all(np.isnan(sens.main_effect[0, i, :, n]))
                continue
            sub = dict(fixed, **{NAMES[k]: g})
            ref = _Tensor(emu, box, sub).mean
            np.testing.assert_allclose(sens.main_effect[0, i, :, n], ref, atol=tol)
    if sens.joint_effect is not None:
        for p, (na, nb) in enumerate(sens.pairs):
            a, b = sens.names.index(na), sens.names.index(nb)
            for i, j in itertools.product(range(sens.joint_grid.shape[0]), repeat=2):
                ga, gb = sens.joint_grid[i, a], sens.joint_grid[j, b]
                if np.isnan(ga) or np.isnan(gb):
                    assert np.all(np.isnan(sens.joint_effect[0, i, j, :, p]))
                    continue
                ref = _Tensor(emu, box, dict(fixed, **{na: ga, nb: gb})).mean
                np.testing.assert_allclose(sens.joint_effect[0, i, j, :, p], ref, atol=tol)


def test_categorical_and_mean_basis_equal_the_integrated_emulator_mean(emu):
    """Indices of every kind, pairs, main-effect curves (the categorical input's at its 3
    levels, NaN below) and joint surfaces equal the tensor rule on predict_mean (measured:
    5e-12), with no, a constant and a linear mean basis."""
    box = {"x": (0.1, 1.9), "kind": (0, 1, 3), "a": (-0.9, 0.8)}
    sens = gpmsa.sensitivity(emu, draws=False, bounds={"x": box["x"], "a": box["a"]},
                             pairs="all", main_effect_grid=4, joint_effect_grid=2)  # fmt: skip
    assert sens.bounds["kind"] == (0, 1, 3)
    assert sens.effect_grid.shape == (4, 3) and sens.joint_grid.shape == (3, 3)
    np.testing.assert_array_equal(sens.effect_grid[:, 1], [0, 1, 3, np.nan])
    _check_against_tensor(emu, sens, box, {}, 1e-9)


def test_a_subset_of_levels_fixed_inputs_and_a_narrow_box(emu):
    """bounds= lists levels (0 and 3 of 0, 1, 3); a categorical input fixed at a level; a
    continuous box 1e-6 of the domain wide (the linear term's moments by quadrature there)."""
    box = {"x": (0.1, 1.9), "kind": (0, 3), "a": (-0.9, 0.8)}
    sens = gpmsa.sensitivity(emu, draws=False, bounds={"kind": [3, 0], "a": box["a"],
                             "x": box["x"]}, main_effect_grid=2, pairs="all")  # fmt: skip
    assert sens.bounds["kind"] == (0, 3)
    _check_against_tensor(emu, sens, box, {}, 1e-9)
    sens = gpmsa.sensitivity(emu, draws=False, fixed={"kind": 1}, bounds={"x": box["x"],
                             "a": box["a"]}, main_effect_grid=3)  # fmt: skip
    assert sens.fixed == {"kind": 1.0}
    _check_against_tensor(emu, sens, box, {"kind": 1}, 1e-9)
    narrow = {"x": (0.7, 0.74), "a": (0.2, 0.23)}  # sqrt(beta) (b - a) < NARROW: quadrature
    sens = gpmsa.sensitivity(emu, draws=False, bounds=narrow, fixed={"kind": 3}, pairs="all")
    T = _Tensor(emu, narrow, {"kind": 3})
    ref = np.column_stack([T.cond_var((k,)) / T.var for k in (0, 2)])
    np.testing.assert_allclose(sens.main[0], ref, atol=1e-6)  # measured 3e-8 (as before)
    np.testing.assert_allclose(sens.interaction[0, :, 0], 1 - ref.sum(axis=1), atol=1e-6)


def test_the_centred_first_moment_on_wide_and_narrow_intervals():
    """E[(z - mid) exp(-g (z - c)^2)], z ~ U[a, b]: closed form and (narrow) quadrature against
    200-point Gauss-Legendre, relative to its scale (b - a) / 2 (measured: 1e-15)."""
    from gpmsa.predictive.sobol import NARROW, _centred_gauss

    c = np.array([-0.3, 0.0, 0.4, 0.5, 0.9, 1.4])
    g2, w2 = np.polynomial.legendre.leggauss(200)
    for gamma, a, b in ((4.0, 0.0, 1.0), (0.01, 0.0, 1.0), (30.0, 0.2, 0.3), (2.0, 0.5, 0.5 + 1e-6),
                        ((NARROW / 0.1) ** 2 * 1.0001, 0.3, 0.4)):  # fmt: skip
        mid, half = 0.5 * (a + b), 0.5 * (b - a)
        z = mid + half * g2
        ref = 0.5 * w2 @ ((z - mid)[:, None] * np.exp(-gamma * (z[:, None] - c) ** 2))
        np.testing.assert_allclose(_centred_gauss(gamma, c, a, b) / half, ref / half, atol=1e-13)


def test_indices_and_curves_within_monte_carlo_error_over_draws():
    """A fitted emulator (numpy backend, linear mean basis, a categorical input), 3 posterior
    draws: the categorical input's main-effect curve at each level and the main and total
    indices of each draw (pick-freeze: Saltelli 2010, Jansen; 6,000 points per matrix) within
    4.5 standard errors of Monte Carlo on that draw's predict_mean (measured: 2.5 at most)."""
    rng = np.random.default_rng(1)
    m = 36
    x = np.column_stack([rng.uniform(0, 1, m), np.arange(m) % 3])
    t = rng.uniform(0, 1, (m, 1))
    y = np.sin(3 * x[:, :1]) + 0.4 * x[:, 1:] + t * (1 + 0.5 * x[:, 1:])
    data = gpmsa.SimData(x=x, t=t, y=y, x_names=["x", "kind"], t_names=["a"],
                         x_categorical=["kind"])  # fmt: skip
    emu = gpmsa.fit(data, n_iter=12, tune=False, seed=0, mean_basis="linear")
    sens = gpmsa.sensitivity(emu, n_draws=3, main_effect_grid=3)
    lo, hi = np.array([0.0, 0.0, 0.0]), np.array([1.0, 2.0, 1.0])
    lo[[0, 2]], hi[[0, 2]] = [x[:, 0].min(), t.min()], [x[:, 0].max(), t.max()]

    def sample(n):
        Z = lo + (hi - lo) * rng.uniform(size=(n, 3))
        Z[:, 1] = rng.integers(0, 3, n)
        return Z

    for s, i in enumerate(sens.draw_index):
        sub = gpmsa.Emulator.from_params(data, {k: emu.draws[k][i] for k in
                                                ("betaU", "lamUz", "lamWs", "lamWOs")},
                                         mean_basis="linear")  # fmt: skip
        f = lambda Z, e=sub: e.predict_mean(Z[:, :2], Z[:, 2:])[:, 0]  # noqa: E731
        for g in range(3):
            Z = sample(3000)
            Z[:, 1] = g
            fz = f(Z)
            z = (fz.mean() - sens.main_effect[s, g, 0, 1]) / (fz.std() / np.sqrt(fz.size))
            assert abs(z) < 4.5
        A, B = sample(6000), sample(6000)
        fA, fB = f(A), f(B)
        var = np.var(np.concatenate([fA, fB]))
        for k in range(3):
            ABk = A.copy()
            ABk[:, k] = B[:, k]
            fAB = f(ABk)
            # Saltelli 2010 and Jansen, each a mean: its z-score by its own standard error
            for est, ref in ((fB * (fAB - fA) / var, sens.main[s, 0, k]),
                             (0.5 * (fA - fAB) ** 2 / var, sens.total[s, 0, k])):  # fmt: skip
                z = (est.mean() - ref) / (est.std() / np.sqrt(est.size))
                assert abs(z) < 4.5


def _additive(mean_basis):
    """y = c[kind] + x^2 (kind: levels 0, 1, 2 with c = 0, 0.5, -0.3; x on [0, 1]), 16 runs per
    level, interpolated (the categorical rho exp(-beta / 4) = 0.14)."""
    x = np.tile(np.linspace(0, 1, 16), 3)
    kind = np.repeat([0, 1, 2], 16)
    y = np.array([0.0, 0.5, -0.3])[kind] + x**2
    data = gpmsa.SimData(x=x[:, None], t=kind[:, None], y=y[:, None], x_names=["x"],
                         t_names=["kind"], t_categorical=["kind"])  # fmt: skip
    params = {"betaU": [[3.0], [8.0]], "lamUz": [1.0], "lamWs": [1e6], "lamWOs": [1e5]}
    return gpmsa.Emulator.from_params(data, params, mean_basis=mean_basis)


@pytest.mark.parametrize("mean_basis", [None, "constant"])
def test_an_additive_function_has_its_analytic_shares(mean_basis):
    """Var(x^2) = 4/45 and Var(c) over the 3 levels (over 2 with bounds=) give the main
    indices; additive: main = total, interaction 0 (within 0.01; measured 1e-4). Fixing kind
    leaves x all the variance."""
    emu = _additive(mean_basis)
    c = np.array([0.0, 0.5, -0.3])
    for levels in ((0, 1, 2), (1, 2)):
        share = np.var(c[list(levels)]) / (np.var(c[list(levels)]) + 4 / 45)
        sens = gpmsa.sensitivity(emu, draws=False, bounds={"kind": levels}, pairs="all",
                                 main_effect_grid=3)  # fmt: skip
        np.testing.assert_allclose(sens.main[0, 0], [1 - share, share], atol=0.01)
        np.testing.assert_allclose(sens.total[0, 0], [1 - share, share], atol=0.01)
        assert abs(sens.interaction[0, 0, 0]) < 0.01
        curve = sens.main_effect[0, : len(levels), 0, 1]
        np.testing.assert_allclose(curve, c[list(levels)] + 1 / 3, atol=0.01)
    sens = gpmsa.sensitivity(emu, draws=False, fixed={"kind": 2})
    assert sens.main[0, 0, 0] == pytest.approx(1.0)
    assert sens.mean[0, 0] == pytest.approx(-0.3 + 1 / 3, abs=0.01)


def test_a_linear_function_with_a_linear_mean_basis_is_exact():
    """y = 2 x + 3 t on [0, 1] x [0, 2]: the GLS trend carries it all, so the indices are
    Var(2x) / V = (1/3) / (1/3 + 3) = 0.1 and 0.9 to rounding, the curves straight lines."""
    rng = np.random.default_rng(0)
    x, t = rng.uniform(0, 1, (30, 1)), rng.uniform(0, 2, (30, 1))
    data = gpmsa.SimData(x=x, t=t, y=2 * x + 3 * t, x_names=["x"], t_names=["t"])
    params = {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [1e6], "lamWOs": [1e5]}
    emu = gpmsa.Emulator.from_params(data, params, mean_basis="linear")
    box = {"x": (x.min(), x.max()), "t": (t.min(), t.max())}
    sens = gpmsa.sensitivity(emu, draws=False, bounds=box, main_effect_grid=3)
    vx, vt = (2 * np.ptp(x)) ** 2 / 12, (3 * np.ptp(t)) ** 2 / 12
    np.testing.assert_allclose(sens.main[0, 0], [vx / (vx + vt), vt / (vx + vt)], atol=1e-6)
    np.testing.assert_allclose(sens.total[0, 0], sens.main[0, 0], atol=1e-6)
    mid = np.mean([box["t"]]) * 3
    np.testing.assert_allclose(sens.main_effect[0, :, 0, 0], 2 * sens.effect_grid[:, 0] + mid,
                               atol=1e-6)  # fmt: skip


def test_summary_and_figure_take_a_categorical_curve():
    emu = categorical_emulator("constant")
    sens = gpmsa.sensitivity(emu, draws=False, main_effect_grid=5)
    cur = sens.main_effect_summary()["kind"]
    np.testing.assert_array_equal(cur["grid"], [0, 1, 3, np.nan, np.nan])
    assert np.all(np.isfinite(cur["mean"][:3])) and np.all(np.isnan(cur["mean"][3:]))
    fig = gpmsa.plots.main_effect_curves(sens)
    assert [a.get_xlabel() for a in fig.axes if a.get_visible()] == list(NAMES)


def test_bad_levels_and_a_callable_mean_basis_are_refused():
    emu = categorical_emulator(None)
    cases = [
        (
            {"bounds": {"kind": (0, 2)}},
            "lists level 2, not a training level of the categorical "
            r"input kind \(levels \[0, 1, 3\]\)",
        ),
        ({"bounds": {"kind": [1, 1]}}, "lists level 1 twice"),
        ({"bounds": {"kind": [3]}}, r"at least 2 levels .* fixed=\{'kind': level\}"),
        ({"bounds": {"kind": 1}}, "kind is categorical; give the levels to vary over"),
        ({"bounds": {"kind": [0, 0.5]}}, "lists level 0.5, not a training level"),
        ({"fixed": {"kind": 2}}, r"fix it at one of its training levels \[0, 1, 3\]"),
    ]
    for kw, msg in cases:
        with pytest.raises(GPMSAError, match=msg):
            gpmsa.sensitivity(emu, draws=False, **kw)
    rng = np.random.default_rng(0)
    x = rng.uniform(size=(20, 2))
    data = gpmsa.SimData(x=x[:, :1], t=x[:, 1:], y=x.sum(axis=1, keepdims=True))
    params = {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [1e6], "lamWOs": [1e5]}
    own = gpmsa.Emulator.from_params(data, params, mean_basis=lambda z: np.ones((len(z), 1)))
    with pytest.raises(GPMSAError, match=r"supports the mean bases \('constant', 'linear'\), "
                                         "not a callable one"):  # fmt: skip
        gpmsa.sensitivity(own, draws=False)
