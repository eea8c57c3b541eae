"""Sobol indices of the emulator (GPM/SA's gSens): the closed-form integrals and two analytic
functions whose indices are known."""

import warnings

import numpy as np
import pytest
from _predict_cases import vector_fit
from scipy.stats import qmc

import gpmsa
from gpmsa import GPMSAError
from gpmsa.model.correlation import correlation
from gpmsa.predictive import sensitivity


def _mean_function(emu):
    """The emulator's posterior mean at native inputs Z (N, p + q), standardised weights
    through K, native units: the same as ``Emulator.predict(...)[0]``, without the variance."""
    std = emu.standardizer
    prm = emu.params
    alphas = []
    for j in range(emu.p_u):
        S = correlation(emu.zt, None, prm["betaU"][:, j]) / prm["lamUz"][j]
        S[np.diag_indices(emu.m)] += 1 / (emu.lam_sim[j] * prm["lamWOs"][0]) + 1 / prm["lamWs"][j]
        alphas.append(np.linalg.solve(S, emu.w[:, j]))

    def f(Z):
        p = emu.p
        z = np.hstack([std.x_to_unit(Z[:, :p]), std.t_to_unit(Z[:, p:])])
        w = np.column_stack([correlation(z, emu.zt, prm["betaU"][:, j]) / prm["lamUz"][j]
                             @ alphas[j] for j in range(emu.p_u)])  # fmt: skip
        return std.y_from_std(w @ emu.K.T)

    return f


def _jansen(f, lo, hi, n, rng):
    """Monte-Carlo main (Saltelli 2010) and total (Jansen) indices of f over U[lo, hi]."""
    d = len(lo)
    A = lo + (hi - lo) * rng.uniform(size=(n, d))
    B = lo + (hi - lo) * rng.uniform(size=(n, d))
    fA, fB = f(A), f(B)
    V = np.var(np.vstack([fA, fB]), axis=0)
    S1, ST = [], []
    for k in range(d):
        ABk = A.copy()
        ABk[:, k] = B[:, k]
        fAB = f(ABk)
        S1.append(np.mean(fB * (fAB - fA), axis=0) / V)
        ST.append(0.5 * np.mean((fA - fAB) ** 2, axis=0) / V)
    return np.array(S1).T, np.array(ST).T, V


@pytest.fixture(scope="module")
def fixed_emulator():
    """A functional output (6 outputs, 3 components) with two calibration parameters, at given
    parameters: the indices of its mean are a deterministic function to check."""
    rng = np.random.default_rng(3)
    m, s = 40, np.linspace(0, 1, 6)
    x, t = rng.uniform(0, 2, (m, 1)), rng.uniform(-1, 1, (m, 2))
    y = (np.sin(2 * x) * (1 + s) + np.outer(t[:, 0] ** 2, s)
         + 0.5 * np.outer(t[:, 1] * x[:, 0], 1 - s))  # fmt: skip
    data = gpmsa.SimData(x=x, t=t, y=y, index=s, x_names=["x"], t_names=["a", "b"])
    params = {"betaU": 2.0 + np.arange(3)[None, :] * np.ones((3, 1)), "lamUz": [1, 2, 3],
              "lamWs": [1e4] * 3, "lamWOs": [1e4]}  # fmt: skip
    return gpmsa.Emulator.from_params(data, params, n_pc=3)


def test_closed_form_equals_monte_carlo_on_the_emulator_mean(fixed_emulator):
    """The erf integrals against brute-force Monte Carlo (2 x 10^5 points per matrix) on the
    emulator's mean, with one range narrowed by ``bounds``: per output element and input,
    within 0.01 (the Monte-Carlo standard error is about 0.002)."""
    emu = fixed_emulator
    sens = sensitivity(emu, draws=False, bounds={"a": (-0.9, 0.8)})
    lo = np.array([emu.domain["x"][0], -0.9, emu.domain["b"][0]])
    hi = np.array([emu.domain["x"][1], 0.8, emu.domain["b"][1]])
    f = _mean_function(emu)
    Z = lo + (hi - lo) * np.random.default_rng(9).uniform(size=(50, 3))
    np.testing.assert_allclose(f(Z), emu.predict(Z[:, :1], Z[:, 1:], resid=False)[0])
    S1, ST, V = _jansen(f, lo, hi, 200_000, np.random.default_rng(0))
    np.testing.assert_allclose(sens.main[0], S1, atol=0.01)
    np.testing.assert_allclose(sens.total[0], ST, atol=0.01)
    np.testing.assert_allclose(sens.variance[0], V, rtol=0.01)
    agg = np.sum(S1 * V[:, None], axis=0) / V.sum()
    np.testing.assert_allclose(sens.main_aggregated[0], agg, atol=0.01)
    assert sens.names == ("x", "a", "b") and sens.bounds["a"] == (-0.9, 0.8)


def test_fixed_inputs_give_the_indices_of_the_conditional_function(fixed_emulator):
    emu = fixed_emulator
    sens = sensitivity(emu, draws=False, fixed={"x": 1.5})
    assert sens.names == ("a", "b") and sens.main.shape == (1, 6, 2)
    lo = np.array([emu.domain["a"][0], emu.domain["b"][0]])
    hi = np.array([emu.domain["a"][1], emu.domain["b"][1]])

    mean = _mean_function(emu)

    def f(Z):
        return mean(np.hstack([np.full((Z.shape[0], 1), 1.5), Z]))

    S1, ST, _ = _jansen(f, lo, hi, 200_000, np.random.default_rng(1))
    np.testing.assert_allclose(sens.main[0], S1, atol=0.01)
    np.testing.assert_allclose(sens.total[0], ST, atol=0.01)


def test_ishigami_indices_within_0_03():
    """Ishigami (a = 7, b = 0.1) on [-pi, pi]^3: x1 as the known input, (x2, x3) as calibration
    parameters, 256 Sobol-sequence runs, a short fit (200 sweeps after 20 x 20 tuning sweeps).
    Indices of the emulator mean over 50 posterior draws, against the analytic values."""
    m = 256
    z = qmc.scale(qmc.Sobol(3, seed=1).random(m), [-np.pi] * 3, [np.pi] * 3)
    y = np.sin(z[:, 0]) + 7 * np.sin(z[:, 1]) ** 2 + 0.1 * z[:, 2] ** 4 * np.sin(z[:, 0])
    data = gpmsa.SimData(x=z[:, :1], t=z[:, 1:], y=y[:, None], x_names=["x1"],
                         t_names=["x2", "x3"])  # fmt: skip
    emu = gpmsa.fit(data, n_iter=200, seed=0, n_keep=100, tune_rounds=20)
    box = {k: (-np.pi, np.pi) for k in ("x1", "x2", "x3")}
    with pytest.warns(UserWarning, match="outside the emulator's domain"):  # the box's edges
        sens = sensitivity(emu, bounds=box, n_draws=50)
    main, total = sens.main_aggregated.mean(axis=0), sens.total_aggregated.mean(axis=0)
    np.testing.assert_allclose(main, [0.3139, 0.4424, 0.0], atol=0.03)
    np.testing.assert_allclose(total, [0.5576, 0.4424, 0.2437], atol=0.03)
    np.testing.assert_array_equal(sens.main[:, 0, :], sens.main_aggregated)
    assert sens.main.shape == (50, 1, 3)
    assert np.all(sens.main_aggregated.std(axis=0) < 0.02)  # spread over draws: small here


def test_functional_output_indices_within_0_03():
    """y(s; z) = (1 - s) u1 + s u2 + 2 u1 u3 on an output grid s in [0, 1] (9 points), with
    u_k the inputs centred and scaled to [-1/2, 1/2] (native ranges [10, 20], [0, 1], [-2, 2]).
    Per output element: V1 = (1 - s)^2 / 12, V2 = s^2 / 12, V13 = 4 / 144 (u3 acts only through
    the interaction), so S = (V1, V2, 0) / V and ST = (V1 + V13, V2, V13) / V. Also the
    aggregated indices (sums over s) and a check per output element."""
    lo, hi = np.array([10.0, 0.0, -2.0]), np.array([20.0, 1.0, 2.0])
    s = np.linspace(0, 1, 9)
    z = qmc.scale(qmc.LatinHypercube(3, seed=2).random(60), lo, hi)
    u = (z - (lo + hi) / 2) / (hi - lo)
    y = np.outer(u[:, 0], 1 - s) + np.outer(u[:, 1], s) + 2.0 * (u[:, 0] * u[:, 2])[:, None]
    data = gpmsa.SimData(x=z[:, :1], t=z[:, 1:], y=y, index=s, x_names=["x1"],
                         t_names=["x2", "x3"])  # fmt: skip
    emu = gpmsa.fit(data, n_iter=200, seed=0, n_keep=100, tune_rounds=20)
    box = dict(zip(("x1", "x2", "x3"), zip(lo, hi, strict=True), strict=True))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the box's edges lie just outside the design
        sens = sensitivity(emu, bounds=box, n_draws=50)
    V1, V2, V13 = (1 - s) ** 2 / 12, s**2 / 12, np.full(s.size, 4 / 144)
    V = V1 + V2 + V13
    S = np.column_stack([V1, V2, 0 * V]) / V[:, None]
    ST = np.column_stack([V1 + V13, V2, V13]) / V[:, None]
    np.testing.assert_allclose(sens.main.mean(axis=0), S, atol=0.03)
    np.testing.assert_allclose(sens.total.mean(axis=0), ST, atol=0.03)
    agg_S = np.array([V1.sum(), V2.sum(), 0.0]) / V.sum()
    agg_ST = np.array([(V1 + V13).sum(), V2.sum(), V13.sum()]) / V.sum()
    np.testing.assert_allclose(sens.main_aggregated.mean(axis=0), agg_S, atol=0.03)
    np.testing.assert_allclose(sens.total_aggregated.mean(axis=0), agg_ST, atol=0.03)
    np.testing.assert_allclose(sens.variance.mean(axis=0), V, rtol=0.05)
    summ = sens.summary(0.9)
    assert summ["x1"]["main_lo"] <= summ["x1"]["main"] <= summ["x1"]["main_hi"]


def test_per_component_indices_and_draw_spread():
    emu = vector_fit()
    sens = sensitivity(emu, n_draws=20)
    assert sens.main_pc.shape == (20, emu.p_u, 2) and sens.draw_index.size == 20
    assert np.all((sens.main_pc >= -1e-9) & (sens.main_pc <= sens.total_pc + 1e-9))
    point = sensitivity(emu, draws=False)
    assert point.main.shape[0] == 1 and point.draw_index.tolist() == [-1]


# --- bad input ---------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"bounds": {"y": (0, 1)}}, r"bounds names unknown inputs \['y'\]"),
        ({"bounds": {"t": (1.0, 0.0)}}, r"bounds\['t'\] must be finite with lo < hi"),
        ({"bounds": {"t": 3}}, r"bounds\['t'\] must be \(lo, hi\)"),
        ({"bounds": {"t": (-1.0, 5.0)}}, r"bounds: t reaches .* by more than 10%"),
        ({"fixed": {"x": 1.0, "t": 0.0}}, "every input is fixed"),
        ({"fixed": {"x": 9.0}}, r"fixed\['x'\]: x reaches"),
        ({"fixed": {"x": "a"}}, r"fixed\['x'\] must be a number"),
        ({"fixed": {"x": 1.0}, "bounds": {"x": (0, 1)}}, "both in bounds and in fixed"),
        ({"n_draws": 0}, "n_draws must be an integer >= 1"),
    ],
)
def test_bad_input_names_the_problem(kw, match):
    with pytest.raises(GPMSAError, match=match):
        sensitivity(vector_fit(), **kw)


def test_no_draws_kept(fixed_emulator):
    with pytest.raises(GPMSAError, match="kept none"):
        sensitivity(fixed_emulator)


def test_mean_gauss_takes_two_error_functions_per_point_with_the_same_bits(monkeypatch):
    """Each of the m x m pair integrals of a draw costs error functions: one per end of the
    range per point (2 m^2), not three branches' worth each (6 m^2, 70 % of sensitivity()'s
    time), with the bits of the three-branch formula (tails by erfc, the middle by erf)."""
    from scipy.special import erf, erfc

    from gpmsa.predictive import sobol

    def reference(gamma, c, a, b):  # the three-branch formula, each branch on every point
        s = np.sqrt(gamma)
        lo, hi = s * (a - c), s * (b - c)
        diff = np.where(lo > 0, erfc(lo) - erfc(hi),
                        np.where(hi < 0, erfc(-hi) - erfc(-lo), erf(hi) - erf(lo)))  # fmt: skip
        return sobol._SQRT_PI_2 * diff / (s * (b - a))

    c = np.random.default_rng(0).uniform(-3.0, 4.0, size=(40, 50))  # every branch, deep tails
    for gamma, a, b in ((30.0, 0.0, 1.0), (2.0, 0.2, 0.9), (400.0, 0.3, 0.5)):
        assert np.array_equal(sobol._mean_gauss(gamma, c, a, b), reference(gamma, c, a, b))
    calls = []

    def counted(fn):
        return lambda v: calls.append(np.size(v)) or fn(v)

    monkeypatch.setattr(sobol, "erf", counted(erf))
    monkeypatch.setattr(sobol, "erfc", counted(erfc))
    sobol._mean_gauss(30.0, c, 0.0, 1.0)
    assert sum(calls) == 2 * c.size
