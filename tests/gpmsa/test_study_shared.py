"""Shared calibration parameters across models (gpmsa.calibrate_study, gpmsa.fit_study)."""

import numpy as np
import pytest

import gpmsa
from gpmsa.mcmc.diagnostics import ess
from tests.gpmsa._study_cases import emulator, observations

TIGHT = gpmsa.Priors(lamOs=gpmsa.GammaPrior(1e6, 1e6 / 400.0))
"""A lamOs prior so tight (mean 400, relative sd 1e-3) that lamOs is in effect known: then a
study whose models each have their own lamOs is the same model as one with all the data."""


def _within(a: np.ndarray, b: np.ndarray, ess_a: float, ess_b: float, k: float = 4.0):
    """Means and sds agree within k Monte-Carlo standard errors (sd of the mean: sd/sqrt(ESS);
    of the sd, for a near-normal posterior: sd/sqrt(2 ESS))."""
    sd = max(a.std(), b.std())
    se_mean = sd * np.sqrt(1.0 / ess_a + 1.0 / ess_b)
    se_sd = sd * np.sqrt(1.0 / (2 * ess_a) + 1.0 / (2 * ess_b))
    assert abs(a.mean() - b.mean()) < k * se_mean, (a.mean(), b.mean(), se_mean)
    assert abs(a.std() - b.std()) < k * se_sd, (a.std(), b.std(), se_sd)


def test_two_halves_sharing_theta_equal_one_model_with_all_the_data():
    emu = emulator(TIGHT)
    x, y = observations(0.4, 8, 0.05, np.random.default_rng(3))
    study = gpmsa.calibrate_study([emu, emu], [x[::2], x[1::2]], [y[::2], y[1::2]],
                                  shared=["t"], n_samples=6000, n_burn=1000, seed=11)  # fmt: skip
    one = gpmsa.calibrate(emu, x, y, n_samples=6000, n_burn=1000, seed=12)
    exact = gpmsa.Calibrator(emu, method="grid").update(x, y)
    a, b = study.posterior.chains["t"], one.chains["t"]
    ess_a, ess_b = ess(a), ess(b)
    assert ess_a > 400 and ess_b > 400
    _within(a.ravel(), b.ravel(), ess_a, ess_b)
    # and against the exact grid posterior (no Monte-Carlo error on that side)
    sd = exact.sd("t")
    assert abs(a.mean() - exact.mean("t")) < 4 * sd / np.sqrt(ess_a)
    assert abs(a.std() - sd) < 4 * sd / np.sqrt(2 * ess_a)
    assert abs(a.mean() - 0.4) < 3 * sd  # and the truth
    # the per-model view: the same draws under the emulator's names
    mp = study.member_posterior("model1")
    assert mp.names == ("t", "lamOs") and np.array_equal(mp.samples["t"], a.ravel())
    for bad in (True, 1.0, 2, -1, [0]):  # not a model index (a bool was taken as 1)
        with pytest.raises(gpmsa.GPMSAError, match=r"model index must be an integer in \[0, 1\]"):
            study.member_posterior(bad)


def test_own_parameters_stay_separate_and_match_single_calibrations():
    """Nothing shared: the study is two independent calibrations."""
    emu = emulator(TIGHT)
    rng = np.random.default_rng(5)
    (x1, y1), (x2, y2) = observations(0.3, 4, 0.05, rng), observations(0.7, 4, 0.05, rng)
    study = gpmsa.calibrate_study([emu, emu], [x1, x2], [y1, y2], labels=["a", "b"],
                                  n_samples=4000, n_burn=500, seed=1)  # fmt: skip
    assert set(study.posterior.names) == {"t[a]", "t[b]", "lamOs[a]", "lamOs[b]"}
    for name, (x, y) in (("t[a]", (x1, y1)), ("t[b]", (x2, y2))):
        exact = gpmsa.Calibrator(emu, method="grid").update(x, y)
        draws = study.posterior.chains[name]
        assert abs(draws.mean() - exact.mean("t")) < 4 * exact.sd("t") / np.sqrt(ess(draws))


def test_shared_and_own_parameters_mix():
    """Two models with two parameters each, one shared: the study has three elements."""
    e1 = emulator(None, 0.0, 1.0, "t")
    e2 = emulator(None, 0.0, 1.0, "s")
    x, y = observations(0.4, 3, 0.05, np.random.default_rng(2))
    study = gpmsa.calibrate_study([e1, e2, e1], [x, x, x], [y, y, y], shared=["t"],
                                  n_samples=300, n_burn=50, seed=3, tune=False)  # fmt: skip
    assert study.layout.index == ((0,), (1,), (0,))
    assert [el.name for el in study.layout.elements] == ["t", "s[model1]"]


def test_several_chains_do_not_depend_on_the_workers():
    emu = emulator(None)
    x, y = observations(0.4, 3, 0.05, np.random.default_rng(2))
    kw = dict(shared=["t"], n_samples=200, n_burn=50, seed=4, n_chains=2, tune_rounds=5)
    with pytest.warns(gpmsa.ConvergenceWarning):
        one = gpmsa.calibrate_study([emu, emu], [x, x], [y, y], n_jobs=1, **kw)
    with pytest.warns(gpmsa.ConvergenceWarning):
        two = gpmsa.calibrate_study([emu, emu], [x, x], [y, y], n_jobs=2, **kw)
    assert np.array_equal(one.draws["theta"], two.draws["theta"])
    assert one.posterior.info["convergence"]["n_chains"] == 2


def test_joint_fit_shares_theta_and_recovers_it():
    """fit_study: two models (their own emulator parameters) share t; truth 0.4."""
    rng = np.random.default_rng(8)
    from tests.gpmsa._study_cases import sim_data

    sim = sim_data()
    obs = []
    for lo in (0.1, 0.5):
        x = np.linspace(lo, lo + 0.4, 4)[:, None]
        obs.append(gpmsa.ObsData(x=x, y=x * np.exp(1.5 * 0.4) + 0.03 * rng.standard_normal(
            (4, 1))))  # fmt: skip
    study = gpmsa.fit_study([sim, sim], obs, labels=["left", "right"], shared=["t"],
                            n_iter=1500, seed=5, tune_rounds=20)  # fmt: skip
    assert study.kind == "fit"
    post = study.posterior
    assert abs(post.mean("t") - 0.4) < max(3 * post.sd("t"), 0.03)
    for emu in study.members:  # each member's own calibration draws are the shared ones
        assert np.allclose(emu.calibration["theta_native"][:, 0], post.samples["t"])
        assert emu.params["lamUz"].shape == (1,)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"shared": ["E"]}, "shared parameter 'E' is unknown"),
        ({"hierarchical": ["E"]}, "hierarchical parameter 'E' is unknown"),
        ({"shared": ["t"], "hierarchical": ["t"]}, "both shared and hierarchical"),
        ({"labels": ["a", "a"]}, "labels must differ"),
        ({"labels": ["a/b", "c"]}, "model label 'a/b'"),
        ({"labels": ["a"]}, "got 1 labels for 2 models"),
        ({"hyper": {"mu_mean": 0.5}}, "hyper must be a gpmsa.HyperPriors"),
        ({"n_burn": 500}, "n_burn must be"),
        ({"tune_rounds": 0}, "tune_rounds must be an integer in [1, 1000000], got 0"),
        ({"tune_levels": 1}, "tune_levels must be an integer in [2, 1000], got 1"),
        ({"tune_rounds": 10**9}, "tune_rounds must be an integer in"),
    ],
)
def test_bad_study_input_is_named(kwargs, message):
    emu = emulator(None)
    x, y = observations(0.4, 2, 0.05, np.random.default_rng(0))
    with pytest.raises(gpmsa.GPMSAError, match=message.replace("[", r"\[")):
        gpmsa.calibrate_study(
            [emu, emu], [x, x], [y, y], **{"n_samples": 100, "n_burn": 10, **kwargs}
        )


def test_different_bounds_of_a_shared_parameter_are_refused():
    narrow = emulator(None, 0.0, 0.8)
    x, y = observations(0.4, 2, 0.05, np.random.default_rng(0))
    for kw in ({"shared": ["t"]}, {"hierarchical": ["t"]}):
        with pytest.raises(gpmsa.GPMSAError, match="'t' has different bounds"):
            gpmsa.calibrate_study([emulator(None), narrow], [x, x], [y, y], n_samples=100,
                                  n_burn=10, **kw)  # fmt: skip


def test_mismatched_numbers_are_refused():
    emu = emulator(None)
    x, y = observations(0.4, 2, 0.05, np.random.default_rng(0))
    with pytest.raises(gpmsa.GPMSAError, match="mismatched numbers of models"):
        gpmsa.calibrate_study([emu, emu], [x, x, x], [y, y], shared=["t"])
    with pytest.raises(gpmsa.GPMSAError, match="one entry per model"):
        gpmsa.calibrate_study(emu, x, y)
    with pytest.raises(gpmsa.GPMSAError, match="in one model only"):
        gpmsa.calibrate_study([emu], [x], [y], shared=["t"])
    with pytest.raises(gpmsa.GPMSAError, match="mismatched numbers of models"):
        gpmsa.fit_study([emu], [], shared=["t"])


def _tiny_fit_study(**kwargs):
    from tests.gpmsa._study_cases import sim_data

    sim = sim_data()
    obs = [gpmsa.ObsData(x=[[0.3]], y=[[0.5]]), gpmsa.ObsData(x=[[0.7]], y=[[1.2]])]
    return gpmsa.fit_study([sim, sim], obs, shared=["t"], seed=2, tune=False, n_jobs=1,
                           **kwargs)  # fmt: skip


def test_fit_study_keeps_at_most_n_keep_draws_as_fit_does():
    """fit_study thinned by ceil(chains x kept / n_keep) alone: 2 chains x 3 kept sweeps with
    n_keep=3 kept 4 draws (3 chains, 30,000 sweeps, n_keep=1000: 1002); fit keeps <= n_keep."""
    for n_iter, n_burn, chains, n_keep in ((5, 2, 2, 3), (20, 10, 3, 4), (50, 10, 2, 7)):
        with pytest.warns(gpmsa.ConvergenceWarning):
            study = _tiny_fit_study(n_iter=n_iter, n_burn=n_burn, n_chains=chains,
                                    n_keep=n_keep)  # fmt: skip
        assert study.posterior.samples["t"].size <= n_keep
        assert all(e.n_draws <= n_keep for e in study.members)
    with pytest.raises(gpmsa.GPMSAError, match=r"n_keep=2 is fewer than n_chains=3"):
        _tiny_fit_study(n_iter=6, n_burn=1, n_chains=3, n_keep=2)


def test_fit_study_takes_a_numpy_integer_n_iter_as_fit_does():
    """n_iter=np.int64(20) left n_burn None: 'n_burn must be an integer ..., got None'."""
    study = _tiny_fit_study(n_iter=np.int64(20))
    assert study.settings["n_burn"] == 4
    assert study.members[0].n_draws == 16


def test_fit_study_mean_point_lies_within_its_draws_as_fit_does():
    """point="mean" clips each element's mean to its draws' range, as gpmsa.fit does: a
    parameter whose draws never moved keeps exactly its value (the mean of equal floats can
    round one ulp past it; seed 5 leaves model b's lamUz constant)."""
    import warnings

    t = np.linspace(0.1, 0.9, 12)[:, None]
    x = np.tile([[0.0], [1.0]], (6, 1))
    sim = gpmsa.SimData(x=x, t=t, y=(x + 2 * t), t_names=["E"])
    obs = [gpmsa.ObsData(x=[[0.5]], y=[[1.5]]), gpmsa.ObsData(x=[[0.2]], y=[[1.2]])]
    for seed in (5, 12):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # a run this short does not converge
            study = gpmsa.fit_study([sim, sim], obs, shared=["E"], n_iter=12, n_burn=2,
                                    seed=seed, tune=False)  # fmt: skip
        for emu in study.members:
            for k, v in emu.params.items():
                d = emu.draws[k]
                assert np.all(d.min(axis=0) <= v) and np.all(v <= d.max(axis=0)), (seed, k)


def test_the_point_estimate_helper_clips_a_constant_mean():
    from gpmsa.fitting.fit import point_estimate

    draws = {k: np.full((3, 1), 0.1) for k in ("betaU", "lamUz", "lamWs", "lamWOs")}
    assert np.mean(draws["lamUz"]) != 0.1  # (0.1 + 0.1 + 0.1) / 3 rounds up
    params = point_estimate(draws, np.zeros(3), "mean")
    assert all(np.array_equal(v, [0.1]) for v in params.values())
    draws["lamUz"] = np.array([[1.0], [2.0], [3.0]])
    assert point_estimate(draws, np.array([0.0, 5.0, 1.0]), "map")["lamUz"] == [2.0]


def test_a_calibrated_models_posterior_refuses_other_observations(tmp_path):
    """calibrate_study records each model's observations as gpmsa.calibrate does (info
    "obs_values_sha256" of ``member_posterior``), so that ``full_prediction(posterior=)``
    refuses another model's (before: taken silently), also after saving and loading."""
    emu = emulator(None)
    rng = np.random.default_rng(7)
    (x1, y1), (x2, y2) = observations(0.3, 3, 0.05, rng), observations(0.7, 3, 0.05, rng)
    study = gpmsa.calibrate_study([emu, emu], [x1, x2], [y1, y2], shared=["t"],
                                  n_samples=200, n_burn=50, seed=2, tune=False)  # fmt: skip
    own, other = gpmsa.ObsData(x=x1, y=y1), gpmsa.ObsData(x=x2, y=y2)
    one = gpmsa.calibrate(emu, x1, y1, n_samples=100, n_burn=10, seed=0)
    post = study.member_posterior(0)
    assert post.info["obs_values_sha256"] == one.info["obs_values_sha256"]
    gpmsa.full_prediction(emu, own, [[0.5]], posterior=post, discrepancy=None, n_draws=3)
    with pytest.raises(gpmsa.GPMSAError, match="obs holds other observations"):
        gpmsa.full_prediction(emu, other, [[0.5]], posterior=post, discrepancy=None)
    study.save(tmp_path / "s.gpmsa")
    loaded = gpmsa.load_study(tmp_path / "s.gpmsa").member_posterior(1)
    assert loaded.info["obs_values_sha256"] == other.values_digest()
    with pytest.raises(gpmsa.GPMSAError, match="obs holds other observations"):
        gpmsa.full_prediction(emu, own, [[0.5]], posterior=loaded, discrepancy=None)


def test_each_models_observations_are_checked_and_reduced_once(monkeypatch):
    """calibrate_study reduces each model's observations once and records the digest of that
    reduction (it reduced them a second time for the digest, under a warnings filter); a
    backend calibration (fast=False) hands calibrate's reduction to its Problem. Draws as
    before: the same Problem is built."""
    import gpmsa.calibration.calibrate as calibrate_mod
    import gpmsa.studies.run as run_mod

    emu = emulator(None)
    rng = np.random.default_rng(7)
    (x1, y1), (x2, y2) = observations(0.3, 3, 0.05, rng), observations(0.7, 3, 0.05, rng)
    calls = []
    real = calibrate_mod.reduce

    def counted(*args, **kwargs):
        calls.append(args[1])
        return real(*args, **kwargs)

    monkeypatch.setattr(run_mod, "reduce", counted)
    monkeypatch.setattr(calibrate_mod, "reduce", counted)
    study = gpmsa.calibrate_study([emu, emu], [x1, x2], [y1, y2], shared=["t"],
                                  n_samples=60, n_burn=10, seed=2, tune=False)  # fmt: skip
    assert len(calls) == 2
    digests = [study.member_posterior(i).info["obs_values_sha256"] for i in (0, 1)]
    assert digests == [gpmsa.ObsData(x=x, y=y).values_digest() for x, y in ((x1, y1), (x2, y2))]
    calls.clear()
    post = gpmsa.calibrate(emu, x1, y1, fast=False, n_samples=40, n_burn=10, seed=0, tune=False)
    assert len(calls) == 1
    assert post.info["obs_values_sha256"] == digests[0]


def test_calibration_problem_takes_a_reduction_only_without_a_discrepancy():
    from gpmsa.calibration.calibrate import calibration_problem
    from gpmsa.calibration.observations import reduce

    emu = emulator(None)
    x, y = observations(0.3, 3, 0.05, np.random.default_rng(1))
    data = reduce(emu, x, y)
    given, own = calibration_problem(emu, x, y, reduced=data), calibration_problem(emu, x, y)
    assert np.array_equal(given.obs.z, own.obs.z)
    assert all(np.array_equal(given.init[k], own.init[k]) for k in own.init)
    with pytest.raises(gpmsa.GPMSAError, match="reduced= is the no-discrepancy reduction"):
        calibration_problem(emu, x, y, discrepancy="constant", reduced=data)
