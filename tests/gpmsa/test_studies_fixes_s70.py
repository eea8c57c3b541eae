"""Shared and hierarchical studies (session 70): hyperpriors given to a study with no
hierarchical group were ignored without a word; a uniform sd prior's sd_max of 1e-8 ran a chain
that never left its start (0 acceptance, the group sd reported as 1e-154); a model without
observations was refused with a shape message; the study's posteriors carried no units, so
their plots had none (one model's calibration's do)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from _study_cases import PARAMS, emulator, observations, sim_data

import gpmsa
from gpmsa.studies.layout import SD_MAX_MIN


def _obs(n_models: int = 2, seed: int = 0):
    rng = np.random.default_rng(seed)
    pairs = [observations(0.45, 5, 0.05, rng) for _ in range(n_models)]
    return [x for x, _ in pairs], [y for _, y in pairs]


def _quiet(fn, *args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return fn(*args, **kwargs)


RUN = {"n_samples": 30, "n_burn": 5, "tune_rounds": 2, "seed": 0}


@pytest.mark.parametrize("hyper", [gpmsa.HyperPriors(), gpmsa.HyperPriors.sepia()])
def test_hyperpriors_without_a_hierarchical_group_are_refused(hyper):
    xs, ys = _obs()
    with pytest.raises(gpmsa.GPMSAError, match=r"hyper: .*no hierarchical group.*hierarchical="):
        gpmsa.calibrate_study([emulator()] * 2, xs, ys, shared=["t"], hyper=hyper, **RUN)
    obs = [gpmsa.ObsData(x=x, y=y) for x, y in zip(xs, ys, strict=True)]
    with pytest.raises(gpmsa.GPMSAError, match=r"hyper: .*no hierarchical group"):
        gpmsa.fit_study([sim_data()] * 2, obs, hyper=hyper, n_iter=20, seed=0)
    study = _quiet(gpmsa.calibrate_study, [emulator()] * 2, xs, ys, shared=["t"], **RUN)
    with pytest.raises(gpmsa.GPMSAError, match=r"hyper: .*no hierarchical group"):
        gpmsa.calibrate_study([emulator()] * 2, xs, ys, shared=["t"], hyper=hyper,
                              **{**RUN, "n_burn": 0}, init=study)  # fmt: skip


def test_a_continuation_without_a_group_ignores_the_recorded_hyperpriors():
    """A study file before sd_prior recorded SEPIA's hyperpriors (a group-less one too): it
    continues without hyper= (which is now refused there), as their prior acts on nothing."""
    xs, ys = _obs()
    src = _quiet(gpmsa.calibrate_study, [emulator()] * 2, xs, ys, shared=["t"], **RUN)
    old = gpmsa.Study(src.kind, src.members, src.layout, gpmsa.HyperPriors.sepia(), src.draws,
                      src.settings)  # fmt: skip
    more = _quiet(gpmsa.calibrate_study, [emulator()] * 2, xs, ys, shared=["t"],
                  **{**RUN, "n_burn": 0}, init=old)  # fmt: skip
    assert more.settings["continued_from"] is None and more.draws["theta"].shape[1] == 30


def test_a_continuation_with_a_group_still_refuses_other_hyperpriors():
    xs, ys = _obs()
    src = _quiet(gpmsa.calibrate_study, [emulator()] * 2, xs, ys, hierarchical=["t"], **RUN)
    with pytest.raises(gpmsa.GPMSAError, match="its hyper differ"):
        gpmsa.calibrate_study([emulator()] * 2, xs, ys, hierarchical=["t"],
                              hyper=gpmsa.HyperPriors.sepia(), **{**RUN, "n_burn": 0},
                              init=src)  # fmt: skip


@pytest.mark.parametrize("sd_max", [1e-8, 5e-5, 9.9e-4])
def test_an_sd_max_too_small_to_mix_is_refused(sd_max):
    xs, ys = _obs()
    hyper = gpmsa.HyperPriors(sd_max=sd_max)  # a HyperPriors (and a study file) may hold it
    with pytest.raises(gpmsa.GPMSAError, match=r"sd_max=.* below 0.001.*0.01 to 10.*shared="):
        gpmsa.calibrate_study([emulator()] * 2, xs, ys, hierarchical=["t"], hyper=hyper, **RUN)
    obs = [gpmsa.ObsData(x=x, y=y) for x, y in zip(xs, ys, strict=True)]
    with pytest.raises(gpmsa.GPMSAError, match=r"sd_max=.* below 0.001"):
        gpmsa.fit_study([sim_data()] * 2, obs, hierarchical=["t"], hyper=hyper, n_iter=20)


def test_the_smallest_sd_max_kept_moves():
    """At SD_MAX_MIN the chain (started at mu = theta = 0.5 exactly) moves; at 1e-8 it stayed
    at its start with every proposal rejected and lam drifting to 1e308."""
    xs, ys = _obs(3)
    hyper = gpmsa.HyperPriors(sd_max=SD_MAX_MIN)
    study = _quiet(gpmsa.calibrate_study, [emulator()] * 3, xs, ys, hierarchical=["t"],
                   hyper=hyper, n_samples=300, n_burn=50, seed=1)  # fmt: skip
    rates = study.settings["accept_rate"]
    assert min(rates[f"t[model{i}]"] for i in range(3)) > 0.1 and rates["t.mu"] > 0.1
    sd = study.posterior.samples["t.sd"]
    assert 1e-6 < sd.min() and sd.max() < SD_MAX_MIN
    assert gpmsa.HyperPriors.sepia().sd_max < 1e9  # the gamma prior does not use sd_max


@pytest.mark.parametrize(
    ("x", "y", "what"),
    [(np.empty((0, 1)), np.empty((0, 1)), "x_obs"), ([], [], "x_obs"),
     ([[0.5]], np.empty((0, 1)), "y_obs")],
)  # fmt: skip
def test_a_model_without_observations_is_named(x, y, what):
    xs, ys = _obs()
    with pytest.raises(gpmsa.GPMSAError,
                       match=rf"model 'b' has no observations \(its {what} holds no "
                             r"experiments.*leave model 'b' out"):  # fmt: skip
        gpmsa.calibrate_study([emulator()] * 2, [xs[0], x], [ys[0], y], labels=["a", "b"],
                              shared=["t"], **RUN)  # fmt: skip


def _with_units(unit: str = "Pa") -> gpmsa.Emulator:
    s = sim_data()
    sim = gpmsa.SimData(x=s.x, t=s.t, y=s.y, x_names=["x"], t_names=["t"], t_units=[unit])
    return gpmsa.Emulator.from_params(sim, PARAMS)


def test_study_posteriors_carry_the_emulators_units(tmp_path):
    xs, ys = _obs(3)
    emu = _with_units()
    one = _quiet(gpmsa.calibrate, emu, xs[0], ys[0], n_samples=30, n_burn=5, seed=0)
    study = _quiet(gpmsa.calibrate_study, [emu] * 3, xs, ys, hierarchical=["t"], **RUN)
    want = {f"t[model{i}]": "Pa" for i in range(3)} | {"t.mu": "Pa", "t.sd": "Pa"}
    assert study.posterior.info["units"] == want
    assert study.member_posterior(1).info["units"] == one.info["units"] == {"t": "Pa"}
    fig = study.posterior.plot("t.mu")
    assert (fig.axes[0].get_xlabel(), one.plot("t").axes[0].get_xlabel()) == ("t.mu (Pa)",
                                                                            "t (Pa)")  # fmt: skip
    trace = gpmsa.plots.traces(study.posterior, names=["t[model0]"])
    assert "t[model0] (Pa)" in [ax.get_ylabel() for ax in trace.axes]
    study.save(tmp_path / "s.gpmsa")  # the study file is unchanged: units come from members
    assert gpmsa.load_study(tmp_path / "s.gpmsa").posterior.info["units"] == want


def test_a_shared_parameter_whose_models_disagree_on_its_unit_gets_none():
    xs, ys = _obs()
    study = _quiet(gpmsa.calibrate_study, [_with_units("Pa"), _with_units("MPa")], xs, ys,
                   shared=["t"], **RUN)  # fmt: skip
    assert "t" not in study.posterior.info["units"]
    assert study.member_posterior(1).info["units"] == {"t": "MPa"}
