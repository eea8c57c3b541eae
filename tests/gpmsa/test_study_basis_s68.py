"""A study's continuation (``fit_study(..., init=study)``, ``calibrate_study(..., init=study)``,
``append=True``) across a basis whose columns are the source's up to their signs and order: the
same models, their state mapped as a single fit's continuation maps it (s68)."""

import functools
import warnings

import numpy as np
import pytest
from _basis_cases import GROUPS, D, basis_obs, basis_sim

import gpmsa
from gpmsa.calibration.calibrate import calibration_problem
from gpmsa.fitting.continuation import sweeps_run
from gpmsa.model.discrepancy import record
from gpmsa.model.problem import prepare
from gpmsa.studies import continuation as cont
from gpmsa.studies.record import DISCREPANCIES
from gpmsa.studies.sampler import StudyState

KW = {"labels": ["a", "b"], "shared": ["t"], "n_chains": 2, "tune_rounds": 3, "tune_levels": 3}


@functools.cache
def _data():
    return basis_sim(), [basis_obs(0.05 * k) for k in range(2)]


def _fit_study(**kw):
    sim, obs = _data()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # short chains
        return gpmsa.fit_study([sim] * 2, obs, **{**KW, **kw})


@functools.cache
def _fit_source():
    return _fit_study(n_iter=40, n_keep=10, seed=0)  # 5 draws a chain, thin 8


def _moved_basis():
    return _fit_source().members[0].K[:, ::-1] * [1.0, -1.0]  # swapped, one sign flipped


def test_fit_study_maps_a_reordered_basis_start_and_widths():
    src = _fit_source()
    sim, obs = _data()
    K = _moved_basis()
    preps = [prepare(sim, o, basis=K) for o in obs]
    problems = [p.problem for p in preps]
    starts = cont.chain_starts(src, cont.fit_starts(src, problems, preps, obs, 2))
    there = [prepare(sim, o, basis=src.members[0].K).problem for o in obs]
    for c in range(2):  # the same models: the same log posterior at the mapped state
        for j, member in enumerate(src.members):
            np.testing.assert_array_equal(starts[c][0][j]["lamUz"],
                                          member.draws["lamUz"][5 * c + 4][::-1])  # fmt: skip
        here = StudyState(problems, src.layout, src.hyper, *starts[c], np.random.default_rng(0))
        old = cont.chain_starts(src, cont.fit_starts(src, there, preps, obs, 2))[c]
        ref = StudyState(there, src.layout, src.hyper, *old, np.random.default_rng(0))
        assert here.log_post() == pytest.approx(ref.log_post(), rel=1e-10)
    more = _fit_study(n_iter=8, seed=1, init=src, basis=K)
    was, now = src.settings[cont.WIDTHS_BY_CHAIN], more.settings[cont.WIDTHS_BY_CHAIN]
    for lab in ("a", "b"):  # each chain runs on with its widths, component 0 the source's 1
        assert was[f"{lab}.lamUz[0]"] != was[f"{lab}.lamUz[1]"]
        assert now[f"{lab}.lamUz[0]"] == was[f"{lab}.lamUz[1]"]
        assert now[f"{lab}.lamWs[1]"] == was[f"{lab}.lamWs[0]"]
        assert now[f"{lab}.betaU[1, 0]"] == was[f"{lab}.betaU[1, 1]"]


def test_an_appended_fit_study_pools_the_mapped_source():
    src, K = _fit_source(), _moved_basis()
    run = {"n_iter": 8, "seed": 1, "init": src, "basis": K, "tune": False}
    own = _fit_study(**run)  # the continuation alone: its sweeps' acceptance
    emu = _fit_study(append=True, **run)
    for j, member in enumerate(emu.members):  # each chain's source part first, mapped
        old = src.members[j]
        pooled = member.draws["betaU"].reshape(2, -1, 2, 2)[:, :5]
        np.testing.assert_array_equal(pooled, old.draws["betaU"].reshape(2, 5, 2, 2)[..., ::-1])
        lam = member.draws["lamWs"].reshape(2, -1, 2)[:, :5]
        np.testing.assert_array_equal(lam, old.draws["lamWs"].reshape(2, 5, 2)[..., ::-1])
    n, was = sweeps_run(src.settings), src.settings["accept_rate"]
    for lab in ("a", "b"):
        for new, old in ((f"{lab}.lamUz[0]", f"{lab}.lamUz[1]"), ("t", "t")):
            r = own.settings["accept_rate"][new]
            assert emu.settings["accept_rate"][new] == pytest.approx(
                (was[old] * n + r * 8) / (n + 8), rel=1e-12
            )


def test_a_held_component_with_the_basis_reordered_is_still_refused():
    held = {"fixed": {"lamUz": {0: 1.0}}, "n_iter": 8, "tune": False}
    src = _fit_study(seed=0, n_keep=4, **held)
    with pytest.raises(gpmsa.GPMSAError, match="model 'a': init=study was another model: its "
                       "fixed parameters differ"):  # fmt: skip
        _fit_study(seed=1, init=src, basis=_moved_basis(), **held)


@functools.cache
def _emulator():
    return gpmsa.fit(_data()[0], n_iter=40, seed=0, n_keep=10)


def _calibrate(**kw):
    _, obs = _data()
    args = {"discrepancy": D, "discrepancy_groups": GROUPS, **KW, **kw}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # short chains
        return gpmsa.calibrate_study([_emulator()] * 2, obs, **args)


@functools.cache
def _cal_source():
    return _calibrate(n_samples=40, n_burn=10, seed=0)


@pytest.mark.parametrize("append", [False, True])
def test_calibrate_study_continues_across_d_s_signs_and_order_bit_for_bit(append):
    run = {"n_samples": 8, "seed": 1, "init": _cal_source(), "append": append, "tune": False}
    ref = _calibrate(**run).draws
    # -D, and D's columns reordered (each keeping its group) with a sign flipped: the same
    # draws; the log posterior recorded of the reordered basis's agrees to rounding (its
    # determinant's sums run in another order; as gpmsa.fit's emu.log_post)
    for d, groups in ((-D, GROUPS), (D[:, [2, 0, 1]] * [1, -1, 1], [1, 0, 0])):
        got = _calibrate(discrepancy=d, discrepancy_groups=groups, **run).draws
        assert got.keys() == ref.keys()
        for k, v in ref.items():
            if k == "log_post" and groups != GROUPS:
                np.testing.assert_allclose(got[k], v, rtol=1e-12, atol=0.0)
            else:
                np.testing.assert_array_equal(got[k], v, err_msg=k)


@pytest.mark.parametrize("kw", [
    {"discrepancy": D**2},  # another basis
    {"discrepancy": D[:, [1, 0, 2]], "discrepancy_groups": [0, 1, 1]},  # columns change groups
    {"discrepancy": D, "discrepancy_groups": [0, 1, 1]},
    {"discrepancy": [-D, D**2]},  # one model's the same, the other's not
])  # fmt: skip
def test_calibrate_study_still_refuses_another_discrepancy(kw):
    with pytest.raises(gpmsa.GPMSAError, match=r"init=study was another study: its "
                       r"discrepancy differ \(discrepancy: "):  # fmt: skip
        _calibrate(n_samples=8, seed=1, init=_cal_source(), **kw)


def test_same_discrepancies_maps_only_a_model_s_signed_reordering():
    _, obs = _data()
    old = _cal_source().settings[DISCREPANCIES]
    probs = {}
    for name, d in (("minus", -D), ("other", D**2)):
        probs[name] = calibration_problem(_emulator(), obs[0].x, obs[0].y, discrepancy=d,
                                          discrepancy_groups=GROUPS).obs  # fmt: skip
    for name, same in (("minus", True), ("other", False)):
        new = {"a": {**old["a"], **record(probs[name])}, "b": old["b"]}
        assert new != old
        assert (cont.same_discrepancies(old, new, {"a": probs[name]}) == old) is same
    moved = {"a": {**old["a"], **record(probs["minus"]), "discrepancy": "linear"}}
    assert cont.same_discrepancies(old, moved, {"a": probs["minus"]}) == moved  # another kind
