"""Study options accepted and then without effect, and study arguments taken as something else
(session 79 sweep of ``fit_study`` / ``calibrate_study``), each now refused by name:

- ``fit_study(priors=)`` giving a hierarchical parameter a theta prior other than the default:
  its elements take their group's truncated normal, so the draws were bit for bit those
  without it (confirmed before the fix, seeded, one and two chains, tempered too);
- ``HyperPriors(sd_prior="gamma", sd_max=...)`` given to a study: only the uniform sd prior
  reads sd_max (bit for bit ``HyperPriors.sepia()``'s draws before the fix);
- ``shared`` / ``hierarchical`` given as a set (its order, which orders the groups and the
  sweep, changed with PYTHONHASHSEED: the same seeded study drew other theta and mu in
  another process) or a dict (its values ignored), and ``labels`` as a set (a model could
  take another's label);
- ``fixed`` as a dict by label (as ``priors`` takes one) was read as parameter names
  ("unknown parameter 'a'").

The calls that take these options with effect run as before, bit for bit."""

import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.errors import GPMSAError
from tests.gpmsa._study_cases import emulator, observations, sim_data

RNG_DATA = [
    observations(th, 3, 0.03, np.random.default_rng(4 + k)) for k, th in enumerate((0.35, 0.5))
]
RUN = dict(labels=["a", "b"], seed=5, tune_rounds=3, tune_levels=2)


def _calibrate(**kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gpmsa.calibrate_study(
            [emulator(None)] * 2, [d[0] for d in RNG_DATA], [d[1] for d in RNG_DATA],
            **{**RUN, "n_samples": 30, "n_burn": 5, **kw},
        )  # fmt: skip


def _fit(**kw):
    obs = [gpmsa.ObsData(x=d[0], y=d[1]) for d in RNG_DATA]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gpmsa.fit_study([sim_data(), sim_data()], obs,
                               **{**RUN, "n_iter": 30, "n_burn": 5, **kw})  # fmt: skip


def _same(a, b) -> bool:
    return a.draws.keys() == b.draws.keys() and all(
        np.array_equal(a.draws[k], b.draws[k]) for k in a.draws
    )


@pytest.mark.parametrize(
    "priors",
    [gpmsa.Priors(theta_mean=[0.2], theta_sd=[0.05]), gpmsa.Priors(theta_sd=2.0),
     {"a": None, "b": gpmsa.Priors(theta_mean=0.3)}],
)  # fmt: skip
def test_fit_study_refuses_a_theta_prior_of_a_hierarchical_parameter(priors):
    with pytest.raises(GPMSAError, match=r"model '[ab]': priors gives hierarchical parameter "
                                         r"'t' the theta prior .*no effect.*HyperPriors"
                                         r"\(mu_mean=.*default \(0.5, 10\)"):  # fmt: skip
        _fit(hierarchical=["t"], priors=priors)


def test_the_default_theta_prior_of_a_hierarchical_parameter_runs_as_before():
    plain = _fit(hierarchical=["t"])
    spelled = _fit(hierarchical=["t"], priors=gpmsa.Priors(theta_mean=[0.5], theta_sd=[10.0]))
    assert _same(plain, spelled)
    # a shared or own parameter's prior acts as before
    shared = _fit(shared=["t"], priors=gpmsa.Priors(theta_mean=0.2, theta_sd=0.05))
    assert not _same(shared, _fit(shared=["t"]))


def test_a_gamma_sd_prior_with_sd_max_is_refused():
    gamma = gpmsa.HyperPriors(sd_prior="gamma", sd_max=0.3)
    with pytest.raises(GPMSAError, match=r"HyperPriors.sd_max=0.3 with sd_prior='gamma'.*no "
                                         r"effect.*sd_prior='uniform'"):  # fmt: skip
        _calibrate(hierarchical=["t"], hyper=gamma)
    with pytest.raises(GPMSAError, match=r"sd_max=0.3 with sd_prior='gamma'"):
        _fit(hierarchical=["t"], hyper=gamma)
    # SEPIA's prior, and a uniform one's sd_max, act as before
    sepia = _calibrate(hierarchical=["t"], hyper=gpmsa.HyperPriors.sepia())
    assert sepia.hyper.sd_prior == "gamma"
    narrow = _calibrate(hierarchical=["t"], hyper=gpmsa.HyperPriors(sd_max=0.3))
    assert narrow.posterior.samples["t.sd"].max() < 0.3


def test_a_study_that_carries_them_still_continues(monkeypatch):
    """A study fitted before these refusals (a hierarchical parameter's own prior, a gamma sd
    prior's sd_max) continues with its own settings: the refusals are for new studies."""
    from gpmsa.studies import layout as study_layout
    from gpmsa.studies import run as study_run

    own = gpmsa.Priors(theta_mean=[0.2], theta_sd=[0.05])
    gamma = gpmsa.HyperPriors(sd_prior="gamma", sd_max=0.3)
    with monkeypatch.context() as old:  # as the code before the refusals ran
        old.setattr(study_run, "_refuse_group_priors", lambda layout: None)
        old.setattr(study_layout, "SD_MAX_DEFAULT", 0.3)
        fitted = _fit(hierarchical=["t"], priors=own, hyper=gamma)
        calibrated = _calibrate(hierarchical=["t"], hyper=gamma)
    more = _fit(hierarchical=["t"], priors=own, hyper=gamma, init=fitted, n_burn=0)
    assert more.draws and all(np.size(v) for v in more.draws.values())
    again = _calibrate(hierarchical=["t"], hyper=gamma, init=calibrated, n_burn=0)
    assert again.posterior.samples["t.sd"].size > 0
    with pytest.raises(GPMSAError, match="hierarchical parameter 't'"):  # a new one: refused
        _fit(hierarchical=["t"], priors=own)


@pytest.mark.parametrize(
    "kw, match",
    [(dict(hierarchical={"t"}), r"hierarchical must be a list or tuple .* got a set .*"
                                r"hierarchical=\['t'\]"),
     (dict(shared=frozenset({"t"})), r"shared must be a list or tuple .* got a set"),
     (dict(shared={"t": 0.4}), r"shared must be a list of parameter names, got a dict .*no "
                               r"effect.*fixed=.*shared=\['t'\]"),
     (dict(hierarchical={"t": gpmsa.HyperPriors()}), r"hierarchical .* got a dict.*hyper="),
     (dict(labels={"a", "b"}), r"labels must be a list or tuple of 2 strings in the models' "
                               r"order, got a set")],
)  # fmt: skip
def test_unordered_names_and_dicts_of_values_are_refused(kw, match):
    with pytest.raises(GPMSAError, match=match):
        _calibrate(**kw)
    with pytest.raises(GPMSAError, match=match):
        _fit(**kw)


def test_names_in_a_list_or_tuple_run_as_before():
    listed = _calibrate(hierarchical=["t"])
    assert _same(listed, _calibrate(hierarchical=("t",), labels=("a", "b")))
    assert _same(listed, _calibrate(hierarchical="t"))  # one name as a str


def test_fixed_by_label_is_named_as_such():
    with pytest.raises(GPMSAError, match=r"fixed: a dict is every model's parameter -> value, "
                                         r"and \['a', 'b'\] are the study's labels.*a list "
                                         r"with one entry .* per model"):  # fmt: skip
        _calibrate(shared=["t"], fixed={"a": {"theta": {"t": 0.4}}, "b": None})
    with pytest.raises(GPMSAError, match=r"\['a'\] are the study's labels"):
        _fit(fixed={"a": {"lamUz": [1.0]}})
    one = _calibrate(shared=["t"], fixed={"theta": {"t": 0.4}})  # every model's, as before
    assert _same(one, _calibrate(shared=["t"], fixed=[{"theta": {"t": 0.4}}] * 2))
    assert np.all(one.posterior.samples["t"] == 0.4)
