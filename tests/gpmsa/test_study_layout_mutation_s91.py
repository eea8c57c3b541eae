"""Exact checks of the study layout (``gpmsa.studies.layout``), from mutation testing of the
module (session 91): the hyperpriors' refusals and defaults at their edges, the precision's prior
density, the unit-value tolerance of a shared element, the parameter-name lists and the checks
a study makes of its layout, each with a hand-computed expectation."""

from __future__ import annotations

import dataclasses
import math
import re
import warnings

import numpy as np
import pytest

from gpmsa import Priors
from gpmsa.errors import GPMSAError, UnusedSettingWarning
from gpmsa.studies.layout import (
    SD_MAX_MIN,
    Element,
    HyperPriors,
    Layout,
    build_layout,
    check_hyper,
    check_study_names,
    finite,
    model_theta_priors,
)

EPS = np.finfo(float).eps


def _bounds(*pairs: tuple[float, float]) -> tuple[np.ndarray, np.ndarray]:
    """One model's native (t_min, t_max) from (lo, hi) per parameter."""
    return np.array([p[0] for p in pairs], float), np.array([p[1] for p in pairs], float)


def _two(shared=(), hierarchical=()) -> Layout:
    """Models a (E in (0, 1), k in (2, 3)) and b (E in (0, 1), m in (4, 5)), prior (0.5, 10)."""
    return build_layout(("a", "b"), [("E", "k"), ("E", "m")],
                        [_bounds((0, 1), (2, 3)), _bounds((0, 1), (4, 5))],
                        [(0.5, 10.0), (0.5, 10.0)], shared, hierarchical)  # fmt: skip


def _quiet(**kw) -> HyperPriors:
    """HyperPriors(**kw), any warning an error."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return HyperPriors(**kw)


# --- the dataclasses are frozen ------------------------------------------------------------


def test_hyperpriors_element_and_layout_are_frozen():
    layout = _two(shared=["E"])
    for obj, field in ((HyperPriors(), "mu_mean"), (layout.elements[0], "group"),
                       (layout, "groups")):  # fmt: skip
        with pytest.raises(dataclasses.FrozenInstanceError):
            setattr(obj, field, 0)
    assert isinstance(layout.elements[0], Element)


# --- HyperPriors: refusals -----------------------------------------------------------------


@pytest.mark.parametrize(("kw", "name"), [({"lam_start": "5"}, "lam_start"),
                                          ({"mu_mean": None}, "mu_mean"),
                                          ({"mu_sd": True}, "mu_sd"),
                                          ({"sd_max": False}, "sd_max")])  # fmt: skip
def test_a_non_number_is_refused_by_name(kw, name):
    with pytest.raises(GPMSAError, match=rf"^HyperPriors\.{name} must be a number, got "):
        HyperPriors(**kw)


def test_mu_range_at_exactly_1e150_sds_is_refused():
    # (|0.5 - 0.5| + 0.5) / 5e-151 is 1e150 exactly: the bound is exclusive
    assert (abs(0.5 - 0.5) + 0.5) / 5e-151 == 1e150
    with pytest.raises(GPMSAError, match=r"lies 1e\+150 sds from the mean"):
        HyperPriors(mu_sd=5e-151)
    assert HyperPriors(mu_sd=1e-150).mu_sd == 1e-150  # 5e149 sds: kept


def test_mu_range_counts_from_the_unit_interval_centre():
    # mu_mean -0.5: (|-0.5 - 0.5| + 0.5) / 1e-150 = 1.5e150 sds, refused (|-0.5 + 0.5| would
    # give 5e149, kept)
    with pytest.raises(GPMSAError, match=r"lies 1\.5e\+150 sds"):
        HyperPriors(mu_mean=-0.5, mu_sd=1e-150)


def test_sd_max_whose_square_underflows_is_refused():
    with pytest.raises(
        GPMSAError, match=r"^HyperPriors\.sd_max=1e-200: its square and 4/sd_max\^2"
    ):
        HyperPriors(sd_max=1e-200)


def test_sd_max_whose_default_start_precision_overflows_is_refused():
    # sd_max = 2**-511: sd^2 = 2**-1022 (the smallest normal float) and 1/sd^2 = 2**1022 are
    # finite, but the default start lam 4/sd^2 = 2**1024 is not (it was inf, a value lam_start=
    # refuses, and to_dict wrote it as Infinity)
    with pytest.raises(GPMSAError, match=r"^HyperPriors\.sd_max=1\.49.*e-154: its square"):
        HyperPriors(sd_max=2.0**-511)
    up = math.nextafter(2.0**-511, 1.0)
    h = HyperPriors(sd_max=up)
    assert h.lam_start == 4.0 / (up * up) and math.isfinite(h.lam_start)
    assert HyperPriors(**h.to_dict()) == h


def test_default_start_precision():
    assert HyperPriors().lam_start == 5.0  # sd_max 1: 5 * 1 > 1, SEPIA's 5
    assert HyperPriors(sd_max=0.5).lam_start == 5.0  # 5 * 0.25 = 1.25 > 1
    # 5 * 0.42**2 = 0.882: 5 would start outside (0, sd_max); 4 / sd_max**2, an sd of 0.21
    assert HyperPriors(sd_max=0.42).lam_start == 4.0 / 0.42**2 == 22.67573696145125
    assert HyperPriors(sd_prior="gamma").lam_start == 5.0


def test_start_precision_at_the_uniform_sd_bound_is_refused():
    # lam_start 4 with sd_max 0.5: start sd 1/sqrt(4) = 0.5 = sd_max, outside (0, 0.5)
    with pytest.raises(
        GPMSAError,
        match=r"^HyperPriors\.lam_start=4\.0 gives a start sd 0\.5 "
        r"outside the uniform sd prior's \(0, sd_max=0\.5\)$",
    ):
        HyperPriors(sd_max=0.5, lam_start=4.0)
    assert HyperPriors(sd_max=0.5, lam_start=6.0).lam_start == 6.0  # start sd 0.408
    assert HyperPriors(sd_prior="gamma", lam_start=0.5).lam_start == 0.5  # no sd bound


def test_gamma_settings_warn_only_under_the_uniform_sd_prior():
    _quiet()
    _quiet(sd_prior="gamma", lam_a=2.0, lam_b=0.5)
    with pytest.warns(UnusedSettingWarning, match=r"lam_a=1\.0 and lam_b=0\.5 set the gamma"):
        HyperPriors(lam_b=0.5)


# --- HyperPriors: the precision's prior ----------------------------------------------------


def test_uniform_sd_prior_of_the_precision():
    h = HyperPriors(sd_max=0.5)
    assert h.lam_min == 4.0  # sd_max**-2
    assert h.log_prior_lam(4.0) == -math.inf  # sd = sd_max: the support is open
    assert h.log_prior_lam(3.0) == -math.inf
    assert h.log_prior_lam(16.0) == -1.5 * math.log(16.0)


def test_gamma_prior_of_the_precision():
    h = HyperPriors(sd_prior="gamma", lam_a=3.0, lam_b=0.5)
    assert h.lam_min == 0.0
    assert h.log_prior_lam(0.0) == -math.inf
    assert h.log_prior_lam(2.0) == 2.0 * math.log(2.0) - 1.0  # (a - 1) log lam - b lam


# --- Layout.same_unit_value ----------------------------------------------------------------


def _bounded(*bounds: tuple[float, float]) -> Layout:
    return Layout(("a",), (), (), (), tuple(bounds), ())


def test_same_unit_value_at_its_tolerance():
    layout = _bounded((0.0, 1.0), (-1.0, 1.0), (2.0, 6.0))
    tol = 2e-12 + 8 * EPS  # element 0: 2e-12 (|0| + |1|) / (1 - 0) + 8 eps
    assert tol == 2.0017763568394002e-12
    assert layout.same_unit_value(0, tol, 0.0) and layout.same_unit_value(0, 0.0, tol)
    assert not layout.same_unit_value(0, math.nextafter(tol, 1.0), 0.0)
    assert not layout.same_unit_value(0, 0.0, math.nextafter(tol, 1.0))
    # element 1: 2e-12 (1 + 1) / 2 + 8 eps, the same; |lo| counts
    assert layout.same_unit_value(1, 1e-12, 0.0) and not layout.same_unit_value(1, 3e-12, 0.0)
    # element 2: 2e-12 (2 + 6) / (6 - 2) + 8 eps = 4.0018e-12
    assert layout.same_unit_value(2, 0.25 + 3.9e-12, 0.25)
    assert not layout.same_unit_value(2, 0.25 + 4.1e-12, 0.25)


# --- parameter-name lists and build_layout's refusals --------------------------------------


@pytest.mark.parametrize(("shared", "match"), [
    ({"E": 2e11}, r"^shared must be a list of parameter names, got a dict \{'E'"),
    ({"E"}, r"^shared must be a list or tuple of parameter names, got a set \{'E'\}"),
    (5, r"^shared must be a sequence of parameter names, got 5$"),
])  # fmt: skip
def test_shared_names_that_are_no_list_are_refused(shared, match):
    with pytest.raises(GPMSAError, match=match):
        _two(shared=shared)


def test_a_name_list_holding_a_non_name_or_a_name_twice_is_refused():
    with pytest.raises(GPMSAError, match=r"^shared must hold parameter names \(str\), got 1$"):
        _two(shared=["E", 1])
    with pytest.raises(GPMSAError, match=r"^hierarchical names a parameter twice: \['E', 'E'\]$"):
        _two(hierarchical=("E", "E"))


def test_a_name_both_shared_and_hierarchical_is_refused():
    with pytest.raises(GPMSAError, match=r"^parameters \['E'\] are both shared and hierarchical"):
        _two(shared=["E"], hierarchical=("E",))


def test_bounds_for_fewer_models_than_labels_are_refused():
    with pytest.raises(
        GPMSAError,
        match=r"^got 2 models' parameter names and 1 models' ranges "
        r"for 2 labels$",
    ):
        build_layout(("a", "b"), [("E",), ("E",)], [_bounds((0, 1))], [(0.5, 10.0)] * 2)


def test_per_element_priors_of_another_count_are_refused():
    priors = Priors(theta_mean=(0.2, 0.3, 0.4))
    with pytest.raises(
        GPMSAError,
        match=r"gives 3 per-element theta prior\(s\) but the model "
        r"has q = 2",
    ):
        model_theta_priors(priors, 2)
    assert model_theta_priors(priors, 3) == [(0.2, 10.0), (0.3, 10.0), (0.4, 10.0)]


# --- a study's checks of its layout --------------------------------------------------------


@pytest.mark.parametrize("param", ["E[", "E]"])
def test_a_parameter_name_with_one_bracket_is_refused(param):
    layout = build_layout(("a",), [(param,)], [_bounds((0, 1))], [(0.5, 10.0)])
    with pytest.raises(GPMSAError, match=rf"^calibration parameter '{re.escape(param)}': "):
        check_study_names(layout)


def test_gamma_hyperpriors_with_an_sd_max_of_their_own():
    layout = _two(hierarchical=["E"])
    hyper = HyperPriors(sd_prior="gamma", sd_max=2.0)
    with pytest.raises(GPMSAError, match=r"^HyperPriors\.sd_max=2\.0 with sd_prior='gamma'"):
        check_hyper(hyper, True, layout)  # a new study by default
    assert check_hyper(hyper, True, layout, fresh=False) is None  # a continuation keeps them


def test_sd_max_at_the_smallest_a_study_runs_with():
    layout = _two(hierarchical=["E"])
    assert SD_MAX_MIN == 1e-3
    assert check_hyper(HyperPriors(sd_max=1e-3), True, layout) is None
    with pytest.raises(GPMSAError, match=r"^HyperPriors\.sd_max=0\.000999.* is below 0\.001"):
        check_hyper(HyperPriors(sd_max=math.nextafter(1e-3, 0.0)), True, layout)


def test_finite():
    assert finite(10**30) is True  # beyond numpy's isfinite, within float64
    assert finite(10**400) is False  # beyond float64
    assert finite(math.nan) is False and finite(-math.inf) is False
