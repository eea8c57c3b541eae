"""Starts inside bounded priors (a GPM/SA default start outside a prior's bounds moves to that
prior's median inside them; a user's own start is refused), and ``Posterior.summary``'s "held"
for what ``fixed=`` holds (calibrate, calibration_posterior, ``gpmsa info``)."""

import contextlib
import functools
import io
import warnings

import numpy as np
import pytest
from scipy import stats
from test_discrepancy_groups_s61 import BASIS, GROUPS, _data

import gpmsa
from gpmsa import GammaPrior, GPMSAError, Priors
from gpmsa.cli.main import main
from gpmsa.mcmc import starts
from gpmsa.model.problem import prepare

VAGUE = GammaPrior(1.0, 1e-3)
ABOVE = GammaPrior(1.0, 1e-3, 1000.0)  # excludes GPM/SA's start lamVz = 20
MEDIAN = 1000.0 + 1000.0 * np.log(2.0)  # of Exp(rate 1e-3) truncated to (1000, inf)


def _problem(lam_vz, **priors):
    data, obs = _data()
    return prepare(data, obs, priors=Priors(lamVz=lam_vz, **priors), discrepancy=BASIS,
                   discrepancy_groups=GROUPS).problem  # fmt: skip


@functools.cache
def _emulator():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gpmsa.fit(_data()[0], n_iter=30, tune=False, seed=0)


def _quiet(f, *args, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # short chains, the toy's y_obs outside the emulator
        return f(*args, **kw)


# --- starts inside the prior's bounds -----------------------------------------------------------
def test_a_group_prior_excluding_the_default_start_fits_and_calibrates():
    """Before: GPMSAError 'lamVz = [20.0, 20.0] ('gpmsa' start) lies outside ... (init='prior',
    or a fixed= value)' from fit and calibrate, one chain or several."""
    data, obs = _data()
    kw = dict(discrepancy=BASIS, discrepancy_groups=GROUPS, tune=False, seed=0)
    pri = Priors(lamVz=[VAGUE, ABOVE])
    for n_chains in (1, 2):
        emu = _quiet(gpmsa.fit, data, obs, n_iter=8, n_chains=n_chains, n_jobs=1, priors=pri, **kw)
        assert np.all(emu.calibration["lamVz"][:, 1] > 1000.0)
    post = _quiet(gpmsa.calibrate, _emulator().with_calibration_priors(lamVz=pri.lamVz), obs,
                  n_samples=8, n_burn=0, n_chains=2, **kw)  # fmt: skip
    assert np.all(post.samples["lamVz[1]"] > 1000.0)


def test_the_moved_start_is_the_truncated_priors_median_and_the_rest_gpmsas():
    problem = _problem([VAGUE, ABOVE])
    _, (first,) = starts.chain_starts(problem, "gpmsa", np.random.SeedSequence(0).spawn(1))
    assert first["lamVz"][0] == 20.0  # inside its bounds: GPM/SA's, exactly
    np.testing.assert_allclose(first["lamVz"][1], MEDIAN, rtol=1e-12)
    for name in problem.names:
        if name != "lamVz":
            np.testing.assert_array_equal(first[name], problem.init[name])
    assert problem.init["lamVz"].tolist() == [20.0, 20.0]  # the problem itself is unchanged
    _, jitter = starts.chain_starts(problem, "jitter", np.random.SeedSequence(0).spawn(3))
    for start in jitter:  # log-uniform around the median, cut to the bounds
        assert MEDIAN / 10 < max(start["lamVz"][1], 1000.0) <= start["lamVz"][1] < MEDIAN * 10


@pytest.mark.parametrize(("a", "b", "lower", "upper"), [
    (1.0, 1e-3, 1000.0, np.inf), (1.0, 0.0025, 1e4, 1e5), (5.0, 5.0, 0.3, 0.31),
    (3.0, 3e-3, 60.0, 1e5), (1.0, 0.0025, 0.5, 2.0),
])  # fmt: skip
def test_inside_median_is_scipys_truncated_median(a, b, lower, upper):
    d = stats.gamma(a, scale=1.0 / b)
    want = d.isf(0.5 * (d.sf(lower) + d.sf(upper)))
    got = starts.inside_median(*(np.array([v]) for v in (a, b, lower, upper)))[0]
    np.testing.assert_allclose(got, want, rtol=1e-10)


def test_inside_median_far_in_a_tail_stays_inside_and_near_the_mass():
    """Where the prior's mass inside the bounds underflows: ln 2 / slope inside the bound."""
    a, b, lower, upper = (np.array(v) for v in ([1.0, 1e6], [1e-3, 2e5], [1e6, 0.0],
                                                [np.inf, 4.0]))  # fmt: skip
    got = starts.inside_median(a, b, lower, upper)
    np.testing.assert_allclose(got, [1e6 + 1e3 * np.log(2.0), 4.0 - np.log(2.0) / 49999.75])
    assert np.all((got > lower) & (got < upper))


def test_every_precision_and_a_users_own_start_outside_is_refused():
    """lamWs, lamOs start inside bounds excluding 1000 and max(20, a/b); a given init= value
    outside its bounds is refused naming it, never moved."""
    problem = _problem(VAGUE, lamWs=GammaPrior(1.0, 0.0025, 1e4, 1e5),
                       lamOs=GammaPrior(1.0, 1e-3, 0.0, 5.0))  # fmt: skip
    _, (first,) = starts.chain_starts(problem, "gpmsa", np.random.SeedSequence(0).spawn(1))
    assert np.all((first["lamWs"] > 1e4) & (first["lamWs"] < 1e5))
    assert 0.0 < first["lamOs"][0] < 5.0
    given = {"lamVz": [[20.0, 20.0]]}
    with pytest.raises(
        GPMSAError,
        match=r"lamVz = \[20.0, 20.0\] \('given' start\) lies outside "
        r".*\(1000, inf\)\].*\(init\['lamVz'\] inside them, or leave lamVz out",
    ):
        starts.chain_starts(_problem([VAGUE, ABOVE]), given, np.random.SeedSequence(0).spawn(1))
    _, (left_out,) = starts.chain_starts(_problem([VAGUE, ABOVE]), {"lamOs": [[30.0]]},
                                         np.random.SeedSequence(0).spawn(1))  # fmt: skip
    np.testing.assert_allclose(left_out["lamVz"], [20.0, MEDIAN], rtol=1e-12)


# --- "held" in Posterior.summary ----------------------------------------------------------------
def test_a_calibrate_posterior_marks_what_fixed_holds():
    """Before: no "held" key (a held lamOs read 'ESS nan R-hat nan'), no info["held"]."""
    _, obs = _data()
    kw = dict(n_samples=12, n_burn=0, n_chains=2, tune=False, seed=1)
    fast = _quiet(gpmsa.calibrate, _emulator(), obs, fixed={"lamOs": 30.0}, **kw)
    assert fast.info["held"] == ["lamOs"]
    assert {n: r["held"] for n, r in fast.summary().items()} == {"t": False, "lamOs": True}
    back = _quiet(gpmsa.calibrate, _emulator(), obs, discrepancy=BASIS, discrepancy_groups=GROUPS,
                  fixed={"lamVz": {1: 50.0}}, **kw)  # fmt: skip
    summary = back.summary()
    assert [n for n, r in summary.items() if r["held"]] == ["lamVz[1]"] == back.info["held"]
    free = _quiet(gpmsa.calibrate, _emulator(), obs, **kw)
    assert "held" not in free.info and not any(r["held"] for r in free.summary().values())


def test_a_held_name_with_varying_draws_or_a_hostile_list_is_not_held():
    post = gpmsa.Posterior({"a": np.arange(5.0), "b": np.ones(5)}, info={"held": ["a", 7]})
    assert {n: r["held"] for n, r in post.summary().items()} == {"a": False, "b": False}
    post = gpmsa.Posterior({"b": np.ones(5)}, info={"held": "b"})  # not a list: ignored
    assert not post.summary()["b"]["held"]


def test_calibration_posterior_and_gpmsa_info_of_a_fit_with_fixed(tmp_path):
    data, obs = _data()
    emu = _quiet(gpmsa.fit, data, obs, n_iter=12, n_chains=2, n_jobs=1, tune=False, seed=0,
                 discrepancy=BASIS, discrepancy_groups=GROUPS,
                 fixed={"lamOs": 30.0, "lamVz": {0: 40.0}, "betaV": {(0, 1): 0.5}})  # fmt: skip
    post = gpmsa.calibration_posterior(emu)
    assert post.info["held"] == ["lamOs", "betaV[0,1]", "lamVz[0]"]
    held = [n for n, r in post.summary().items() if r["held"]]
    assert sorted(held) == ["betaV[0,1]", "lamOs", "lamVz[0]"]
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        main(["info", str(emu.save(tmp_path / "e.gpmsa"))])
    text = out.getvalue()
    assert "posterior lamOs: held at [30] (fixed=)" in text
    assert "posterior lamVz: mean [40, " in text and "ESS [held, " in text
    assert "posterior betaV: mean [" in text and "ESS [" in text
    line = next(ln for ln in text.splitlines() if ln.startswith("posterior betaV"))
    assert line.count("held") == 2 and line.split("R-hat [")[1].split(", ")[1] == "held]"
