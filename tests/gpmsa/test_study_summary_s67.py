"""``Study.summary()`` and ``Study.to_arviz()``: the pooled posterior's summary (held
parameters marked, as ``gpmsa info`` prints them) and its chains for arviz, the names those of
``study.posterior``; each model's entries those of its ``member_posterior``."""

import warnings
from functools import cache

import numpy as np
import pytest
from _study_cases import emulator, observations

import gpmsa
from gpmsa import GPMSAError


@cache
def _study(kind: str) -> gpmsa.Study:
    """Two models, "hier": hierarchical t, 2 chains, model a's lamOs held at 1; "shared": a
    shared t, one chain."""
    rng = np.random.default_rng(4)
    data = [observations(th, 3, 0.03, rng) for th in (0.35, 0.5)]
    xs, ys = [d[0] for d in data], [d[1] for d in data]
    kw = {"labels": ["a", "b"], "n_samples": 60, "n_burn": 20, "tune": False, "seed": 0}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # so short chains are not converged
        if kind == "hier":
            fixed = [{"lamOs": 1.0}, None]
            return gpmsa.calibrate_study([emulator(None)] * 2, xs, ys, hierarchical=["t"],
                                         n_chains=2, fixed=fixed, **kw)  # fmt: skip
        return gpmsa.calibrate_study([emulator(None)] * 2, xs, ys, shared=["t"], **kw)


@pytest.mark.parametrize("kind", ["hier", "shared"])
def test_summary_is_the_pooled_posteriors_and_matches_each_member(kind):
    study = _study(kind)
    summary = study.summary()
    assert tuple(summary) == study.posterior.names
    bare = {n: {k: v for k, v in row.items() if k != "held"} for n, row in summary.items()}
    whole = study.posterior.summary()
    np.testing.assert_equal(
        bare, {n: {k: v for k, v in row.items() if k != "held"} for n, row in whole.items()}
    )  # NaN equal to NaN
    t_of = {"hier": "t[{}]", "shared": "t"}[kind]
    for lab in study.labels:
        member = study.member_posterior(lab).summary()
        for own, pooled in (("t", t_of.format(lab)), ("lamOs", f"lamOs[{lab}]")):
            np.testing.assert_equal(summary[pooled], member[own])  # NaN where undefined; held
        draws = study.posterior.samples[t_of.format(lab)]
        assert summary[t_of.format(lab)]["median"] == np.quantile(draws, 0.5)
        assert summary[t_of.format(lab)]["n_draws"] == draws.size


def test_summary_marks_what_fixed_holds_and_nothing_else():
    summary = _study("hier").summary()
    assert [n for n, row in summary.items() if row["held"]] == ["lamOs[a]"]
    held = summary["lamOs[a]"]
    assert held["mean"] == 1.0 and held["sd"] == 0.0 and np.isnan(held["ess"])
    assert set(summary) >= {"t[a]", "t[b]", "t.mu", "t.sd", "t.lam", "lamOs[b]"}
    assert not any(row["held"] for row in _study("shared").summary().values())


def test_a_hostile_held_list_does_not_make_a_sampled_name_held():
    """As ``gpmsa info``: only strings of settings["held"], and only constant draws."""
    s = _study("hier")
    settings = {**s.settings, "held": ["t[a]", 5, None]}
    other = gpmsa.Study(s.kind, s.members, s.layout, s.hyper, s.draws, settings)
    summary = other.summary()
    assert not summary["t[a]"]["held"] and not summary["lamOs[a]"]["held"]


def test_summary_level_and_its_check():
    summary = _study("shared").summary(0.5)
    row = summary["t"]
    assert {"q25", "q75"} <= set(row)
    draws = _study("shared").posterior.samples["t"]
    assert (row["q25"], row["q75"]) == tuple(np.quantile(draws, [0.25, 0.75]))
    for bad in (1.0, 0, "0.9", [0.9], True):
        with pytest.raises(GPMSAError, match="level must be a number in"):
            _study("shared").summary(bad)


@pytest.mark.parametrize(("kind", "n_chains"), [("hier", 2), ("shared", 1)])
def test_to_arviz_keeps_the_chains_and_the_log_posterior(kind, n_chains):
    study = _study(kind)
    idata = study.to_arviz()
    assert tuple(idata.posterior.data_vars) == study.posterior.names
    n_draws = study.draws["log_post"].shape[1]
    for name in study.posterior.names:
        values = idata.posterior[name].values
        assert values.shape == (n_chains, n_draws)
        assert np.array_equal(values, study.posterior.chains[name])
        assert np.array_equal(values.reshape(-1), study.posterior.samples[name])
    assert np.array_equal(idata.sample_stats["lp"].values, study.draws["log_post"])
    if kind == "hier":
        assert np.all(idata.posterior["lamOs[a]"].values == 1.0)  # held: its value throughout
