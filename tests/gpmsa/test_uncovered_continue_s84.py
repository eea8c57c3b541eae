"""Continuation paths the whole suite never ran (session 84's coverage sweep, third part):
``fit(..., init=emulator)``, ``calibrate(..., init=posterior)`` and ``calibrate_study(...,
init=study)`` with sources whose records are damaged (a hand-edited or corrupted settings),
other observations, other engines, a source of another backend and a twice-appended
calibration. Two defects: a tempered source whose ladder record is damaged was refused with
the advice "pass temperatures=", and following it raised the same error (fit and study); a
source whose hot-copy record is damaged advised "temperatures=", and passing its own ladder
raised the same error (now: another ladder, or 1)."""

import copy
import importlib.util
import warnings

import numpy as np
import pytest
from _calib_cases import road_emulator, road_obs
from _continue_cases import continue_data, continue_fit
from _level_cases import level_function, level_sim
from _tempering_cases import fit_two_mode
from test_study_tempering_s73 import LADDER, _study

import gpmsa
from gpmsa.errors import BackendUnavailableError, GPMSAError

pytestmark = pytest.mark.filterwarnings(
    "ignore::gpmsa.ConvergenceWarning", "ignore::gpmsa.OutsideEmulatorWarning"
)
SMALL = {"tune_rounds": 1, "tune_levels": 2}


@pytest.fixture(scope="module")
def joint():
    """A short joint fit of the continuation case (2 chains)."""
    return continue_fit(n_iter=30)


def _more(source, **kw):
    data, obs = continue_data()
    return gpmsa.fit(data, kw.pop("obs", obs), init=source, n_iter=10, n_chains=2, seed=1, **kw)


@pytest.fixture(scope="module")
def tempered():
    """A tempered fit of the two-mode case (ladder (1, 2, 4), 2 chains) recording its hot
    copies."""
    return fit_two_mode(n_iter=20, n_chains=2, seed=3, temperatures=3, n_jobs=1, **SMALL)


def _hot(source, **kw):
    return fit_two_mode(init=source, n_iter=10, n_chains=2, seed=4, n_jobs=1, **kw)


def _edited(source, **settings):
    out = copy.deepcopy(source)
    out.settings.update(settings)
    return out


def test_a_damaged_ladder_record_continues_at_the_ladder_given(tempered):
    """Before: "its tempering record ... is damaged (...); pass temperatures=", and passing it
    raised the same (the hot-copy check read the damaged record again)."""
    src = _edited(tempered, temperatures="x")
    with pytest.raises(GPMSAError, match="tempering record .* is damaged .*pass temperatures="):
        _hot(src)
    more = _hot(src, temperatures=[1.0, 2.0, 4.0])
    assert more.n_draws == 2 * 10 and more.settings["tune"] is True  # its copies tuned
    with pytest.raises(GPMSAError, match="tune=False with a tempered continuation"):
        _hot(src, temperatures=[1.0, 2.0, 4.0], tune=False)  # its copies do not resume
    with pytest.raises(GPMSAError, match="continues its 2 chain"):
        fit_two_mode(init=src, n_iter=10, n_chains=3, seed=4, temperatures=[1.0, 2.0, 4.0])
    adapted = _edited(tempered, adapted_temperatures=[[1.0, 2.0, 4.0]])  # one chain's, not 2
    with pytest.raises(GPMSAError, match=r"damaged \(adapted_temperatures of shape \(1, 3\)"):
        _hot(adapted)
    assert _hot(adapted, temperatures=1).settings.get("temperatures") is None


def test_a_damaged_hot_copy_record_advises_another_ladder(tempered):
    """Before: "... or temperatures=", and the source's own ladder raised the same."""
    src = _edited(tempered, hot_states=[1, 2])
    for given in ({}, {"temperatures": [1.0, 2.0, 4.0]}):
        with pytest.raises(
            GPMSAError,
            match=r"hot_copies\['starts'\] must be a dict.*"
            r"temperatures= another ladder \(1: none\)",
        ):
            _hot(src, **given)
    for given in ({"temperatures": 1}, {"temperatures": [1.0, 3.0, 9.0]}):
        assert _hot(src, **given).n_draws > 0


def test_swap_every_given_to_a_tempered_continuation_is_kept(tempered):
    more = _hot(tempered, swap_every=2)
    assert more.settings["swap_every"] == 2 and more.settings["temperatures"] == [1.0, 2.0, 4.0]


def test_a_categorical_theta_hot_record_that_is_damaged_is_named():
    rng = np.random.default_rng(2)
    sim = level_sim(rng, 18)
    xo = np.linspace(0.1, 0.9, 4)[:, None]
    truth = np.column_stack([np.full(4, 0.4), np.full(4, 1)])
    obs = gpmsa.ObsData(x=xo, y=level_function(xo, truth)[:, None])
    src = gpmsa.fit(sim, obs, n_iter=20, n_chains=2, seed=0, temperatures=3, n_jobs=1, **SMALL)
    for theta, match in (([["a", "b"]], r"\['theta'\] must be a numeric array"),
                         ([[[0.1]]], r"\['theta'\] must have shape \(2, 2, 2\)")):  # fmt: skip
        bad = copy.deepcopy(src)
        bad.settings["hot_states"]["theta"] = theta
        with pytest.raises(GPMSAError, match="recorded hot copies .*" + match):
            gpmsa.fit(sim, obs, init=bad, n_iter=10, n_chains=2, seed=1, n_jobs=1)


def test_other_observations_and_damaged_records_are_named(joint):
    other = gpmsa.ObsData(x=[[0.3], [0.7]], y=[[0.5], [0.6]])
    with pytest.raises(GPMSAError, match="fitted jointly with other observations"):
        _more(joint, obs=other)
    bad = _edited(joint, proportional_steps="yes")
    with pytest.raises(
        GPMSAError,
        match=r"proportional_steps'\] must be true, false or null, "
        "got 'yes'; pass proportional_steps= or tune=True",
    ):
        _more(bad)
    assert _more(bad, proportional_steps=True).settings["proportional_steps"] is True
    bad = _edited(joint, step_widths={"theta": [[0.1], [0.2, 0.3]]})
    with pytest.raises(GPMSAError, match="recorded step widths .*ragged.*pass step_widths"):
        _more(bad)
    bad = _edited(joint, step_widths=[1, 2])
    with pytest.raises(GPMSAError, match="recorded step widths .*got list.*pass step_widths"):
        _more(bad)
    assert _more(bad, tune=True).n_draws > 0
    assert _more(bad, step_widths={"theta": 0.1}).n_draws > 0  # tuned from them


def test_an_append_pools_no_acceptance_rate_it_cannot_weigh(joint):
    """A source of a NUTS backend (pyro's rate is another figure), one recording no rate, or
    one whose rate has another shape: the pooled summary gives none (no wrong weighting)."""
    plain = _more(joint, append=True)
    assert "accept" in plain.diagnostics["theta"]
    nuts = _edited(joint, backend="pyro")  # its step_widths are then not Metropolis widths
    with pytest.raises(GPMSAError, match="pass tune=False"):
        _more(nuts, append=True)
    assert "accept" not in _more(nuts, append=True, tune=False).diagnostics["theta"]
    unrated = copy.deepcopy(joint)
    for entry in unrated.diagnostics.values():
        entry.pop("accept", None)
    assert "accept" not in _more(unrated, append=True).diagnostics["theta"]
    ragged = copy.deepcopy(joint)
    ragged.diagnostics["theta"]["accept"] = [0.3, 0.4]
    out = _more(ragged, append=True)
    assert "accept" not in out.diagnostics["theta"] and "accept" in out.diagnostics["lamOs"]


@pytest.fixture(scope="module")
def road():
    emu = road_emulator()
    x, y = road_obs()
    return emu, x, y, gpmsa.calibrate(emu, x, y, n_samples=100, n_burn=20, seed=1)


def _calibrate(road, **kw):
    emu, x, y, _ = road
    return gpmsa.calibrate(emu, x, y, **{"n_samples": 30, "seed": 2, "n_burn": 0, **kw})


def test_calibrate_refuses_sources_that_hold_no_chains(road):
    emu, x, y, _ = road
    grid = gpmsa.Calibrator(emu).update(x, y)
    with pytest.raises(GPMSAError, match="this one \\(method 'grid'\\) records no chains"):
        _calibrate(road, init=grid)
    with pytest.raises(GPMSAError, match="init must be a start rule or a Posterior .*got list$"):
        _calibrate(road, init=[1.0])


def test_calibrate_names_the_engine_a_fast_source_continues_on(road):
    src = road[3]
    with pytest.raises(GPMSAError, match="ran on the fast numpy sampler .*: leave fast= out$"):
        _calibrate(road, init=src, fast=False)
    if importlib.util.find_spec("torch") is None:  # an install without the torch extra
        with pytest.raises(BackendUnavailableError, match="backend 'torch' needs torch"):
            _calibrate(road, init=src, backend="torch")
    else:
        with pytest.raises(GPMSAError, match="leave backend='torch' out \\(and fast=\\)"):
            _calibrate(road, init=src, backend="torch")
    assert _calibrate(road, init=src).info["engine"] == "fast"  # as advised


@pytest.mark.parametrize("edit, match", [
    ({"proportional_steps": 1}, r"info\['proportional_steps'\] must be true or false, got 1"),
    ({"step_widths": [["a"]]}, r"are not positive widths of 2 elements for 1 chain"),
])  # fmt: skip
def test_calibrate_names_a_damaged_source_record_and_tune_true_runs(road, edit, match):
    src = copy.deepcopy(road[3])
    src.info.update(edit)
    with pytest.raises(GPMSAError, match=match + ".*pass tune=True"):
        _calibrate(road, init=src)
    assert _calibrate(road, init=src, tune=True).info["tune"] is True


def test_calibrate_names_missing_draws(road):
    src = copy.deepcopy(road[3])
    del src.chains["lamOs"]
    with pytest.raises(GPMSAError, match="has no 'lamOs' draws"):
        _calibrate(road, init=src)


def test_an_appended_calibration_appends_again_counting_every_part(road):
    src = road[3]
    once = _calibrate(road, init=src, append=True)
    twice = _calibrate(road, init=once, append=True, n_samples=20, seed=3)
    name = next(iter(src.chains))
    np.testing.assert_array_equal(twice.chains[name][:, :110], once.chains[name])
    info = twice.info
    assert (info["appended_after"], info["pooled_sweeps"], info["sweeps_run"]) == (110, 130, 150)
    alone = _calibrate(road, init=once, n_samples=20, seed=3).info["accept_rate"]
    pooled = (np.array(once.info["accept_rate"]) * 130 + np.array(alone) * 20) / 150
    np.testing.assert_allclose(info["accept_rate"], pooled, rtol=1e-12)  # weighted by sweeps


def test_a_calibration_rate_of_another_shape_is_not_weighed(road):
    emu, x, y, _ = road
    src = gpmsa.calibrate(emu, x, y, n_samples=40, n_burn=10, seed=1, fast=False)
    bad = copy.deepcopy(src)
    bad.info["accept_rate"] = {k: [[0.1, 0.2, 0.3]] for k in src.info["accept_rate"]}
    out = _calibrate(road, init=bad, append=True, fast=False)
    plain = _calibrate(road, init=src, append=True, fast=False)
    own = _calibrate(road, init=src, fast=False)
    assert out.info["accept_rate"]["theta"] == own.info["accept_rate"]["theta"]  # its own
    assert plain.info["accept_rate"]["theta"] != own.info["accept_rate"]["theta"]  # weighted


def test_a_tempered_calibration_with_a_damaged_ladder_continues_at_the_one_given(road):
    emu, x, y, _ = road
    src = gpmsa.calibrate(emu, x, y, n_samples=40, n_burn=10, seed=1, fast=False,
                          temperatures=[1, 2], **SMALL)  # fmt: skip
    src.info["temperatures"] = "x"
    with pytest.raises(GPMSAError, match="tempering record .* is damaged .*pass temperatures="):
        _calibrate(road, init=src, fast=False)
    assert _calibrate(road, init=src, fast=False, temperatures=[1, 2]).info["temperatures"]


def _study_more(source, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return _study(
            n_samples=10,
            n_chains=2,
            seed=5,
            init=source,
            **{"tune_rounds": 2, "tune_levels": 3, **kw},
        )


def test_a_study_whose_ladder_record_is_damaged_continues_at_the_ladder_given():
    """Before: "pass temperatures=", then the same error for temperatures=LADDER or 1."""
    src = _study(n_samples=20, n_burn=0, n_chains=2, seed=4, temperatures=LADDER,
                 tune_rounds=2, tune_levels=3)  # fmt: skip
    bad = copy.deepcopy(src)
    bad.settings["temperatures"] = "x"
    with pytest.raises(GPMSAError, match="init=study: its tempering record .* pass temperatures="):
        _study_more(bad)
    assert _study_more(bad, temperatures=LADDER).settings["temperatures"] == LADDER
    assert _study_more(bad, temperatures=1).settings.get("temperatures") is None
    hot = copy.deepcopy(src)
    hot.settings["hot_states"]["theta"] = [1]
    with pytest.raises(GPMSAError, match=r"do not fit this study .*another ladder \(1: none\)"):
        _study_more(hot, temperatures=LADDER)
    assert _study_more(hot, temperatures=1).draws["theta"].shape[:2] == (2, 10)


@pytest.fixture(scope="module")
def plain_study():
    return _study(n_samples=20, n_burn=0, n_chains=2, seed=4, tune_rounds=2, tune_levels=3)


def _damaged(study, settings=None, draws=None):
    out = copy.deepcopy(study)
    for key, value in (settings or {}).items():
        if value is None:
            del out.settings[key]
        else:
            out.settings[key] = value
    out.draws.update(draws or {})
    return out


@pytest.mark.parametrize("settings, match", [
    ({"step_widths_by_chain": [1]}, "do not name this study's sweep elements"),
    ({"step_widths_by_chain": {"t": ["a", 1.0]}}, "not finite positive widths for 2 chain"),
    ({"proportional_steps": 1}, r"settings\['proportional_steps'\] must be true or false"),
])  # fmt: skip
def test_a_study_with_a_damaged_record_is_named_and_tune_true_runs(plain_study, settings, match):
    bad = _damaged(plain_study, settings)
    with pytest.raises(GPMSAError, match=f"init=study: its .*{match}.*pass tune=True"):
        _study_more(bad)
    assert _study_more(bad, tune=True).settings["tune"] is True


def test_a_study_recording_no_chain_widths_tunes_unless_untuned(plain_study):
    """A source without per-chain widths (an older file) is tuned again where its chains
    were tuned (their own widths are unknown); untuned ones run on GPM/SA's widths."""
    assert _study_more(_damaged(plain_study, {"step_widths_by_chain": None})).settings["tune"]
    untuned = _damaged(plain_study, {"step_widths_by_chain": None, "tune": False})
    assert _study_more(untuned).settings["tune"] is False


def test_a_study_append_names_draws_it_cannot_pool(plain_study):
    lam = plain_study.draws["lam"]
    with pytest.raises(GPMSAError, match=r"init=study's draws \['extra', .* not this study's"):
        _study_more(_damaged(plain_study, draws={"extra": lam}), append=True, tune=False)
    nan = plain_study.draws["lamOs"] * np.nan
    with pytest.raises(GPMSAError, match="no finite log posterior in this study"):
        _study_more(_damaged(plain_study, draws={"lamOs": nan}))
