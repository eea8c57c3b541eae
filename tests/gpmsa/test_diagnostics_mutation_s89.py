"""Exact tests of `gpmsa.mcmc.diagnostics`, written from a mutation run over the module (s89):
each pins a boundary, a wording or a value that a single-site change of the source would alter
and that no other test noticed. ESS, R-hat, autocorrelation and HDI are compared with ArviZ on
small fixed arrays, and the split R-hat also with the formula of Vehtari et al. (2021) computed
here by hand."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from scipy.stats import norm, rankdata

from gpmsa.errors import ConvergenceWarning, GPMSAError
from gpmsa.mcmc import diagnostics as dg

X = np.array([0.3, -1.2, 0.8, 2.1, -0.4, 0.9, 1.7, -0.6, 0.2, 1.1, -0.9, 0.5, 1.4, -0.1, 0.7, 2.4])
"""Sixteen fixed draws."""


def _arviz():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        import arviz
    return arviz


# --- names, numbers shown, units ----------------------------------------------------------------
def test_element_names_of_a_scalar_a_vector_and_a_matrix():
    assert dg.element_names("s", ()) == ["s"]
    assert dg.element_names("v", (1,)) == ["v[0]"]
    assert dg.element_names("v", (3,)) == ["v[0]", "v[1]", "v[2]"]
    assert dg.element_names("m", (2, 3)) == [
        "m[0,0]", "m[0,1]", "m[0,2]", "m[1,0]", "m[1,1]", "m[1,2]"
    ]  # fmt: skip
    assert dg.element_names("m", (1, 1)) == ["m[0,0]"]


def test_beyond_shows_as_many_decimals_as_put_the_value_beyond_its_limit():
    assert dg.beyond(1.02, 1.01, 3) == "1.020"
    assert dg.beyond(1.0102, 1.01, 3) == "1.0102"
    assert dg.beyond(1.0100001, 1.01, 3) == "1.0100001"
    assert dg.beyond(50.0, 100.0, 0) == "50"
    assert dg.beyond(99.6, 100.0, 0) == "99.6"
    # one that no 8 further decimals tell apart stops at places + 8
    assert dg.beyond(1.01 + 1e-15, 1.01, 3) == "1.01000000000"


def test_cf_time_units():
    assert dg.is_cf_time_unit("days") and dg.is_cf_time_unit("s since start")
    assert not dg.is_cf_time_unit("m") and not dg.is_cf_time_unit("")


# --- histogram bins -----------------------------------------------------------------------------
def test_histogram_bins_keeps_bins_unless_the_draws_lie_ulps_apart():
    assert dg.histogram_bins(np.array([]), 10) == 10
    assert dg.histogram_bins(np.array([2.0, 2.0]), 10) == 10
    assert dg.histogram_bins(np.array([0.0, 1.0]), 10) == 10
    assert dg.histogram_bins(np.array([[0.0, 1.0], [0.5, 0.25]]), 7) == 7
    u = np.spacing(1.0)
    edges = dg.histogram_bins(np.array([1.0, 1.0 + 3 * u]), 10)
    assert np.array_equal(edges, [1.0, 1.0 + u, 1.0 + 2 * u, 1.0 + 3 * u])
    assert dg.bins_apart(0.0, 1.0, 10) and not dg.bins_apart(1.0, 1.0 + u, 2)
    assert dg.bins_apart(1.0, 1.0 + 2 * u, 2)  # edges 1, 1 + u, 1 + 2u: distinct
    # edges 1 - u, 1 - u/2, 1, 1 (1 + u/2 rounds to even), 1 + u: equal ones past the first
    assert not dg.bins_apart(1.0 - u, 1.0 + u, 4)
    edges = dg.histogram_bins(np.array([1.0 - u, 1.0 + u]), 4)
    assert np.array_equal(edges, [1.0 - u, 1.0 - u / 2, 1.0, 1.0 + u])


# --- ESS and R-hat ------------------------------------------------------------------------------
def _rhat_by_hand(x: np.ndarray) -> float:
    """Rank-normalised split R-hat, Vehtari et al. (2021) eqs. 3-4 and section 4.2: the larger
    of the bulk R-hat and the folded (tail) one."""

    def split(a):
        half = a.shape[1] // 2
        return np.vstack([a[:, :half], a[:, -half:]])

    def z(a):
        r = rankdata(a, method="average").reshape(a.shape)
        return norm.ppf((r - 3 / 8) / (a.size + 1 / 4))

    def basic(a):
        n = a.shape[1]
        w = a.var(axis=1, ddof=1).mean()
        b = n * a.mean(axis=1).var(ddof=1)
        return math.sqrt(((n - 1) / n * w + b / n) / w)

    return max(basic(z(split(x))), basic(z(split(np.abs(x - np.median(x))))))


def test_rhat_of_fixed_chains_is_arviz_and_the_formula():
    x = X.reshape(2, 8)
    az = _arviz()
    assert dg.rhat(x) == pytest.approx(float(az.rhat(x)), rel=1e-12)
    assert dg.rhat(x) == pytest.approx(_rhat_by_hand(x), rel=1e-12)


def test_rhat_needs_eight_draws_a_chain_and_splits_one_chain_into_equal_halves():
    az = _arviz()
    assert math.isnan(dg.rhat(X[None, :7]))
    assert dg.rhat(X[None, :8]) == pytest.approx(float(az.rhat(X[:8].reshape(2, 4))), rel=1e-12)
    # nine draws: halves of four, the ninth left out (not ArviZ's own split of one chain)
    halves = np.vstack([X[:4], X[4:8]])
    assert dg.rhat(X[:9]) == pytest.approx(float(az.rhat(halves)), rel=1e-12)
    assert dg.rhat(X[:9]) == pytest.approx(_rhat_by_hand(halves), rel=1e-12)
    assert dg.rhat(X[:9]) != pytest.approx(float(az.rhat(X[None, :9])), rel=1e-6)
    assert math.isnan(dg.rhat(np.full((2, 10), 0.5)))
    stuck_apart = np.vstack([np.zeros(10), np.ones(10)])
    assert dg.rhat(stuck_apart) == math.inf


def test_ess_needs_four_draws_a_chain_and_is_arviz_bulk_ess():
    az = _arviz()
    assert math.isnan(dg.ess(X[None, :3]))
    assert math.isnan(dg.ess(np.full((2, 6), 1.0)))
    assert dg.ess(X[None, :4]) == pytest.approx(float(az.ess(X[None, :4])), rel=1e-12)
    x = X[:12].reshape(2, 6)
    assert dg.ess(x) == pytest.approx(float(az.ess(x)), rel=1e-12)
    assert dg.ess(X) == dg.ess(X[None, :])  # 1-D: one chain


def test_autocorrelation_by_hand_and_constant_chains_nan():
    out = dg.autocorrelation(np.array([[1.0, -1.0, 1.0, -1.0], [2.0, 2.0, 2.0, 2.0]]))
    # biased autocovariance / its lag 0: (4, -3, 2, -1) / 4
    assert np.allclose(out[0], [1.0, -0.75, 0.5, -0.25], rtol=0, atol=1e-12)
    assert np.isnan(out[1]).all()
    narrow = dg.autocorrelation(np.array([0.1, -0.1, 0.1, -0.1]))  # a spread below 1 too
    assert np.allclose(narrow, [[1.0, -0.75, 0.5, -0.25]], rtol=0, atol=1e-12)
    assert dg.autocorrelation(np.array([[3.0, 3.0]])).shape == (1, 2)


def test_hdi_of_evenly_spaced_draws_is_the_first_shortest_interval():
    # ten draws 0..9, level 0.5: intervals of 5 draws, all 5 wide; the first is (0, 5)
    assert dg.hdi(np.arange(10.0), 0.5) == (0.0, 5.0)


# --- summarize ----------------------------------------------------------------------------------
def test_summarize_gives_mean_sd_and_acceptance_per_element():
    d = np.array([[[1.0, 10.0], [3.0, 10.0]], [[5.0, 10.0], [7.0, 10.0]]])  # (2, 2, 2)
    out = dg.summarize({"a": d, "b": d[:, :, 0]}, {"a": np.array([[0.2, 0.4], [0.6, 1.0]])})
    a = out["a"]
    assert a["mean"] == [4.0, 10.0]
    assert a["sd"][0] == pytest.approx(math.sqrt(20 / 3), rel=1e-15) and a["sd"][1] == 0.0
    assert a["accept"] == [pytest.approx(0.4), pytest.approx(0.7)]
    assert all(math.isnan(v) for v in a["ess"] + a["rhat"])  # two draws a chain
    assert "accept" not in out["b"] and out["b"]["mean"] == [4.0]
    one = dg.summarize({"c": np.array([[2.5]])})["c"]
    assert one["mean"] == [2.5] and math.isnan(one["sd"][0])
    two = dg.summarize({"c": np.array([[1.0, 3.0]])})["c"]
    assert two["sd"] == [pytest.approx(math.sqrt(2.0))]
    x = X.reshape(2, 8)
    s = dg.summarize({"x": x})["x"]
    assert s["ess"] == [dg.ess(x)] and s["rhat"] == [dg.rhat(x)] and math.isfinite(s["rhat"][0])


# --- convergence --------------------------------------------------------------------------------
def _one(rhat, ess, n_chains=2, n_draws=100, **kw) -> dict:
    return dg.convergence({"a": {"rhat": [rhat], "ess": [ess]}}, {"a": ()}, n_chains, n_draws,
                          **kw)  # fmt: skip


def test_an_element_at_the_limits_is_converged_and_the_record_is_whole():
    rec = _one(1.01, 100.0)
    assert rec == {
        "n_chains": 2, "n_draws": 100, "rhat_max": 1.01, "ess_min": 100.0,
        "rhat": {"a": [1.01]}, "ess": {"a": [100.0]},
        "max_rhat": ["a", 1.01], "min_ess": ["a", 100.0], "flagged": {}, "converged": True,
    }  # fmt: skip
    assert type(rec["n_chains"]) is int and type(rec["n_draws"]) is int
    assert _one(1.0101, 100.0)["flagged"] == {"a": "R-hat 1.0101"}
    assert _one(1.01, 99.9)["flagged"] == {"a": "ESS 99.9"}
    assert _one(1.2, 40.0)["flagged"] == {"a": "R-hat 1.200, ESS 40"}
    assert _one(math.inf, 3.0)["flagged"] == {"a": "R-hat inf, ESS 3"}
    assert _one(math.inf, 3.0)["max_rhat"] == ["a", None]


def test_too_few_draws_constant_draws_and_levels():
    assert _one(1.0, 500.0, n_draws=7)["flagged"] == {"a": "too few draws to judge (7 a chain)"}
    assert _one(1.0, 500.0, n_draws=8)["flagged"] == {}
    short = _one(1.5, 50.0, n_draws=7)  # not judged further: no worst element either
    assert short["flagged"] == {"a": "too few draws to judge (7 a chain)"}
    assert short["max_rhat"] == ["", None] and short["min_ess"] == ["", None]
    assert _one(None, None)["flagged"] == {"a": "constant draws (no proposal accepted)"}
    assert _one(math.nan, math.nan, n_chains=1)["flagged"] == {
        "a": "constant draws (no proposal accepted)"
    }
    assert _one(None, None, n_chains=1, levels={"a"})["flagged"] == {}
    assert _one(None, None, levels={"a"})["flagged"] == {
        "a": "constant draws (one level in every chain)"
    }
    # one of the two computed is no constant chain: judged on what there is
    assert _one(1.0, math.nan)["flagged"] == {} and _one(math.nan, 500.0)["flagged"] == {}
    assert _one(1.5, math.nan)["flagged"] == {"a": "R-hat 1.500"}


def test_one_chains_noise_band_is_closed_and_needs_ess_min():
    # 1 + RHAT_NOISE / ESS: 1 + 7 / 140 = 1.05 exactly
    noise = " (within one converged chain's noise at ESS 140)"
    assert _one(1.05, 140.0, n_chains=1)["flagged"] == {"a": "R-hat 1.050" + noise}
    assert _one(1.0501, 140.0, n_chains=1)["flagged"] == {"a": "R-hat 1.050"}
    assert _one(1.05, 140.0, n_chains=2)["flagged"] == {"a": "R-hat 1.050"}
    # at ESS_MIN itself: 1 + 7 / 100 = 1.07
    noise = " (within one converged chain's noise at ESS 100)"
    assert _one(1.06, 100.0, n_chains=1)["flagged"] == {"a": "R-hat 1.060" + noise}
    assert _one(1.06, 99.5, n_chains=1)["flagged"] == {"a": "R-hat 1.060, ESS 99.5"}


def test_the_worst_elements_leave_out_held_ones_and_non_finite_ess():
    summary = {"a": {"rhat": [1.3, 1.02, 5.0], "ess": [80.0, math.nan, 2.0]},
               "b": {"rhat": [1.001], "ess": [900.0]}}  # fmt: skip
    rec = dg.convergence(summary, {"a": (3,), "b": ()}, 2, 50, held={"a[2]"})
    assert rec["max_rhat"] == ["a[0]", 1.3] and rec["min_ess"] == ["a[0]", 80.0]
    assert rec["flagged"] == {"a[0]": "R-hat 1.300, ESS 80", "a[1]": "R-hat 1.020"}
    assert rec["rhat"] == {"a": [1.3, 1.02, 5.0], "b": [1.001]} and not rec["converged"]
    none = dg.convergence({"c": {"rhat": [None], "ess": [None]}}, {"c": ()}, 2, 100)
    assert none["max_rhat"] == ["", None] and none["min_ess"] == ["", None]


# --- read back ----------------------------------------------------------------------------------
def test_read_back_reads_inf_only_for_an_rhat_flagged_infinite_of_a_known_shape():
    flagged = {"a[0]": dg.INFINITE_RHAT, "a[1]": "R-hat 1.2", "b": 3}
    summary = {"a": {"rhat": [None, None], "ess": [None, 5.0]}, "b": {"rhat": [None]},
               "c": "kept", "d": {"rhat": [None]}}  # fmt: skip
    out = dg.read_back(summary, {"a": (2,), "b": (), "d": (2,)}, flagged)
    assert out["a"]["rhat"][0] == math.inf and math.isnan(out["a"]["rhat"][1])
    assert math.isnan(out["a"]["ess"][0]) and out["a"]["ess"][1] == 5.0
    assert math.isnan(out["b"]["rhat"][0])  # a reason that is no text
    assert out["c"] == "kept"
    assert math.isnan(out["d"]["rhat"][0])  # a shape of another size: names unknown
    assert all(math.isnan(v) for v in dg.read_back({"a": {"rhat": [None]}}, {"a": ()})["a"]["rhat"])


def test_read_back_convergence():
    assert dg.read_back_convergence(None, {}) is None
    rec = {"flagged": {"a[1]": dg.INFINITE_RHAT + ", ESS 3"}, "rhat": {"a": [1.0, None]},
           "ess": {"a": [None, 3.0]}, "max_rhat": ["a[1]", None], "n_chains": 2}  # fmt: skip
    out = dg.read_back_convergence(rec, {"a": (2,)})
    assert out["rhat"]["a"] == [1.0, math.inf]
    assert math.isnan(out["ess"]["a"][0]) and out["ess"]["a"][1] == 3.0
    assert out["max_rhat"] == ["a[1]", None] and out["n_chains"] == 2 and out["flagged"] is rec[
        "flagged"]  # fmt: skip
    assert rec["rhat"]["a"] == [1.0, None]  # not changed
    odd = {"flagged": None, "rhat": {"a": [None]}, "ess": None}
    out = dg.read_back_convergence(odd, {"a": ()})
    assert math.isnan(out["rhat"]["a"][0]) and out["ess"] is None


# --- the warning --------------------------------------------------------------------------------
def _warned(record: dict, **kw) -> str:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        dg.warn_unconverged(record, "fit", **kw)
    assert len(caught) == 1 and caught[0].category is ConvergenceWarning
    return str(caught[0].message)


def _record(flagged: dict, max_rhat: list, n_chains: int = 2) -> dict:
    return {"n_chains": n_chains, "n_draws": 50, "rhat_max": 1.01, "ess_min": 100.0,
            "max_rhat": max_rhat, "flagged": flagged}  # fmt: skip


APART = (
    " R-hat {r} ({el}) says the {who} apart, not merely that they are short: if longer "
    "chains do not bring them together, the posterior may have several modes that no chain "
    "crosses (compare the chains: to_arviz(), gpmsa.plots.traces; parallel tempering moves "
    "between modes: the numpy and torch samplers' temperatures= option of gpmsa.fit, "
    "calibrate(fast=False), calibrate_study and fit_study)."
)


def test_no_warning_without_a_flagged_element():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        dg.warn_unconverged(_record({}, ["a", 1.5]), "fit")
        dg.warn_unconverged({"flagged": None}, "fit")
    assert caught == []


def test_the_warning_of_several_chains_in_full():
    text = _warned(_record({"theta[0]": "R-hat 1.500", "b": "ESS 40"}, ["theta[0]", 1.5]),
                   names={"theta[0]": "k"}, more=", or fewer parameters")  # fmt: skip
    assert text == (
        "fit: 2 parameter element(s) not converged over 2 chains x 50 draws (need R-hat <= "
        "1.01 and bulk ESS >= 100): theta[0] (k): R-hat 1.500; b: ESS 40. Run longer chains "
        "(n_iter) or more of them, or fewer parameters."
        + APART.format(r="1.500", el="theta[0] (k)", who="chains lie")
    )
    # at RHAT_APART itself no word of chains apart; an infinite one (None) is apart
    assert _warned(_record({"b": "R-hat 1.1"}, ["b", 1.1])) == (
        "fit: 1 parameter element(s) not converged over 2 chains x 50 draws (need R-hat <= "
        "1.01 and bulk ESS >= 100): b: R-hat 1.1. Run longer chains (n_iter) or more of them."
    )
    assert "apart" not in _warned(_record({"b": "ESS 40"}, ["", None]))
    assert "apart" not in _warned(_record({"b": "ESS 40"}, None))  # a record without one
    inf = _warned(_record({"b": "R-hat inf"}, ["b", None]))
    assert inf.endswith(APART.format(r="inf", el="b", who="chains lie"))
    assert "apart" in _warned(_record({"b": "R-hat 1.1001"}, ["b", 1.1001]))


def test_the_warning_of_one_chain_in_full():
    noise = "R-hat 1.050 (within one converged chain's noise at ESS 140)"
    text = _warned(_record({"a": noise}, ["a", 1.05], n_chains=1), length="n_samples")
    assert text == (
        "fit: 1 parameter element(s) not converged over 1 chain x 50 draws (need R-hat <= "
        f"1.01 and bulk ESS >= 100): a: {noise}. One chain's split R-hat compares the chain's "
        "halves and cannot show whether independent chains agree: run a longer chain "
        "(n_samples) or n_chains >= 2. Each R-hat flagged lies within the noise of one "
        "converged chain at its ESS (up to 1 + 7 / ESS in 1% of converged chains), as it does "
        "for a drift of up to about one posterior sd over the chain: a longer chain "
        "(n_samples) tells them apart."
    )
    mixed = _warned(_record({"a": noise, "b": "ESS 40"}, ["a", 1.2], n_chains=1))
    assert "Each R-hat flagged" not in mixed
    assert mixed.endswith(APART.format(r="1.200", el="a", who="chain's halves lie"))


def test_the_constant_draws_hint_for_one_chain_and_for_several():
    one = _warned(_record({"a": "constant draws (no proposal accepted)"}, ["", None], 1))
    assert one.endswith(
        "or n_chains >= 2. Constant draws in the chain: a categorical theta's chain that never "
        "leaves the level it started at reads so too, whether the posterior holds one level or "
        "the chain is stuck (run chains started at other levels, or let parallel tempering's "
        "temperatures= move between them: docs/models.md)."
    )
    several = _warned(_record({"a": "constant draws (one level in every chain)"}, ["", None]))
    assert several.endswith(
        "or more of them. Constant draws in every chain: a categorical theta's chains that "
        "never leave the levels they started at read so too, whether the posterior holds one "
        "level or the chains are stuck (start chains at other levels, or let parallel "
        "tempering's temperatures= move between them: docs/models.md)."
    )


# --- the InferenceData --------------------------------------------------------------------------
def test_to_inference_data_keeps_units_but_times_and_refuses_dimension_names():
    draws = {"a": np.zeros((2, 3, 2)), "b": np.ones((2, 3)), "c": np.ones((2, 3))}
    idata = dg.to_inference_data(draws, log_post=np.zeros((2, 3)),
                                 units={"a": "m", "b": "days", "c": "", "z": "s"})  # fmt: skip
    assert idata.posterior["a"].attrs == {"units": "m"}
    assert "units" not in idata.posterior["b"].attrs and "units" not in idata.posterior["c"].attrs
    assert np.array_equal(idata.sample_stats["lp"].values, np.zeros((2, 3)))
    assert "sample_stats" not in dg.to_inference_data({"a": np.zeros((2, 3))}).groups()
    two = dg.to_inference_data({"a": np.zeros((2, 3, 2)), "a_dim_1": np.ones((2, 3))})
    assert list(two.posterior.data_vars) == ["a", "a_dim_1"]  # a has one axis: a_dim_0
    for name in ("chain", "draw"):
        with pytest.raises(GPMSAError, match=f"parameter '{name}' is named as one of ArviZ"):
            dg.to_inference_data({name: np.zeros((2, 3))})
    with pytest.raises(GPMSAError, match="parameter 'a_dim_0'"):
        dg.to_inference_data({"a": np.zeros((2, 3, 2)), "a_dim_0": np.zeros((2, 3))})
