"""Data validation, transforms and bases; bad input raises GPMSAError naming the problem."""

import subprocess
import sys
import warnings

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import gpmsa
from gpmsa.model.basis import basis_weights, discrepancy_basis, interpolate_basis, pca_basis
from gpmsa.model.problem import check_x_obs, prepare
from gpmsa.model.transforms import Standardizer


def sim(m=20, p=1, q=1, l=1, seed=0, **kw):
    rng = np.random.default_rng(seed)
    x, t = rng.random((m, p)), rng.random((m, q))
    y = np.sin(3 * x.sum(1, keepdims=True) + np.linspace(0, 1, l)) * (1 + t.sum(1, keepdims=True))
    return gpmsa.SimData(x=x, t=t, y=y, **kw)


@pytest.mark.parametrize(
    "kw, match",
    [
        ({"x": [[0.1], [np.nan]] * 10}, r"x must be finite, got nan at index \(1, 0\)"),
        ({"y": np.r_[np.ones(19), np.inf]}, "y must be finite, got inf"),
        ({"t": np.ones((21, 1))}, "same number of rows"),
        (
            {"x": np.c_[np.linspace(0, 1, 20), np.full(20, 3.0)]},
            r"design column x\[:, 1\] is constant",
        ),
        ({"y": np.ones(20)}, "y is constant"),
        ({"x": "abc"}, "x must be a numeric array"),
        ({"x_names": ["a", "b"]}, "x_names must have 1 entries"),
        ({"t_names": ["GD"], "t": np.ones((20, 1))}, "design column GD is constant"),
        ({"index": [1, 2]}, "index must have 1 entries"),
    ],
)
def test_simdata_bad_input(kw, match):
    rng = np.random.default_rng(0)
    base = {"x": rng.random((20, 1)), "t": rng.random((20, 1)), "y": rng.random(20)}
    base.update(kw)
    with pytest.raises(gpmsa.GPMSAError, match=match):
        gpmsa.SimData(**base)


def test_fewer_runs_than_parameters_refused():
    rng = np.random.default_rng(0)
    with pytest.raises(
        gpmsa.GPMSAError, match=r"at least p \+ q \+ 2 = 6 simulation runs .* got 5"
    ):
        gpmsa.SimData(x=rng.random((5, 2)), t=rng.random((5, 2)), y=rng.random(5))
    assert issubclass(gpmsa.GPMSAError, ValueError)


def test_obsdata_bad_input_and_ragged():
    with pytest.raises(gpmsa.GPMSAError, match=r"y_obs\[0\] must be finite"):
        gpmsa.ObsData(x=[[0.5]], y=[[np.nan]])
    with pytest.raises(gpmsa.GPMSAError, match="one row per x_obs row"):
        gpmsa.ObsData(x=[[0.5], [0.6]], y=[[1.0, 2.0, 3.0]])
    with pytest.raises(gpmsa.GPMSAError, match="precision must have one entry per experiment"):
        gpmsa.ObsData(x=[[0.5]], y=[[1.0]], precision=[1.0, 2.0])
    with pytest.raises(gpmsa.GPMSAError, match="symmetric positive definite"):
        gpmsa.ObsData(x=[[0.5]], y=[[1.0, 2.0]], precision=[[[1.0, 2.0], [2.0, 1.0]]])
    ragged = gpmsa.ObsData(x=[[0.2], [0.4]], y=[np.ones(3), np.ones(5)],
                           index=[np.linspace(0, 1, 3), np.linspace(0, 1, 5)])  # fmt: skip
    assert isinstance(ragged.y, list) and [len(e) for e in ragged.experiments] == [3, 5]


def test_observations_outside_design_warn_then_refused():
    s = sim()
    lo, hi = s.x.min(), s.x.max()
    with pytest.warns(UserWarning, match="outside the simulation design"):
        prepare(s, gpmsa.ObsData(x=[[hi + 0.05 * (hi - lo)]], y=[[1.0]]))
    with pytest.raises(gpmsa.GPMSAError, match=r"x_obs x0=.* lies outside the simulation .* by "
                                               r"more than 10% of its width"):  # fmt: skip
        prepare(s, gpmsa.ObsData(x=[[hi + 0.5 * (hi - lo)]], y=[[1.0]]))
    with pytest.raises(gpmsa.GPMSAError, match="one value per experiment"):
        prepare(s, gpmsa.ObsData(x=[[0.5]], y=[[1.0, 2.0]]))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        prepare(s, gpmsa.ObsData(x=[[0.5 * (lo + hi)]], y=[[1.0]]))


@settings(max_examples=50, deadline=None)
@given(
    data=arrays(np.float64, (12, 3), elements=st.floats(-1e6, 1e6, allow_nan=False)),
    shift=st.floats(-1e3, 1e3),
)
def test_standardizer_round_trip(data, shift):
    spread = np.ptp(data, axis=0)
    if np.any(spread < 1e-3 * (1 + np.abs(data).max(axis=0))):
        return
    design = (data[:, :2] - data[:, :2].min(axis=0)) / spread[:2]
    singular = np.linalg.svd(design - design.mean(axis=0), compute_uv=False)
    assume(singular[-1] > 1e-6 * singular[0])  # SimData refuses linearly dependent columns
    s = gpmsa.SimData(x=data[:, :1], t=data[:, 1:2] + shift, y=data[:, 2:])
    std = Standardizer.from_sim(s)
    xu = std.x_to_unit(s.x)
    assert xu.min() == pytest.approx(0.0, abs=1e-12) and xu.max() == pytest.approx(1.0, abs=1e-12)
    assert np.allclose(std.x_from_unit(xu), s.x, rtol=1e-9, atol=1e-9 * np.abs(s.x).max())
    assert np.allclose(std.t_from_unit(std.t_to_unit(s.t)), s.t, rtol=1e-9, atol=1e-6)
    ys = std.y_to_std(s.y)
    assert ys.mean() == pytest.approx(0, abs=1e-9) and ys.std(ddof=1) == pytest.approx(1)
    assert np.allclose(std.y_from_std(ys), s.y, rtol=1e-9, atol=1e-9 * np.abs(s.y).max())


def test_pca_basis_variance_fraction_and_weights():
    s = sim(m=30, l=40)
    std = Standardizer.from_sim(s)
    ys = std.y_to_std(s.y)
    K = pca_basis(ys)
    sv = np.linalg.svd(ys, compute_uv=False)
    share = np.cumsum(sv**2) / np.sum(sv**2)
    assert share[K.shape[1] - 1] >= 0.995 and (K.shape[1] == 1 or share[K.shape[1] - 2] < 0.995)
    assert np.allclose(K.T @ K, np.diag(sv[: K.shape[1]] ** 2 / 30))  # U S / sqrt(m)
    w = basis_weights(ys, K)
    assert np.allclose(w @ K.T, ys, atol=0.1)
    assert pca_basis(ys, n_pc=4).shape == (40, 4)
    assert np.array_equal(pca_basis(ys[:, :1]), [[1.0]])
    with pytest.raises(gpmsa.GPMSAError, match=r"n_pc must be in \[1, 30\], got 31"):
        pca_basis(ys, n_pc=31)
    for frac in (0.5, 0.9, 0.99, 0.9999):  # SEPIA's create_K_basis(n_pc=0.99): a fraction
        n = int(np.searchsorted(share, frac - 1e-12) + 1)
        assert n >= 1 and share[n - 1] >= frac and (n == 1 or share[n - 2] < frac)
        np.testing.assert_array_equal(pca_basis(ys, n_pc=frac), pca_basis(ys, n_pc=n))
    for bad in (1.0, 1.5, 0.0, -0.2, float("nan")):
        with pytest.raises(gpmsa.GPMSAError, match=r"an integer >= 1 \(components\) or a variance"):
            pca_basis(ys, n_pc=bad)
    grid = np.linspace(0, 1, 40)
    Ki = interpolate_basis(K, grid, grid[::3])
    assert np.allclose(Ki, K[::3])
    with pytest.raises(gpmsa.GPMSAError, match="within the simulation grid"):
        interpolate_basis(K, grid, np.array([1.5]))


def test_discrepancy_basis_normalised():
    grid = np.linspace(0, 2, 11)
    for kind in ("constant", "linear", np.c_[np.ones(11), grid**2]):
        D = discrepancy_basis(kind, grid)
        assert np.max(np.diag(D @ D.T)) == pytest.approx(1.0)
    assert discrepancy_basis(None, grid) is None
    assert discrepancy_basis("linear", grid).shape == (11, 2)
    with pytest.raises(gpmsa.GPMSAError, match="discrepancy must be None, 'constant'"):
        discrepancy_basis("quadratic", grid)


def test_prepare_gpmsa_priors_and_inits_multivariate():
    s = sim(m=25, l=30, seed=2)
    prep = prepare(s, gpmsa.ObsData(x=[[0.3], [0.6]], y=s.y[:2] + 0.1), discrepancy="linear")
    prob = prep.problem
    ys = prep.standardizer.y_to_std(s.y)
    p_u = prob.p_u
    resid = np.sum((ys - prob.w @ prep.K.T) ** 2)
    assert prob.priors.lamWOs.a == pytest.approx(5 + (30 - p_u) * 25 / 2)
    assert prob.priors.lamWOs.b == pytest.approx(0.005 + resid / 2)
    assert prob.init["lamWOs"][0] == min(
        max(100, prob.priors.lamWOs.a / prob.priors.lamWOs.b), 1e5 - 1
    )
    assert prob.obs.p_v == 2 and prob.obs.u.shape == (2, p_u) and prob.init["betaV"].shape == (1, 1)
    assert prob.names == ("theta", "betaV", "betaU", "lamVz", "lamUz", "lamWs", "lamWOs", "lamOs")
    assert prob.obs.sig_obs.shape == (2 * (2 + p_u),) * 2
    # GLS of y on [D, K] reproduces y up to the residual
    e = prob.obs.y_std[0]
    DK = np.hstack([prob.obs.D[0], prob.obs.K[0]])
    fit = DK @ np.r_[prob.obs.v[0], prob.obs.u[0]]
    assert np.linalg.norm(e - fit) < np.linalg.norm(e)
    assert prob.priors.lamOs.a == pytest.approx(1 + 0.5 * (2 * 30 - 2 * (2 + p_u)))


def test_backend_registry_and_lazy_torch():
    assert "numpy" in gpmsa.backends.available()
    assert gpmsa.backends.get("numpy").sample is not None
    with pytest.raises(gpmsa.GPMSAError, match=r"unknown backend 'stan'; registered: \('numpy'"):
        gpmsa.backends.get("stan")
    code = "import sys, gpmsa; gpmsa.load; sys.exit('torch' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code], check=False).returncode == 0


def test_observation_precision_and_ragged_grids():
    s = sim(m=25, l=30, seed=4, index=np.linspace(0, 1, 30))
    with pytest.raises(gpmsa.GPMSAError, match="experiment 0 has 1 values .* has 30; give ObsData"):
        prepare(s, gpmsa.ObsData(x=[[0.3], [0.6]], y=[[1.0], [2.0]]))
    s1 = sim(m=25, seed=4)
    p1 = prepare(s1, gpmsa.ObsData(x=[[0.3], [0.6]], y=[[1.0], [2.0]], precision=[4.0, 9.0]))
    sd1 = p1.standardizer.y_sd
    assert np.allclose(
        np.diag(p1.problem.obs.sig_obs), 1 / (np.array([4.0, 9.0]) * sd1**2), rtol=1e-6
    )
    full = prepare(s, gpmsa.ObsData(x=[[0.3]], y=s.y[:1], precision=[np.eye(30) * 4.0]))
    sd = full.standardizer.y_sd
    # GLS with a scalar precision: sig_obs = (K^T K lam + ridge)^-1, lam = 4 sd^2
    K = full.K
    expected = np.linalg.inv(
        K.T @ K * 4 * sd**2 + 1e-6 * np.eye(K.shape[1]) + 1e-8 * np.eye(K.shape[1])
    )
    assert np.allclose(full.problem.obs.sig_obs, expected, rtol=1e-6)
    grids = [np.linspace(0, 1, 12), np.linspace(0.2, 0.9, 7)]
    ys = [np.interp(g, s.grid, s.y[0]) for g in grids]
    rag = prepare(s, gpmsa.ObsData(x=[[0.3], [0.6]], y=ys, index=grids), discrepancy="constant")
    obs = rag.problem.obs
    p_u = rag.problem.p_u
    assert obs.u.shape == (2, p_u) and obs.v.shape == (2, 1)
    assert [k.shape for k in obs.K] == [(12, p_u), (7, p_u)]
    assert obs.sig_obs.shape == (2 * (1 + p_u),) * 2
    # the lamOs correction counts every observed element: 19 in all
    assert rag.problem.priors.lamOs.a == pytest.approx(1 + 0.5 * (19 - 2 * (1 + p_u)))


def test_inputs_at_a_rounded_domain_edge_count_as_inside():
    """A design whose top edge is stored as 2 - 2e-16 still accepts v = 2.0 without a warning."""
    rng = np.random.default_rng(3)
    v = np.linspace(0.5, 2.0, 30)
    v[-1] = 1.9999999999999998
    gd = rng.uniform(200, 600, 30)
    std = Standardizer.from_sim(gpmsa.SimData(x=v, t=gd, y=0.02 * gd * v**1.6))
    unit = std.x_to_unit(np.array([[2.0], [0.5]]))
    assert np.array_equal(unit, [[1.0], [0.0]])
    assert std.x_to_unit(np.array([[2.1]]))[0, 0] > 1.0  # beyond rounding: still outside
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_x_obs(std.x_to_unit(np.array([[2.0]])), ("v",))


@settings(max_examples=30, deadline=None)
@given(exponent=st.integers(155, 307), sign=st.sampled_from([-1.0, 1.0]))
def test_outputs_too_large_to_standardise_are_refused(exponent, sign):
    """y of order 1e155 and beyond: the sd's squares overflow, which gave y_sd = inf and NaN
    predictions; now SimData refuses y (and so does the Standardizer)."""
    rng = np.random.default_rng(0)
    x, t = rng.random((20, 1)), rng.random((20, 1))
    y = sign * 10.0**exponent * np.sin(3 * x + t)
    with pytest.raises(gpmsa.GPMSAError, match="y is too large to standardise"):
        gpmsa.SimData(x=x, t=t, y=y)


def test_large_but_standardisable_outputs_and_far_observations():
    s = sim(l=3)
    big = gpmsa.SimData(x=s.x, t=s.t, y=s.y * 1e150)
    std = Standardizer.from_sim(big)
    assert np.isfinite(std.y_sd) and np.all(np.isfinite(std.y_to_std(big.y)))
    far = gpmsa.ObsData(x=[[0.5]], y=[[1e308, -1e308, 1e308]])
    with pytest.raises(gpmsa.GPMSAError, match=r"y_obs\[0\] in standardised units must be finite"):
        prepare(gpmsa.SimData(x=s.x, t=s.t, y=s.y * 1e-100), far)


def test_an_input_cannot_be_both_known_and_calibrated():
    with pytest.raises(gpmsa.GPMSAError, match=r"x_names and t_names must not share a name.*'a'"):
        sim(p=2, q=1, x_names=["a", "b"], t_names=["a"])


COMPLEX = np.array([[0.5 + 1j]] * 20)


@pytest.mark.parametrize(
    ("kw", "match"),
    [({"x": COMPLEX}, "x must hold real numbers, got complex values"),
     ({"t": COMPLEX + 0j}, "t must hold real numbers"),
     ({"y": np.sin(np.arange(20.0)) + 0j}, "y must hold real numbers"),  # zero imaginary part
     ({"x": [[complex(v, 1)] for v in range(20)]}, "x must hold real numbers"),  # a list too
     ({"index": [1j]}, "index must hold real numbers")],
)  # fmt: skip
def test_complex_data_are_refused_not_cast(kw, match):
    rng = np.random.default_rng(0)
    base = {"x": rng.random((20, 1)), "t": rng.random((20, 1)), "y": rng.random(20)}
    with pytest.raises(gpmsa.GPMSAError, match=match):
        gpmsa.SimData(**{**base, **kw})


@pytest.mark.parametrize(
    ("kw", "match"),
    [({"y": np.array([[0.3 + 1j]])}, "y_obs must hold real numbers"),
     ({"y": [np.ones(3) + 0j, np.ones(2)]}, r"y_obs\[0\] must hold real numbers"),
     ({"x": np.array([[0.5 + 0j]])}, "x_obs must hold real numbers"),
     ({"index": np.array([1j])}, "index must hold real numbers"),
     ({"precision": [2 + 1j]}, r"precision\[0\] must hold real numbers"),
     ({"y": [["a"]]}, "y_obs must be a numeric array")],
)  # fmt: skip
def test_complex_observations_are_refused_not_cast(kw, match):
    with pytest.raises(gpmsa.GPMSAError, match=match):
        gpmsa.ObsData(**{"x": [[0.5]], "y": [[0.3]], **kw})


@pytest.mark.parametrize(
    ("kw", "match"),
    [({"theta_sd": 0}, r"Priors.theta_sd must be finite and > 0, got 0.0"),
     ({"theta_sd": -1.0}, "Priors.theta_sd must be finite and > 0"),
     ({"theta_mean": float("nan")}, "Priors.theta_mean must be finite, got nan"),
     ({"rho_a": 0}, "Priors.rho_a must be finite and > 0"),
     ({"rho_b": float("inf")}, "Priors.rho_b must be finite and > 0"),
     ({"rho_cap": 2}, r"Priors.rho_cap must be in \(0, 1\), got 2.0"),
     ({"rho_cap": float("nan")}, r"Priors.rho_cap must be in \(0, 1\)"),
     ({"rho_a": "a"}, r"Priors.rho_a must be a real number, got 'a' \(str\)"),
     ({"theta_sd": 1 + 1j}, r"Priors.theta_sd must be a real number, got \(1\+1j\)"),
     ({"lamUz": {"a": 1}}, "Priors.lamUz must be a gpmsa.GammaPrior"),
     ({"lamUz": (1, 1)}, "Priors.lamUz must be a gpmsa.GammaPrior"),
     ({"corrected": "no"}, "Priors.corrected must be True or False")],
)  # fmt: skip
def test_priors_are_validated_at_construction(kw, match):
    with pytest.raises(gpmsa.GPMSAError, match=match):
        gpmsa.Priors(**kw)


@pytest.mark.parametrize(
    ("args", "match"),
    [((float("nan"), 1.0), "Gamma prior needs 0 < a <= 1e\\+12 and b > 0 finite"),
     ((1.0, float("inf")), "Gamma prior needs"),
     ((1e13, 1.0), "Gamma prior needs 0 < a <= 1e\\+12"),
     ((1.0, 1.0, float("nan")), "Gamma bounds need 0 <= lower < upper"),
     ((1.0, 1.0, 0.0, float("nan")), "Gamma bounds need 0 <= lower < upper"),
     ((1.0, 1.0, float("inf"), float("inf")), "Gamma bounds need"),
     (("a", 1.0), r"GammaPrior.a must be a real number, got 'a' \(str\)"),
     ((1 + 1j, 1.0), "GammaPrior.a must be a real number"),
     (([1, 2], 1.0), r"GammaPrior.a must be a real number, got \[1, 2\] \(list\)")],
)  # fmt: skip
def test_gamma_priors_are_validated_at_construction(args, match):
    with pytest.raises(gpmsa.GPMSAError, match=match):
        gpmsa.GammaPrior(*args)


@settings(max_examples=40, deadline=None)
@given(
    theta_mean=st.floats(-1e3, 1e3),
    theta_sd=st.floats(1e-3, 1e3),
    rho_cap=st.floats(0.01, 0.99),
    a=st.floats(1e-3, 1e12),
    b=st.floats(1e-12, 1e6),
)
def test_valid_priors_round_trip_through_the_file_checks(theta_mean, theta_sd, rho_cap, a, b):
    """Every Priors the constructor accepts is one the emulator file's validator accepts."""
    from gpmsa.fitting.validation import check_priors

    pri = gpmsa.Priors(theta_mean=theta_mean, theta_sd=theta_sd, rho_cap=rho_cap,
                       lamUz=gpmsa.GammaPrior(a, b, 0.3))  # fmt: skip
    check_priors(pri.to_dict())
    assert gpmsa.Priors.from_dict(pri.to_dict()) == pri


def test_a_design_column_in_small_units_varies():
    """Constancy is judged relative to the column's own size: a parameter in m^2 (1e-15 to 1e-13)
    is a design column like any other, and the emulator is the same as in scaled units."""
    rng = np.random.default_rng(0)
    k, x = 10 ** rng.uniform(-15, -13, (40, 1)), rng.uniform(0, 1, (40, 1))
    y = np.log10(k) + x
    small = gpmsa.SimData(x=x, t=k, y=y, t_names=["k"])
    scaled = gpmsa.SimData(x=x, t=k * 1e14, y=y, t_names=["k"])
    emus = [gpmsa.fit(d, n_iter=100, seed=0) for d in (small, scaled)]
    for name in emus[0].params:
        np.testing.assert_allclose(emus[0].params[name], emus[1].params[name], rtol=1e-9)
    with pytest.raises(gpmsa.GPMSAError, match=r"design column k is constant \(1e-14\)"):
        gpmsa.SimData(x=x, t=np.full((40, 1), 1e-14), y=y, t_names=["k"])
    with pytest.raises(gpmsa.GPMSAError, match=r"k varies by only 1 around 1e\+15 .*offset"):
        gpmsa.SimData(x=x, t=x + 1e15, y=y, t_names=["k"])  # was "constant (1e15)"


def test_names_and_units_any_ordered_sequence_but_not_a_set_or_number():
    s = sim(p=1, q=2, x_names=(n for n in ["a"]), t_names=iter(["b", "c"]), t_units=iter("uv"))
    assert s.x_names == ("a",) and s.t_names == ("b", "c") and s.t_units == ("u", "v")
    for kw in (
        {"t_names": {"b", "c"}},
        {"t_names": {"b": 0, "c": 1}},
        {"x_units": 3},
        {"x_names": b"a"},
    ):
        key = next(iter(kw))
        with pytest.raises(gpmsa.GPMSAError, match=rf"{key} must be a list of .*, one per column"):
            sim(p=1, q=2, **kw)


def test_precision_symmetry_is_relative_to_its_scale():
    """A precision in small units (1/Pa^2, say) is checked for symmetry as any other: an
    absolute tolerance would pass any matrix whose entries are below it."""
    lopsided = [[[1e-10, 5e-11], [0.0, 1e-10]]]
    with pytest.raises(gpmsa.GPMSAError, match=r"precision\[0\] must be symmetric"):
        gpmsa.ObsData(x=[[0.5]], y=[[1.0, 2.0]], precision=lopsided)
    small = gpmsa.ObsData(x=[[0.5]], y=[[1.0, 2.0]], precision=[[[2e-10, 5e-11], [5e-11, 1e-10]]])
    assert small.precisions[0][0, 1] == 5e-11
