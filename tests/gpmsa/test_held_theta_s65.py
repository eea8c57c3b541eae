"""Review of session 64's held parameters (``fixed=``): three items.

- A study's held theta read back through the unit scale: ``lo + u * (hi - lo)`` with ``u =
  (v - lo) / (hi - lo)`` came back an ulp off the given native value for about 1 value in 8
  (sd still 0), while ``gpmsa.calibrate`` writes the value given. ``calibrate_study`` and
  ``fit_study`` (its posterior, each member's ``theta_native``) and ``gpmsa.fit``'s
  ``theta_native`` now report it exactly, also after a study's save and load.
- A held categorical theta: ``calibrate`` snapped a value within 1e-12 (unit scale) of a level
  onto it (and reported the value given, not the level), ``fit`` refused the same value ("lies
  outside its prior's bounds"). The snap now lives in ``fixed_elements.theta_unit``: every
  path holds such a value at its level, reported as the level's code; the studies refuse a
  categorical theta whatever the value (their theta moves are continuous).
- The held-element masks: one ``Problem.held_masks`` for calibrate's backend path, the
  studies' records and held theta, fit's draws and the pyro backend's sites.
"""

import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa import GPMSAError
from gpmsa.model import fixed_elements as per_element
from gpmsa.model.problem import prepare
from tests.gpmsa._calib_cases import two_param_emulator

RUN = {"n_samples": 20, "n_burn": 5, "tune_rounds": 2, "tune_levels": 3}
LO, HI = 1.7, 13.3
OFF = (8.221889369850102, 4.702829280782814)  # read back through (LO, HI): an ulp off


def _sim():
    t = np.linspace(LO, HI, 12)[:, None]
    x = np.tile([[0.0], [1.0]], (6, 1))
    return gpmsa.SimData(x=x, t=t, y=(x + 2 * t), t_names=["E"])


def _emulator():
    prm = {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [1e4], "lamWOs": [1e4]}
    return gpmsa.Emulator.from_params(_sim(), prm)


def _quiet(call, *args, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # short toy chains: not converged
        return call(*args, **kw)


def _cal_study(**kw):
    emu = _emulator()
    return _quiet(gpmsa.calibrate_study, [emu, emu], [[[0.5]], [[0.2]]], [[3.5], [3.2]],
                  seed=1, **{**RUN, **kw})  # fmt: skip


def _fit_study(**kw):
    obs = [gpmsa.ObsData(x=[[0.5]], y=[[3.5]]), gpmsa.ObsData(x=[[0.2]], y=[[3.2]])]
    return _quiet(gpmsa.fit_study, [_sim(), _sim()], obs, n_iter=30, seed=1, tune_rounds=2,
                  tune_levels=3, **kw)  # fmt: skip


def test_the_values_read_back_through_the_unit_scale_an_ulp_off():
    std = _emulator().standardizer
    for v in OFF:  # the cases below would pass by luck without this
        assert std.t_from_unit(std.t_to_unit([[v]]))[0, 0] != v


@pytest.mark.parametrize("make", [_cal_study, _fit_study], ids=["calibrate_study", "fit_study"])
def test_a_studys_held_theta_is_reported_exactly_as_given(make, tmp_path):
    v = OFF[0]
    shared = make(shared=["E"], fixed={"theta": {"E": v}})
    assert np.all(shared.posterior.samples["E"] == v) and shared.posterior.sd("E") == 0.0
    assert shared.settings["held_theta"] == {"E": v}
    assert np.all(shared.member_posterior(1).samples["E"] == v)
    own = make(fixed=[{"theta": {"E": OFF[0]}}, {"theta": [OFF[1]]}])  # each model its own
    assert np.all(own.posterior.samples["E[model0]"] == OFF[0])
    assert np.all(own.posterior.samples["E[model1]"] == OFF[1])
    if shared.kind == "fit":  # each member's theta_native, as gpmsa.fit's
        assert all(np.all(m.calibration["theta_native"] == v) for m in shared.members)
        assert np.all(own.members[1].calibration["theta_native"] == OFF[1])
    back = gpmsa.load_study(shared.save(tmp_path / "s.gpmsa"))
    assert np.all(back.posterior.samples["E"] == v)
    assert np.array_equal(back.draws["theta"], shared.draws["theta"])  # unit draws as sampled


def test_a_studys_held_theta_record_that_its_draws_do_not_hold_is_refused():
    study = _cal_study(shared=["E"], fixed={"theta": {"E": OFF[0]}})
    args = ("calibration", study.members, study.layout, study.hyper, study.draws)
    cases = [({"E": OFF[0] + 1e-6}, "is not the value its draws hold"),
             ({"F": 2.0}, "'F' is no study element"), ({"E": "2"}, "must be a number"),
             ([2.0], "must be an object")]  # fmt: skip
    for held, match in cases:
        with pytest.raises(GPMSAError, match=match):
            gpmsa.Study(*args, {**study.settings, "held_theta": held})
    free = _cal_study(shared=["E"])  # a sampled element is no held value
    with pytest.raises(GPMSAError, match="is not the value its draws hold"):
        gpmsa.Study("calibration", free.members, free.layout, free.hyper, free.draws,
                    {**free.settings, "held_theta": {"E": 5.0}})  # fmt: skip


def test_a_fits_held_theta_native_is_the_value_given():
    obs = gpmsa.ObsData(x=[[0.5]], y=[[3.5]])
    emu = _quiet(gpmsa.fit, _sim(), obs, n_iter=30, seed=1, tune_rounds=2,
                 fixed={"theta": {"E": OFF[0]}})  # fmt: skip
    assert np.all(emu.calibration["theta_native"] == OFF[0])
    assert emu.settings["fixed"]["theta"] == [float(emu.calibration["theta"][0, 0])]


def test_calibrate_takes_a_theta_element_keyed_by_a_one_tuple():
    # before: TypeError (int() of the tuple) writing the held value into the draws
    emu = two_param_emulator()
    for fast in (True, False):
        post = _quiet(gpmsa.calibrate, emu, [[0.3], [0.7]], [[0.9], [1.2]], seed=1, fast=fast,
                      fixed={"theta": {(0,): 0.4}}, **RUN)  # fmt: skip
        assert np.all(post.samples["a"] == 0.4) and post.sd("b") > 0


# --- a held categorical theta: snapped with its conversion, on every path ------------------------
def _categorical():
    rng = np.random.default_rng(0)
    x, t = rng.random(30), (np.arange(30) % 3) * 3 + 1  # levels 1, 4, 7: unit 0, 0.5, 1
    shift = np.zeros(8)
    shift[[4, 7]] = 1.0, -0.7
    sim = gpmsa.SimData(x, t, x + shift[t], t_categorical=[0])
    emu = gpmsa.Emulator.from_params(sim, {"betaU": [[1.0], [1.0]], "lamUz": [1.0],
                                           "lamWs": [1e3], "lamWOs": [1e3]})  # fmt: skip
    xo = np.linspace(0.1, 0.9, 5)[:, None]
    return sim, emu, xo, xo[:, 0] + 0.5


NEAR = 4 + 3e-12  # 5e-13 from level 4 on the unit scale: that level
LEVEL_HELD = [({"t0": 4}, 4.0), ({"t0": NEAR}, 4.0), ([NEAR], 4.0), ({0: 7}, 7.0)]
NOT_A_LEVEL = "fixed theta: categorical calibration parameter t0 must be one of its training levels"


def test_theta_unit_puts_a_held_categorical_value_exactly_on_its_level():
    _, emu, _, _ = _categorical()
    std, lv = emu.standardizer, [(0.0, 0.5, 1.0)]
    assert per_element.theta_unit({"t0": NEAR}, std, ["t0"], lv).tolist() == [0.5]  # whole
    assert per_element.theta_unit([NEAR], std, ["t0"], lv)[0] == 0.5
    assert per_element.held_native({"t0": NEAR}, ["t0"], lv) == {0: 4.0}
    assert per_element.held_native([NEAR], ["t0"], [None]) == {0: NEAR}
    with pytest.raises(GPMSAError, match=NOT_A_LEVEL):
        per_element.theta_unit({"t0": 4 + 1e-9}, std, ["t0"], lv)


@pytest.mark.parametrize(("held", "level"), LEVEL_HELD)
def test_calibrate_holds_a_categorical_theta_at_its_level(held, level):
    _, emu, xo, yo = _categorical()
    post = _quiet(gpmsa.calibrate, emu, xo, yo, seed=1, fixed={"theta": held}, **RUN)
    assert np.all(post.samples["t0"] == level)  # before: NEAR itself
    assert post.info["fixed"] == {"theta": [(level - 1) / 6]}
    with pytest.raises(GPMSAError, match=NOT_A_LEVEL):
        gpmsa.calibrate(emu, xo, yo, fixed={"theta": {"t0": 5.0}}, **RUN)


@pytest.mark.parametrize(("held", "level"), LEVEL_HELD)
def test_fit_holds_a_categorical_theta_at_its_level(held, level):
    sim, _, xo, yo = _categorical()
    obs = gpmsa.ObsData(xo, yo[:, None])
    emu = _quiet(gpmsa.fit, sim, obs, n_iter=20, seed=0, tune_rounds=2,
                 fixed={"theta": held})  # before: NEAR refused  # fmt: skip
    assert np.all(emu.calibration["theta_native"] == level)
    assert emu.settings["fixed"] == {"theta": [(level - 1) / 6]}
    with pytest.raises(GPMSAError, match=NOT_A_LEVEL):
        gpmsa.fit(sim, obs, n_iter=20, fixed={"theta": [5.0]})


@pytest.mark.parametrize("value", [4, NEAR])
def test_the_studies_hold_a_categorical_theta_at_its_level(value):
    """The studies calibrate a categorical theta since session 72 (they refused it, held or
    not): held, at its level exactly, as gpmsa.fit holds it."""
    sim, emu, xo, yo = _categorical()
    obs = gpmsa.ObsData(xo, yo[:, None])
    fixed = {"theta": {"t0": value}}
    study = _quiet(gpmsa.calibrate_study, [emu, emu], [xo, xo], [yo, yo], fixed=fixed, **RUN)
    assert np.all(study.posterior.chains["t0[model0]"] == 4.0)
    study = _quiet(gpmsa.fit_study, [sim, sim], [obs, obs], n_iter=20, tune_rounds=2,
                   fixed=fixed)  # fmt: skip
    assert all(np.all(m.calibration["theta_native"] == 4.0) for m in study.members)


def test_the_studies_refuse_a_held_categorical_theta_off_its_levels():
    sim, emu, xo, yo = _categorical()
    obs = gpmsa.ObsData(xo, yo[:, None])
    fixed = {"theta": {"t0": 5.0}}
    with pytest.raises(GPMSAError, match=f"model 'model0': {NOT_A_LEVEL}"):
        gpmsa.calibrate_study([emu, emu], [xo, xo], [yo, yo], fixed=fixed, **RUN)
    with pytest.raises(GPMSAError, match=f"model 'model0': {NOT_A_LEVEL}"):
        gpmsa.fit_study([sim, sim], [obs, obs], n_iter=20, fixed=fixed)


# --- one Problem.held_masks ----------------------------------------------------------------------
def test_problem_held_masks_marks_whole_and_single_elements():
    sim = _sim()
    problem = prepare(sim, gpmsa.ObsData(x=[[0.5]], y=[[3.5]])).problem
    assert problem.held_masks() == {}
    held = problem.with_fixed({"lamOs": 50.0, "betaU": {(1, 0): 0.3}, "theta": {0: 0.25}})
    masks = held.held_masks()
    assert list(masks) == ["theta", "betaU", "lamOs"]  # the sweep order
    assert masks["theta"].tolist() == [True] and masks["lamOs"].tolist() == [True]
    assert masks["betaU"].tolist() == [[False], [True]]
    assert list(held.held_masks(("theta", "lamOs", "lamVz"))) == ["theta", "lamOs"]
    assert held.held_masks(()) == {}
