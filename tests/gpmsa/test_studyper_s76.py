"""``fit_study(priors=, n_pc=, discrepancy=, discrepancy_groups=)`` per model (a list in the
order of the models, or a dict by label), as SEPIA builds each model of a shared or
hierarchical study with its own basis size, discrepancy and priors; ``calibrate_study``'s
discrepancy by label.

Before: each was one value for every model (a list of priors was refused, "priors must be a
gpmsa.Priors or None"; a list of n_pc "n_pc must be an integer"; a discrepancy list "fit_study
takes one discrepancy for every model"), so two models of q = 2 and 3 could not have
per-element theta priors at all."""

import dataclasses
import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.errors import GPMSAError
from tests.gpmsa._study_cases import emulator, observations

LABELS = ["a", "b"]
PA = gpmsa.Priors(theta_mean=[0.3, 0.6], theta_sd=[0.2, 0.5])
"""Model a's (E, k) theta priors."""
PB = gpmsa.Priors(theta_mean=[0.5, 0.3, 0.5], theta_sd=[1.0, 0.2, 3.0])
"""Model b's (c, E, m): its shared E second, with a's prior of E."""


def _sim(names, seed):
    """Ten runs of a four-element output of x and len(names) calibration parameters (each
    design column reaching both ends of (0, 1), so that shared ranges agree)."""
    rng = np.random.default_rng(seed)
    x, t = rng.uniform(size=(10, 1)), rng.uniform(size=(10, len(names)))
    t[0], t[1] = 0.0, 1.0
    s = np.linspace(0.0, 1.0, 4)
    y = x * np.exp(t[:, :1] * s) + 0.3 * t[:, 1:].sum(axis=1, keepdims=True) * s
    return gpmsa.SimData(x=x, t=t, y=y, t_names=list(names))


SIMS = [_sim(["E", "k"], 0), _sim(["c", "E", "m"], 1)]


def _obs():
    return gpmsa.ObsData(x=[[0.3], [0.7]], y=np.ones((2, 4)) * [[0.5], [0.9]])


def _study(**kw):
    run = dict(labels=LABELS, shared=["E"], n_iter=20, seed=1, tune_rounds=1, tune_levels=2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gpmsa.fit_study(SIMS, [_obs(), _obs()], **{**run, **kw})


def _draws(study):
    """Every draw of the study and of its members, for bit-for-bit comparisons."""
    out = [study.draws[k] for k in sorted(study.draws)]
    for e in study.members:
        out += [e.calibration[k] for k in sorted(e.calibration)]
        out += [e.draws[k] for k in sorted(e.draws)]
    return out


def _same(a, b) -> bool:
    da, db = _draws(a), _draws(b)
    return len(da) == len(db) and all(np.array_equal(x, y) for x, y in zip(da, db, strict=True))


def test_models_of_different_q_take_their_own_per_element_theta_priors(tmp_path):
    study = _study(priors={"b": PB, "a": PA})
    priors = {el.name: el.prior for el in study.layout.elements}
    # the shared E sits first in a and second in b: matched by name, its prior a's (0.3, 0.2)
    assert priors == {"E": (0.3, 0.2), "k[a]": (0.6, 0.5), "c[b]": (0.5, 1.0),
                      "m[b]": (0.5, 3.0)}  # fmt: skip
    assert [e.priors.theta_mean for e in study.members] == [PA.theta_mean, PB.theta_mean]
    assert _same(study, _study(priors=[PA, PB]))  # the list in the models' order: the same
    back = gpmsa.load_study(study.save(tmp_path / "s.gpmsa"))
    assert [(e.priors.theta_mean, e.priors.theta_sd) for e in back.members] == [
        (PA.theta_mean, PA.theta_sd), (PB.theta_mean, PB.theta_sd)]  # fmt: skip
    assert {el.name: el.prior for el in back.layout.elements} == priors
    other = dataclasses.replace(PB, theta_sd=[1.0, 0.25, 3.0])  # b's prior of E differs
    with pytest.raises(GPMSAError, match=r"shared parameter 'E'.*a: \(0.3, 0.2\), b: \(0.3, "
                                         r"0.25\).*priors="):  # fmt: skip
        _study(priors=[PA, other])
    # a hierarchical parameter's elements take the group's prior: a model's own prior of it
    # would have no effect (refused); the default at its position leaves the others' acting
    with pytest.raises(GPMSAError, match=r"model 'a': priors gives hierarchical parameter 'E'"):
        _study(priors=[PA, other], shared=[], hierarchical=["E"])
    pa = dataclasses.replace(PA, theta_mean=[0.5, 0.6], theta_sd=[10.0, 0.5])
    pb = dataclasses.replace(PB, theta_mean=[0.5, 0.5, 0.5], theta_sd=[1.0, 10.0, 3.0])
    hier = _study(priors=[pa, pb], shared=[], hierarchical=["E"])
    priors = {el.name: el.prior for el in hier.layout.elements}
    assert priors == {"E[a]": (0.5, 10.0), "k[a]": (0.6, 0.5), "c[b]": (0.5, 1.0),
                      "E[b]": (0.5, 10.0), "m[b]": (0.5, 3.0)}  # fmt: skip


def test_one_value_is_every_models():
    p = gpmsa.Priors(theta_sd=2.0, lamOs=gpmsa.GammaPrior(2.0, 1e-2))
    one = _study(priors=p, n_pc=1, discrepancy="constant")
    assert _same(one, _study(priors=[p, p], n_pc={"a": 1, "b": 1},
                             discrepancy=("constant", "constant")))  # fmt: skip
    assert [e.settings["n_pc"] for e in one.members] == [1, 1]


def test_per_model_n_pc_and_discrepancy_are_recorded_and_continued(tmp_path):
    per = dict(priors={"a": PA, "b": PB}, n_pc=[1, 2], discrepancy={"a": "constant", "b": None})
    study = _study(**per)
    back = gpmsa.load_study(study.save(tmp_path / "s.gpmsa"))
    for s in (study, back):
        assert [e.settings["n_pc"] for e in s.members] == [1, 2]
        assert [e.settings["discrepancy"] for e in s.members] == ["constant", None]
        assert [s.discrepancy(lab) is None for lab in LABELS] == [False, True]
    more = _study(init=back, **per)
    assert more.settings["continued_from"] == back.sha256
    pooled = _study(init=back, append=True, tune=False, **per)
    assert pooled.draws["theta"].shape == (1, 36, 4)  # 16 kept (n_burn 4), then 20 more
    changed = {
        r"model 'b': init=study was fitted to other .*n_pc": dict(n_pc=[1, 1]),
        r"model 'b': init=study was another model: its .*discrepancy differ":
            dict(discrepancy=["constant", "constant"]),
        r"model 'b': init=study was another model: its priors differ": dict(priors=[PA, (
            dataclasses.replace(PB, lamOs=gpmsa.GammaPrior(2.0, 1e-3)))]),
        r"theta priors\) differ .*\[\('m\[b\]', \(0.5, 3.0\).* there, \[\('m\[b\]', \(0.5, 2.0\)":
            dict(priors=[PA, dataclasses.replace(PB, theta_sd=[1.0, 0.2, 2.0])]),
    }  # fmt: skip
    for message, kw in changed.items():
        for append in (False, True):
            with pytest.raises(GPMSAError, match=message):
                _study(init=back, append=append, tune=False, **{**per, **kw})


def test_a_model_s_per_experiment_discrepancy_bases_are_its_entry(tmp_path):
    D = [np.ones((4, 1)), np.linspace(0.5, 1.0, 4)[:, None]]
    study = _study(discrepancy=[D, "linear"], discrepancy_groups=[None, [0, 1]])
    back = gpmsa.load_study(study.save(tmp_path / "s.gpmsa"))
    for s in (study, back):
        assert [e.settings["discrepancy"] for e in s.members] == ["list", "linear"]
        assert s.members[1].settings["discrepancy_groups"] == [0, 1]
        assert s.members[1].calibration["lamVz"].shape[1] == 2
        kept = s.members[0].discrepancy_bases  # as gpmsa.fit keeps a list (normalised)
        assert len(kept) == 2 and np.allclose(kept[1] / kept[1][-1], D[1] / D[1][-1])


@pytest.mark.parametrize(
    ("kw", "message"),
    [
        (dict(priors=[PA]), r"priors has 1 entries for 2 models \['a', 'b'\]"),
        (dict(priors={"a": PA, "c": PB}), r"priors as a dict by label names unknown model\(s\) "
                                          r"\['c'\] and has no entry for model\(s\) \['b'\]"),
        (dict(n_pc={"a": 1}), r"n_pc as a dict by label has no entry for model\(s\) \['b'\]"),
        (dict(priors=[PB, PA]), r"model 'a': priors: Priors.theta_mean gives 3 .* q = 2"),
        (dict(priors=[PA, PA]), r"model 'b': priors: Priors.theta_mean gives 2 .* q = 3"),
        (dict(priors=PA), r"model 'b': priors: Priors.theta_mean gives 2 .* q = 3"),
        (dict(priors=[PA, "x"]), r"model 'b': priors must be a gpmsa.Priors or None, got 'x'"),
        (dict(priors={"a": PA, "b": PB.with_data((1.0, 1.0))}), r"model 'b': priors are already"),
        (dict(n_pc=[1, "x"]), r"model 'b': n_pc must be an integer >= 1, got 'x'"),
        (dict(n_pc=np.array([1, 2])), r"model 'a': n_pc must be"),
        (dict(n_pc=(1, 2, 1)), r"n_pc has 3 entries for 2 models"),
        (dict(discrepancy=[None, "constant", None]), r"discrepancy has 3 entries for 2 models"),
        (dict(discrepancy=5), r"discrepancy must be None, 'constant'"),
        (dict(discrepancy={"a": "constant"}), r"discrepancy as a dict by label has no entry "),
        (dict(discrepancy={"a": None, "b": None}, discrepancy_groups={"b": [0], "a": None}),
         r"model 'b': discrepancy_groups needs a discrepancy basis"),
        (dict(discrepancy="constant", discrepancy_groups=[None, None, None]),
         r"discrepancy_groups has 3 entries for 2 models \['a', 'b'\]"),
    ],
)  # fmt: skip
def test_bad_per_model_values_are_refused_naming_the_argument_and_model(kw, message):
    with pytest.raises(GPMSAError, match=message):
        _study(n_iter=5, **{"priors": [PA, PB], **kw})


def test_calibrate_study_takes_each_model_s_discrepancy_by_label():
    rng = np.random.default_rng(2)
    data = [observations(th, 4, 0.03, rng) for th in (0.35, 0.5)]
    emu = emulator(None)
    run = dict(labels=LABELS, shared=["t"], n_samples=30, n_burn=5, seed=0, tune=False)

    def cal(**kw):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return gpmsa.calibrate_study([emu, emu], [d[0] for d in data], [d[1] for d in data],
                                         **run, **kw)  # fmt: skip

    listed = cal(discrepancy=["constant", None])
    named = cal(discrepancy={"b": None, "a": "constant"}, discrepancy_groups={"a": [0], "b": None})
    assert named.discrepancy("a") is not None and named.discrepancy("b") is None
    assert all(np.array_equal(listed.draws[k], named.draws[k]) for k in listed.draws)
    with pytest.raises(GPMSAError, match=r"discrepancy as a dict by label names unknown model"):
        cal(discrepancy={"a": "constant", "b": None, "B": None})
