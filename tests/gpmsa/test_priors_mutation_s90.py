"""``gpmsa.model.priors`` pinned exactly (the mutation testing of session 90): each log prior at a
chosen point against scipy.stats' own density (less its normalising constant), every bound and
limit at its edge (just inside, on it), defaults of keyword arguments, the stored types, and the
refusals of bad input by their messages."""

from __future__ import annotations

import dataclasses
import json
import math
import warnings

import numpy as np
import pytest
from scipy import special, stats

from gpmsa.errors import GPMSAError
from gpmsa.model.priors import (
    MAX_PRIOR_SHAPE,
    GammaPrior,
    Priors,
    theta_prior_overflow,
)

G1, G2 = GammaPrior(2.0, 0.5, 1.0, 8.0), GammaPrior(4.0, 3.0)
"""Two distinct lamVz group priors (the first bounded on both sides)."""


def _gamma_log_kernel(x, a: float, b: float) -> float:
    """scipy's Gamma(a, rate b) log density less its log normaliser a log b - lgamma(a)."""
    x = np.asarray(x, dtype=np.float64)
    return float(np.sum(stats.gamma.logpdf(x, a, scale=1.0 / b) - a * math.log(b)
                        + special.gammaln(a)))  # fmt: skip


def _beta_log_kernel(beta, a: float, b: float, cap: float = 0.999) -> float:
    """scipy's Beta(a, b) log density of rho = min(exp(-beta/4), cap), plus log B(a, b)."""
    rho = np.minimum(np.exp(-0.25 * np.asarray(beta, dtype=np.float64)), cap)
    return float(np.sum(stats.beta.logpdf(rho, a, b) + special.betaln(a, b)))


def _normal_log_kernel(theta, mean, sd) -> float:
    """scipy's Normal(mean, sd) log density plus log(sd sqrt(2 pi))."""
    theta, mean, sd = (np.asarray(v, dtype=np.float64) for v in (theta, mean, sd))
    return float(
        np.sum(stats.norm.logpdf(theta, mean, sd) + np.log(sd) + 0.5 * math.log(2 * math.pi))
    )


# -- theta_prior_overflow: both limits at their edges ---------------------------------------


@pytest.mark.parametrize(
    ("mean", "sd", "bad"),
    [
        (0.5, 7.5e-155, None),  # 1/sd**2 = 1.78e308, still finite
        (0.5, 7.4e-155, "theta_sd"),  # 1/sd**2 = 1.83e308: inf
        (0.5, 1e-154, None),  # z = 0.5/sd = 5e153: z**2 = 2.5e307
        (0.0, 7.5e-155, None),  # z = 1/sd = 1.33e154: z**2 = 1.78e308
        (1.0, 7.5e-155, None),
        (-0.1, 7.5e-155, "theta_mean"),  # z = 1.1/sd = 1.47e154: z**2 overflows
        (1.1, 7.5e-155, "theta_mean"),
        (1.34e154, 1.0, None),  # z**2 = 1.7956e308 < 1.7977e308
        (1.35e154, 1.0, "theta_mean"),
        (-1.34e154, 1.0, None),
        (-1.35e154, 1.0, "theta_mean"),
    ],
)
def test_theta_prior_overflow_at_its_edges(mean, sd, bad):
    got = theta_prior_overflow(mean, sd)
    assert (got if got is None else got[0]) == bad
    if bad is None:
        Priors(theta_mean=mean, theta_sd=sd)  # accepted
    else:
        with pytest.raises(GPMSAError, match=rf"^Priors\.{bad} = "):
            Priors(theta_mean=mean, theta_sd=sd)


def test_an_overflowing_per_element_theta_prior_is_named_with_its_index():
    with pytest.raises(GPMSAError, match=r"^Priors\.theta_mean\[1\] = 1\.1 is too far"):
        Priors(theta_mean=[0.5, 1.1], theta_sd=7.5e-155)
    with pytest.raises(GPMSAError, match=r"^Priors\.theta_sd\[0\] = 7\.4e-155 is too small"):
        Priors(theta_mean=[0.5, 0.5], theta_sd=[7.4e-155, 1.0])


# -- GammaPrior ------------------------------------------------------------------------------


def test_gamma_shape_limit_at_its_edge():
    assert GammaPrior(MAX_PRIOR_SHAPE, 1.0).a == 1e12
    with pytest.raises(GPMSAError, match=r"^Gamma prior needs 0 < a <= 1e\+12 and b > 0 finite"):
        GammaPrior(float(np.nextafter(1e12, np.inf)), 1.0)


@pytest.mark.parametrize(
    ("kw", "msg"),
    [
        ({"a": 0.0, "b": 1.0}, "got a=0.0, b=1.0"),
        ({"a": 1.0, "b": 0.0}, "got a=1.0, b=0.0"),
        ({"a": 1.0, "b": math.inf}, "got a=1.0, b=inf"),
        ({"a": math.nan, "b": 1.0}, "got a=nan, b=1.0"),
    ],
)
def test_gamma_parameters_refused_at_their_edges(kw, msg):
    with pytest.raises(
        GPMSAError, match=r"^Gamma prior needs 0 < a <= 1e\+12 and b > 0 finite, " + msg
    ):
        GammaPrior(**kw)


@pytest.mark.parametrize(
    ("lower", "upper", "ok"),
    [
        (0.0, math.inf, True),
        (0.0, 5e-324, True),
        (-5e-324, 1.0, False),
        (1.0, 1.0, False),
        (2.0, 1.0, False),
        (math.inf, math.inf, False),
        (0.0, math.nan, False),
    ],
)
def test_gamma_bounds_at_their_edges(lower, upper, ok):
    if ok:
        assert GammaPrior(1.0, 1.0, lower, upper).upper == upper
    else:
        with pytest.raises(GPMSAError, match=r"^Gamma bounds need 0 <= lower < upper, got "):
            GammaPrior(1.0, 1.0, lower, upper)


def test_gamma_fields_are_stored_as_floats_and_frozen():
    g = GammaPrior(np.int64(2), np.float32(0.5), 1, np.int32(9))
    assert [type(getattr(g, k)) for k in ("a", "b", "lower", "upper")] == [float] * 4
    assert json.dumps(Priors(lamOs=g).to_dict()["lamOs"]) == (
        '{"a": 2.0, "b": 0.5, "lower": 1.0, "upper": 9.0}'
    )
    with pytest.raises(dataclasses.FrozenInstanceError):
        g.a = 3.0  # type: ignore[misc]
    assert hash(g) == hash(GammaPrior(2.0, 0.5, 1.0, 9.0))


@pytest.mark.parametrize("bad", [True, "1", None, np.array([1.0])])
def test_gamma_fields_that_are_no_real_number_are_named(bad):
    with pytest.raises(GPMSAError, match=r"^GammaPrior\.b must be a real number, got "):
        GammaPrior(1.0, bad)


def test_gamma_log_density_is_scipys_less_its_constant():
    g = GammaPrior(3.5, 0.25)
    x = np.array([0.3, 2.0, 11.0])
    assert g.log_density(x) == pytest.approx(_gamma_log_kernel(x, 3.5, 0.25), rel=1e-13)
    # by hand: (a - 1) log x - b x
    assert g.log_density(2.0) == pytest.approx(2.5 * math.log(2.0) - 0.5, rel=1e-15)


def test_gamma_log_density_bounds_are_open():
    g = GammaPrior(2.0, 1.0, 1.0, 4.0)
    assert g.log_density(1.0) == -np.inf
    assert g.log_density(4.0) == -np.inf
    assert g.log_density([2.0, 4.0]) == -np.inf
    assert g.log_density([1.0, 2.0]) == -np.inf
    lo, hi = np.nextafter(1.0, 2.0), np.nextafter(4.0, 0.0)
    assert g.log_density(lo) == pytest.approx(math.log(lo) - lo, rel=1e-15)
    assert g.log_density(hi) == pytest.approx(math.log(hi) - hi, rel=1e-15)


# -- Priors: construction and refusals -------------------------------------------------------


def test_priors_are_frozen_and_hashable():
    p = Priors()
    with pytest.raises(dataclasses.FrozenInstanceError):
        p.rho_a = 2.0  # type: ignore[misc]
    assert hash(p) == hash(Priors())


@pytest.mark.parametrize(
    ("kw", "msg"),
    [
        ({"rho_a": 0.0}, r"^Priors\.rho_a must be finite and > 0, got 0\.0$"),
        ({"rho_b": math.inf}, r"^Priors\.rho_b must be finite and > 0, got inf$"),
        ({"rho_b": math.nan}, r"^Priors\.rho_b must be finite and > 0, got nan$"),
        ({"rho_cap": 1.0}, r"^Priors\.rho_cap must be in \(0, 1\), got 1\.0$"),
        ({"rho_cap": 0.0}, r"^Priors\.rho_cap must be in \(0, 1\), got 0\.0$"),
        ({"rho_a": True}, r"^Priors\.rho_a must be a real number, got True \(bool\)$"),
        ({"lamUz": 1.0}, r"^Priors\.lamUz must be a gpmsa\.GammaPrior, got 1\.0$"),
        ({"lamOs": None}, r"^Priors\.lamOs must be a gpmsa\.GammaPrior, got None$"),
        ({"corrected": 1}, r"^Priors\.corrected must be True or False, got 1$"),
        ({"lamVz": []}, r"^Priors\.lamVz must be a gpmsa\.GammaPrior .* or a non-empty list"),
        ({"lamVz": [G1, 1.0]}, r"^Priors\.lamVz must be a gpmsa\.GammaPrior"),
        ({"theta_mean": []}, r"^Priors\.theta_mean must be a number or a non-empty sequence"),
        ({"theta_sd": [1.0, 0.0]}, r"^Priors\.theta_sd\[1\] must be finite and > 0, got 0\.0$"),
        ({"theta_sd": 0.0}, r"^Priors\.theta_sd must be finite and > 0, got 0\.0$"),
        ({"theta_mean": [0.5, "x"]}, r"^Priors\.theta_mean\[1\] must be a real number, got 'x'"),
        (
            {"theta_mean": [0.5, 0.5], "theta_sd": [1.0]},
            r"^Priors\.theta_mean gives 2 .* Priors\.theta_sd 1:",
        ),
        ({"rhoV_a": 1.0}, r"^Priors\.rhoV_a and Priors\.rhoV_b set betaV's Beta prior together"),
        ({"rhoV_b": 1.0}, r"^Priors\.rhoV_a and Priors\.rhoV_b set betaV's Beta prior together"),
        ({"rhoV_a": 1.0, "rhoV_b": [1.0]}, r"^Priors\.rhoV_a and Priors\.rhoV_b must both be"),
        (
            {"rhoV_a": [1.0, 2.0], "rhoV_b": [1.0]},
            r"^Priors\.rhoV_a and Priors\.rhoV_b must both be",
        ),
        (
            {"rhoV_a": [1.0], "rhoV_b": [0.0]},
            r"^Priors\.rhoV_b\[0\] must be finite and > 0, got 0\.0$",
        ),
    ],
)
def test_bad_priors_are_refused_by_name(kw, msg):
    with pytest.raises(GPMSAError, match=msg):
        Priors(**kw)


def test_rho_cap_just_inside_its_interval_is_kept():
    assert Priors(rho_cap=5e-324).rho_cap == 5e-324
    assert Priors(rho_cap=float(np.nextafter(1.0, 0.0))).rho_cap < 1.0


def test_per_element_and_shared_values_are_stored_as_floats():
    p = Priors(
        theta_mean=np.array([0, 1]), theta_sd=2, rhoV_a=[np.int64(3)], rhoV_b=(np.float32(0.5),)
    )
    assert p.theta_mean == (0.0, 1.0) and type(p.theta_mean[0]) is float
    assert p.theta_sd == 2.0 and type(p.theta_sd) is float
    assert p.rhoV_a == (3.0,) and type(p.rhoV_a[0]) is float
    assert p.rhoV_b == (0.5,) and type(p.rhoV_b[0]) is float
    q = Priors(rhoV_a=[1.0, 2.0], rhoV_b=[3.0, 4.0])
    assert (q.rhoV_a, q.rhoV_b) == ((1.0, 2.0), (3.0, 4.0))
    assert p.theta_count == 2 and Priors(theta_sd=[1.0, 2.0, 3.0]).theta_count == 3
    assert Priors().theta_count is None


# -- theta ---------------------------------------------------------------------------------


def test_log_theta_is_scipys_normal_less_its_constant():
    p = Priors(theta_mean=0.3, theta_sd=0.2)
    theta = np.array([0.1, 0.45, 0.9])
    assert p.log_theta(theta) == pytest.approx(_normal_log_kernel(theta, 0.3, 0.2), rel=1e-13)
    assert p.log_prior("theta", [0.7]) == pytest.approx(-0.5 * (0.4 / 0.2) ** 2, rel=1e-15)
    per = Priors(theta_mean=[0.2, 0.6], theta_sd=[0.1, 0.5])
    assert per.log_theta([0.3, 0.1]) == pytest.approx(-0.5 * (1.0 + 1.0), rel=1e-15)
    assert per.log_theta([0.1], elements=[1]) == pytest.approx(-0.5, rel=1e-15)
    assert per.log_theta([0.3], elements=[0]) == pytest.approx(-0.5, rel=1e-15)


def test_log_theta_of_a_batch_reads_elements_along_the_last_axis():
    per = Priors(theta_mean=[0.2, 0.6], theta_sd=[0.1, 0.5])
    batch = np.array([[0.3, 0.1], [0.2, 0.6], [0.1, 0.85]])  # (3, q = 2)
    assert per.log_prior("theta", batch) == pytest.approx(
        -0.5 * (1 + 1 + 0 + 0 + 1 + 0.25), rel=1e-14
    )


def test_log_theta_bounds_are_open():
    p = Priors()
    assert p.log_theta([0.0, 0.5]) == -np.inf
    assert p.log_theta([0.5, 1.0]) == -np.inf
    assert np.isfinite(p.log_theta([5e-324, float(np.nextafter(1.0, 0.0))]))


def test_log_theta_checks_per_element_priors_against_the_vector():
    per = Priors(theta_mean=[0.2, 0.6])
    with pytest.raises(GPMSAError, match=r"^Priors\.theta_mean gives 2 per-element .* q = 3 "):
        per.log_theta([0.5, 0.5, 0.5])
    with pytest.raises(GPMSAError, match=r"^Priors\.theta_sd gives 2 per-element .* q = 1 "):
        Priors(theta_sd=[1.0, 2.0]).log_theta(0.5)


def test_theta_moments():
    assert Priors(theta_mean=0.2, theta_sd=3.0).theta_moments(7) == (0.2, 3.0)
    per = Priors(theta_mean=[0.2, 0.6, 0.7], theta_sd=4.0)
    m, s = per.theta_moments(3)
    np.testing.assert_array_equal(m, [0.2, 0.6, 0.7])
    np.testing.assert_array_equal(s, [4.0, 4.0, 4.0])
    m[0] = 9.0  # a copy
    assert per.theta_moments()[0][0] == 0.2
    m, s = per.theta_moments(None, [2, 0])
    np.testing.assert_array_equal(m, [0.7, 0.2])
    assert per.theta_prior(1) == (0.6, 4.0)


# -- beta ----------------------------------------------------------------------------------


def test_log_beta_is_scipys_beta_of_rho_less_its_constant():
    p = Priors(rho_a=2.5, rho_b=0.7)
    beta = np.array([[0.3, 2.0], [7.0, 40.0]])
    assert p.log_beta(beta) == pytest.approx(_beta_log_kernel(beta, 2.5, 0.7), rel=1e-13)
    # by hand at beta = 4: rho = e^-1
    expect = 1.5 * -1.0 + -0.3 * math.log1p(-math.exp(-1.0))
    assert p.log_prior("betaU", [4.0]) == pytest.approx(expect, rel=1e-15)


def test_log_beta_caps_rho():
    p = Priors(rho_a=3.0, rho_b=0.5, rho_cap=0.9)
    small = 1e-3  # rho = exp(-small/4) > 0.9: capped
    expect = 2.0 * math.log(0.9) - 0.5 * math.log(0.1)
    assert p.log_beta([small]) == pytest.approx(expect, rel=1e-14)
    assert p.scalar_log_prior("betaU")(small) == pytest.approx(expect, rel=1e-14)


def test_log_beta_bounds_and_underflow():
    p = Priors(rho_a=2.0, rho_b=3.0)
    assert p.log_beta([0.0, 1.0]) == -np.inf
    assert p.log_beta([1.0, math.inf]) == -np.inf
    assert p.log_beta([1.0, math.nan]) == -np.inf
    assert np.isfinite(p.log_beta([5e-324]))
    # rho = exp(-1e4 / 4) underflows to 0: log(rho) is -beta/4 itself
    assert p.log_beta([1e4]) == pytest.approx(-2500.0, rel=1e-15)
    assert p.scalar_log_prior("betaU")(1e4) == pytest.approx(-2500.0, rel=1e-15)


def test_an_underflowing_rho_takes_no_log_of_zero():
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # log(0) would warn "divide by zero"
        assert Priors(rho_a=3.0).log_beta([1e4, 2e4]) == pytest.approx(2.0 * -7500.0, rel=1e-15)


def test_betav_uses_its_own_prior_per_group():
    p = Priors(rho_a=1.0, rho_b=0.1, rhoV_a=[2.0, 5.0], rhoV_b=[3.0, 0.5])
    beta = np.array([[0.5, 1.5], [3.0, 9.0]])  # (p, G): column g under group g's prior
    expect = _beta_log_kernel(beta[:, 0], 2.0, 3.0) + _beta_log_kernel(beta[:, 1], 5.0, 0.5)
    assert p.log_beta(beta, "betaV") == pytest.approx(expect, rel=1e-13)
    assert p.log_prior("betaV", beta) == pytest.approx(expect, rel=1e-13)
    assert p.log_beta(beta, "betaU") == pytest.approx(_beta_log_kernel(beta, 1.0, 0.1), rel=1e-13)
    assert p.rho_prior("betaV") == (2.0, 3.0)
    assert p.rho_prior("betaV", 1) == (5.0, 0.5)
    assert p.rho_prior("betaU", 1) == (1.0, 0.1)
    assert p.scalar_log_prior("betaV", 1)(9.0) == pytest.approx(_beta_log_kernel(9.0, 5.0, 0.5),
                                                                 rel=1e-13)  # fmt: skip
    assert p.scalar_log_prior("betaV")(9.0) == pytest.approx(_beta_log_kernel(9.0, 2.0, 3.0),
                                                              rel=1e-13)  # fmt: skip
    a, b = p.rho_arrays("betaV", 2)
    np.testing.assert_array_equal(a, [2.0, 5.0])
    np.testing.assert_array_equal(b, [3.0, 0.5])
    assert p.rho_arrays("betaU", 2) == (1.0, 0.1)
    assert p.rhov_priors(2) == ((2.0, 3.0), (5.0, 0.5))
    one = Priors(rhoV_a=[2.0], rhoV_b=[3.0])  # a 0-d betaV: one group
    assert one.log_beta(4.0, "betaV") == pytest.approx(_beta_log_kernel(4.0, 2.0, 3.0), rel=1e-13)
    for g in (2, -1):
        with pytest.raises(
            GPMSAError, match=rf"^Priors\.rhoV_a, rhoV_b give 2 .* none for group {g}:"
        ):
            p.rho_prior("betaV", g)
    with pytest.raises(
        GPMSAError, match=r"^Priors\.rhoV_a, rhoV_b give 2 per-group .* has 3 precision"
    ):
        p.rhov_priors(3)


def test_betav_with_a_shared_or_no_own_prior():
    shared = Priors(rhoV_a=2.0, rhoV_b=3.0)
    assert shared.rhov_priors(2) == ((2.0, 3.0), (2.0, 3.0))
    assert shared.rho_prior("betaV", 5) == (2.0, 3.0)
    assert shared.rho_arrays("betaV", 2) == (2.0, 3.0)
    assert Priors(rho_a=4.0, rho_b=0.5).rhov_priors(3) == ((4.0, 0.5),) * 3
    assert not Priors().rhov_per_group and not shared.rhov_per_group


# -- precisions ----------------------------------------------------------------------------


def test_precision_log_priors_are_scipys_less_their_constants():
    p = Priors()
    for name, x, a, b in [("lamUz", 2.0, 5.0, 5.0), ("lamWs", 900.0, 3.0, 3e-3),
                          ("lamWOs", 1500.0, 5.0, 5e-3), ("lamOs", 3.0, 1.0, 1e-3),
                          ("lamVz", 40.0, 1.0, 1e-3)]:  # fmt: skip
        assert p.log_prior(name, [x]) == pytest.approx(
            _gamma_log_kernel(x, a, b), rel=1e-13, abs=1e-15
        )
        assert p.scalar_log_prior(name)(x) == pytest.approx(_gamma_log_kernel(x, a, b), rel=1e-13,
                                                            abs=1e-15)  # fmt: skip


def test_scalar_precision_bounds_are_open():
    f = Priors().scalar_log_prior("lamWs")
    assert f(60.0) == -math.inf and f(1e5) == -math.inf
    x = float(np.nextafter(60.0, 61.0))
    assert f(x) == pytest.approx(2.0 * math.log(x) - 3e-3 * x, rel=1e-15)
    x = float(np.nextafter(1e5, 0.0))
    assert f(x) == pytest.approx(2.0 * math.log(x) - 3e-3 * x, rel=1e-15)


def test_scalar_theta_prior_and_its_bounds():
    f = Priors(theta_mean=[0.2, 0.6], theta_sd=[0.1, 0.5]).scalar_log_prior("theta", 1)
    assert f(0.1) == pytest.approx(-0.5, rel=1e-15)
    assert f(0.0) == -math.inf and f(1.0) == -math.inf
    assert f(5e-324) == pytest.approx(-0.5 * 1.2**2, rel=1e-15)
    g = Priors(theta_mean=[0.2, 0.6], theta_sd=[0.1, 0.5]).scalar_log_prior("theta")
    assert g(0.3) == pytest.approx(-0.5, rel=1e-15)


def test_scalar_beta_prior_bounds():
    f = Priors().scalar_log_prior("betaU")
    assert f(0.0) == -math.inf and f(math.inf) == -math.inf and f(math.nan) == -math.inf
    assert f(5e-324) == pytest.approx(-0.9 * math.log1p(-0.999), rel=1e-15)


def test_per_group_lamvz():
    p = Priors(lamVz=[G1, G2])
    assert p.per_group and p.lamVz == (G1, G2) and not Priors().per_group
    x = np.array([3.0, 0.7])
    expect = _gamma_log_kernel(3.0, 2.0, 0.5) + _gamma_log_kernel(0.7, 4.0, 3.0)
    assert p.log_prior("lamVz", x) == pytest.approx(expect, rel=1e-13)
    assert p.log_prior("lamVz", [1.0, 0.7]) == -np.inf  # G1's open lower bound
    assert p.log_prior("lamVz", [8.0, 0.7]) == -np.inf  # G1's open upper bound
    assert p.log_prior("lamVz", [float(np.nextafter(8.0, 0.0)), 0.7]) > -np.inf
    assert p.precision_prior("lamVz") is G1
    assert p.precision_prior("lamVz", 1) is G2
    assert p.precision_prior("lamUz", 7) is p.lamUz
    assert p.scalar_log_prior("lamVz")(3.0) == pytest.approx(
        _gamma_log_kernel(3.0, 2.0, 0.5), rel=1e-13
    )
    assert p.scalar_log_prior("lamVz", 1)(0.7) == pytest.approx(_gamma_log_kernel(0.7, 4.0, 3.0),
                                                                rel=1e-13)  # fmt: skip
    for g in (2, -1):
        with pytest.raises(
            GPMSAError, match=rf"^Priors\.lamVz gives 2 per-group .* none for group {g}:"
        ):
            p.precision_prior("lamVz", g)
    with pytest.raises(
        GPMSAError, match=r"^Priors\.lamVz gives 2 per-group prior\(s\) but .* has 1 "
    ):
        p.lamvz_priors(1)
    assert p.lamvz_priors(2) == (G1, G2)
    assert Priors(lamVz=G2).lamvz_priors(3) == (G2, G2, G2)
    a, b, lo, hi = p.gamma_arrays("lamVz", 2)
    np.testing.assert_array_equal(
        np.stack([a, b, lo, hi]), [[2.0, 4.0], [0.5, 3.0], [1.0, 0.0], [8.0, np.inf]]
    )
    a, b, lo, hi = Priors().gamma_arrays("lamWs", 3)
    np.testing.assert_array_equal(
        np.stack([a, b, lo, hi]), [[3.0] * 3, [3e-3] * 3, [60.0] * 3, [1e5] * 3]
    )


def test_unknown_names_are_refused():
    p = Priors()
    with pytest.raises(GPMSAError, match=r"^unknown parameter name 'lam'$"):
        p.log_prior("lam", 1.0)
    with pytest.raises(GPMSAError, match=r"^unknown parameter name 'lam'$"):
        p.scalar_log_prior("lam")


# -- with_data, to_dict, from_dict ---------------------------------------------------------


def test_with_data_adds_the_corrections_once():
    p = Priors()
    c = p.with_data((10.0, 2.5), (4.0, 0.5))
    assert (c.lamWOs.a, c.lamWOs.b, c.lamWOs.lower, c.lamWOs.upper) == (15.0, 2.505, 60.0, 1e5)
    assert (c.lamOs.a, c.lamOs.b) == (5.0, 0.501)
    assert c.corrected and not p.corrected
    assert c.with_data((1.0, 1.0), (1.0, 1.0)) is c
    d = p.with_data((10.0, 2.5))  # os defaults to no correction
    assert d.lamOs == p.lamOs and d.lamWOs == c.lamWOs and d.corrected


def test_to_dict_and_back():
    p = Priors(theta_mean=[0.2, 0.6], lamVz=[G1, G2], rhoV_a=[2.0, 5.0], rhoV_b=[3.0, 0.5])
    d = p.to_dict()
    assert d["theta_mean"] == [0.2, 0.6] and d["theta_sd"] == 10.0
    assert d["rhoV_a"] == [2.0, 5.0] and d["rhoV_b"] == [3.0, 0.5]
    assert d["lamVz"] == [{"a": 2.0, "b": 0.5, "lower": 1.0, "upper": 8.0},
                          {"a": 4.0, "b": 3.0, "lower": 0.0, "upper": "inf"}]  # fmt: skip
    assert d["lamUz"] == {"a": 5.0, "b": 5.0, "lower": 0.3, "upper": "inf"}
    assert json.loads(json.dumps(d)) == d
    assert Priors.from_dict(json.loads(json.dumps(d))) == p
    plain = Priors().to_dict()
    assert "rhoV_a" not in plain and "rhoV_b" not in plain
    assert plain["lamVz"] == {"a": 1.0, "b": 1e-3, "lower": 0.0, "upper": "inf"}
    assert Priors.from_dict(plain) == Priors()
    shared = Priors(rhoV_a=2.0, rhoV_b=3.0).to_dict()
    assert (shared["rhoV_a"], shared["rhoV_b"]) == (2.0, 3.0)


@pytest.mark.parametrize(
    ("change", "msg"),
    [
        (
            lambda d: d.update(foo=1, bar=2),
            r"^Priors\.from_dict: unknown fields \['bar', 'foo'\]; known ",
        ),
        (lambda d: d.pop("lamWs"), r"^Priors\.from_dict: lamWs must be a dict with a, b"),
        (lambda d: d.update(lamVz=[]), r"^Priors\.from_dict: lamVz as a list needs one prior per "),
        (
            lambda d: d.update(lamVz=[{"a": 1.0, "b": 1.0}, 3]),
            r"^Priors\.from_dict: lamVz\[1\] must be a dict",
        ),
        (
            lambda d: d.update(lamOs={"a": 1.0}),
            r"^Priors\.from_dict: lamOs must be a dict with a, b",
        ),
        (
            lambda d: d.update(lamOs={"a": 1.0, "b": 1.0, "c": 1.0}),
            r"^Priors\.from_dict: lamOs must be",
        ),
        (
            lambda d: d.update(lamOs={"a": "1", "b": 1.0}),
            r"^Priors\.from_dict: lamOs\.a must be a number, got '1'$",
        ),
        (
            lambda d: d.update(lamOs={"a": True, "b": 1.0}),
            r"^Priors\.from_dict: lamOs\.a must be a number",
        ),
        (
            lambda d: d.update(lamOs={"a": 1.0, "b": "inf"}),
            r"^Priors\.from_dict: lamOs: Gamma prior needs 0 < a <= 1e\+12 and b > 0 finite, "
            r"got a=1\.0, b=inf$",
        ),
    ],
)
def test_from_dict_refusals_name_the_field(change, msg):
    d = Priors().to_dict()
    change(d)
    with pytest.raises(GPMSAError, match=msg):
        Priors.from_dict(d)


def test_from_dict_needs_a_dict_and_reads_inf_and_numpy_numbers():
    with pytest.raises(GPMSAError, match=r"^Priors\.from_dict needs a dict, got list$"):
        Priors.from_dict([])
    d = Priors().to_dict()
    d["lamOs"] = {"a": np.int64(2), "b": np.float32(0.5), "upper": "inf"}
    assert Priors.from_dict(d).lamOs == GammaPrior(2.0, 0.5)
    d["lamVz"] = [{"a": 1.0, "b": 2.0}]
    assert Priors.from_dict(d).lamVz == (GammaPrior(1.0, 2.0),)


# -- a NaN ----------------------------------------------------------------------------------


def test_a_nan_is_outside_every_bound_as_in_the_scalar_priors():
    """Fails before session 90's fix: the array priors of theta and of the precisions gave NaN
    for a NaN (``x <= lower`` and ``x >= upper`` both False), where the scalar priors (and betaU's
    array prior) give -inf."""
    p = Priors(lamVz=[G1, G2])
    nan = math.nan
    assert GammaPrior(2.0, 1.0).log_density([1.0, nan]) == -np.inf
    for name, value in [("theta", [0.5, nan]), ("lamOs", [nan]), ("lamUz", nan),
                        ("lamVz", [nan, 1.0]), ("betaU", [nan])]:  # fmt: skip
        assert p.log_prior(name, value) == -np.inf, name
        assert p.scalar_log_prior(name)(nan) == -math.inf, name
    assert p.log_theta([nan], elements=[1]) == -np.inf
