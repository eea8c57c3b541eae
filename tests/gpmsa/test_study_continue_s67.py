"""Continuing a study's chains (``init=study``, session 67): SEPIA's second ``do_mcmc`` of its
shared and hierarchical models."""

import functools
import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.mcmc.diagnostics import ess
from gpmsa.studies import continuation as cont
from gpmsa.studies.sampler import StudyState
from tests.gpmsa._study_cases import emulator, observations, sim_data

LABELS = ["a", "b", "c"]


def _data(n_models: int = 3, seed: int = 3):
    rng = np.random.default_rng(seed)
    pairs = [observations(0.3 + 0.1 * k, 4, 0.05, rng) for k in range(n_models)]
    return [x for x, _ in pairs], [y for _, y in pairs]


TIGHT = gpmsa.Priors(lamOs=gpmsa.GammaPrior(1e6, 1e6 / 400.0))
"""lamOs in effect known (mean 400, relative sd 1e-3), as test_study_shared's."""


def _calibrate(n_samples, seed, init="auto", n_chains=2, priors=None, **kw):
    xs, ys = _data()
    args = {"labels": LABELS, "shared": ["t"], "tune_rounds": 5, "tune_levels": 5, **kw}
    with warnings.catch_warnings():  # short chains: not converged
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        return gpmsa.calibrate_study([emulator(priors)] * 3, xs, ys, n_samples=n_samples, seed=seed,
                                     n_chains=n_chains, init=init, **args)  # fmt: skip


def test_hierarchical_continuation_starts_at_the_source_s_last_draws():
    """Each chain's first sweep runs from the source's last kept draw (theta, lamOs, the
    group's mu and lam) with the widths that chain was tuned to; same seed, same draws."""
    kw = {"shared": [], "hierarchical": ["t"]}
    src = _calibrate(100, 1, n_burn=30, **kw)
    assert set(src.settings[cont.WIDTHS_BY_CHAIN]) == set(src.settings["step_widths"])
    again = _calibrate(50, 7, init=src, **kw)
    s = again.settings
    assert (s["tune"], s["n_burn"], s["init"], s[cont.STEPS]) == (False, 0, "continued", False)
    assert s["continued_from"] is None  # the source was never saved
    xs, ys = _data()
    problems, layout = _problems(src, xs, ys)
    seeds = np.random.SeedSequence(s["seed"]).spawn(2)
    for c in range(2):
        start = cont.chain_starts(src, cont.calibration_starts(src, problems))[c]
        state = StudyState(problems, layout, src.hyper, *start, np.random.default_rng(seeds[c]))
        assert np.array_equal(state.g, src.draws["theta"][c, -1])
        assert (state.mu, state.lam) == (src.draws["mu"][c, -1], src.draws["lam"][c, -1])
        names = list(src.settings["step_widths"])
        widths = np.array([src.settings[cont.WIDTHS_BY_CHAIN][n][c] for n in names])
        state.sweep(widths, False, np.zeros(widths.size))
        assert np.array_equal(state.g, again.draws["theta"][c, 0])
        assert (state.mu, state.lam) == (again.draws["mu"][c, 0], again.draws["lam"][c, 0])
        lam_os = [float(m.params["lamOs"][0]) for m in state.states]
        assert lam_os == list(again.draws["lamOs"][c, 0])
    for k, v in _calibrate(50, 7, init=src, **kw).draws.items():
        assert np.array_equal(v, again.draws[k]), k


def _problems(study, xs, ys):
    """The study's models' calibration problems, as calibrate_study builds them."""
    from gpmsa.calibration.calibrate import calibration_problem

    probs = [calibration_problem(e, x, y) for e, x, y in zip(study.members, xs, ys, strict=True)]
    return probs, study.layout


def test_continuation_agrees_with_a_long_fresh_run():
    """A short study continued runs on to the posterior a long fresh one samples."""
    src = _calibrate(100, 2, n_burn=50, priors=TIGHT)
    more = _calibrate(2000, 3, init=src, priors=TIGHT)
    fresh = _calibrate(2000, 4, priors=TIGHT)
    for name in ("t",):  # lamOs in effect known: t mixes well
        a, b = more.posterior.chains[name], fresh.posterior.chains[name]
        ea, eb = ess(a), ess(b)
        assert min(ea, eb) > 150, (ea, eb)
        sd = max(a.std(), b.std())
        assert abs(a.mean() - b.mean()) < 4 * sd * np.sqrt(1 / ea + 1 / eb), name
        assert abs(a.std() - b.std()) < 4 * sd * np.sqrt(0.5 / ea + 0.5 / eb), name


def test_fit_study_continues_a_loaded_study_and_records_its_digest(tmp_path):
    """A fit_study continuation (emulator parameters too) of a study read back from its file:
    the chain starts at each member's last kept draw, records the file's digest, saves and
    loads; one chain runs on with the widths it recorded."""
    sim = sim_data()
    xs, ys = _data(2)
    obs = [gpmsa.ObsData(x=x, y=y) for x, y in zip(xs, ys, strict=True)]
    kw = {"labels": ["a", "b"], "shared": ["t"], "tune_rounds": 3, "tune_levels": 3, "n_keep": 40}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # short chains, few observations
        src = gpmsa.fit_study([sim] * 2, obs, n_iter=80, seed=1, **kw)
        src.save(tmp_path / "s.gpmsa")
        loaded = gpmsa.load_study(tmp_path / "s.gpmsa")
        more = gpmsa.fit_study([sim] * 2, obs, n_iter=80, seed=5, init=loaded, **kw)
        same = gpmsa.fit_study([sim] * 2, obs, n_iter=80, seed=5, init=src, **kw)
    assert more.settings["continued_from"] == loaded.sha256 is not None
    assert more.settings["step_widths"] == pytest.approx(src.settings["step_widths"])
    assert np.array_equal(more.draws["theta"], same.draws["theta"])
    assert (more.settings["tune"], more.settings["n_burn"]) == (False, 0)
    problems = [m.problem for m in _preps(sim, obs)]
    starts = cont.fit_starts(loaded, problems, _preps(sim, obs), obs, 1)
    for j, member in enumerate(src.members):
        for k in ("betaU", "lamUz", "lamWs", "lamWOs"):
            assert np.array_equal(starts[0][j][k], member.draws[k][-1]), k
        assert np.array_equal(starts[0][j]["lamOs"], member.calibration["lamOs"][-1])
    more.save(tmp_path / "m.gpmsa")
    back = gpmsa.load_study(tmp_path / "m.gpmsa")
    assert back.settings["continued_from"] == loaded.sha256
    for j, member in enumerate(back.members):  # each member names its own source, as fit's
        assert member.settings["continued_from"] == loaded.members[j].model_sha256
    assert np.array_equal(back.draws["theta"], more.draws["theta"])


def _preps(sim, obs):
    from gpmsa.model.problem import prepare

    return [prepare(sim, o) for o in obs]


@functools.cache
def _refused_source():
    """The study each refusal below is asked to continue, made once (the refusals only read it)."""
    return _calibrate(60, 1, n_burn=10)


@pytest.mark.parametrize(
    ("change", "match"),
    [
        ({"n_chains": 1}, r"continues its 2 chain\(s\): pass n_chains=2"),
        ({"shared": [], "hierarchical": ["t"]}, r"its shared, hierarchical, calibration param"),
        ({"hyper": gpmsa.HyperPriors.sepia()}, r"hyper: .*no hierarchical group"),  # s70
        ({"fixed": {"lamOs": 400.0}}, r"its fixed values differ"),
        ({"ys": True}, r"its observations differ"),
        ({"labels": ["a", "b", "d"]}, r"its labels"),
        ({"emulators": True}, r"its emulators differ"),
    ],
)
def test_a_continuation_refuses_another_study(change, match):
    src = _refused_source()
    xs, ys = _data()
    if change.pop("ys", False):
        ys = [y + 0.01 for y in ys]
    emus = [emulator()] * 3
    if change.pop("emulators", False):
        emus = [emulator(lam_w=999.0)] + emus[1:]
    args = {"labels": LABELS, "shared": ["t"], "n_samples": 20, "n_chains": 2, **change}
    with pytest.raises(gpmsa.GPMSAError, match=match):
        gpmsa.calibrate_study(emus, xs, ys, init=src, **args)


def test_a_calibration_study_is_not_a_fit_study_s_start():
    src = _calibrate(60, 1, n_burn=10, n_chains=1)
    sims, (xs, ys) = [sim_data()] * 3, _data()
    obs = [gpmsa.ObsData(x=x, y=y) for x, y in zip(xs, ys, strict=True)]
    with pytest.raises(gpmsa.GPMSAError, match="init=study is a calibration study; fit_study"):
        gpmsa.fit_study(sims, obs, labels=LABELS, shared=["t"], n_iter=20, init=src)
