"""Parallel tempering in studies (session 73: ``calibrate_study``/``fit_study(...,
temperatures=)``, ``gpmsa.studies.sampler``, ``gpmsa.mcmc.tempering.run_ladder``).

Two models share t in [0, 1], their emulators in effect the simulators (a negligible nugget),
their observation precisions known (lamOs held at 1): model "a" observes y = 10 (t - 0.5)^2
four times near 0.9 (modes t ~ 0.2 and 0.8, a barrier of ~70 in log-likelihood between them),
model "b" observes y = t once, loosely (0.75, sd 0.45): it tilts the weights, P(t > 0.5) = 0.678
on an exact grid. Plain chains end each in one mode; with the ladder (1, 4, 16, 64) each chain
visits both, and the pooled weight matches the grid's (docs/internals.md, "Parallel tempering").
"""

import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.errors import GPMSAError
from gpmsa.studies.sampler import StudyState

LADDER = [1.0, 4.0, 16.0, 64.0]
PARAMS = {"betaU": [[0.5]], "lamUz": [1.0], "lamWs": [1e6], "lamWOs": [1e6]}
SD_A, SD_B = 0.15, 0.45
Y_A = 0.9 + SD_A * np.array([[0.3], [-0.5], [0.8], [-0.2]])
Y_B = np.array([[0.75]])
T = np.linspace(0.0, 1.0, 25)[:, None]


def _models():
    a = gpmsa.Emulator.from_params(gpmsa.SimData(t=T, y=10 * (T - 0.5) ** 2, t_names=["t"]),
                                   PARAMS)  # fmt: skip
    b = gpmsa.Emulator.from_params(gpmsa.SimData(t=T, y=T.copy(), t_names=["t"]), PARAMS)
    obs = [gpmsa.ObsData(y=Y_A, precision=SD_A**-2), gpmsa.ObsData(y=Y_B, precision=SD_B**-2)]
    return [a, b], obs


def _study(**kw):
    emus, obs = _models()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # unconverged plain chains; the emulators' tiny sds
        return gpmsa.calibrate_study(emus, obs, shared=["t"], fixed={"lamOs": 1.0},
                                     labels=["a", "b"], **{"n_jobs": 1, **kw})  # fmt: skip


def _grid_upper() -> float:
    """P(t > 0.5) from the models' normal likelihoods and the prior Normal(0.5, 10)."""
    e = np.linspace(0.0, 1.0, 200_001)
    lp = -0.5 * ((Y_A - 10 * (e - 0.5) ** 2) ** 2).sum(0) / SD_A**2
    lp -= 0.5 * ((Y_B - e) ** 2).sum(0) / SD_B**2
    lp -= 0.5 * ((e - 0.5) / 10) ** 2
    w = np.exp(lp - lp.max())
    return float(w[e > 0.5].sum() / w.sum())


def test_tempered_study_finds_both_modes_with_their_weights():
    plain = _study(n_samples=600, n_burn=100, n_chains=2, seed=3, tune_rounds=5)
    up = (plain.draws["theta"][..., 0] > 0.5).mean(axis=1)
    assert set(up.tolist()) == {0.0, 1.0}  # each plain chain in one mode (here one each)
    study = _study(n_samples=1000, n_burn=100, n_chains=4, seed=3, tune_rounds=5,
                   temperatures=LADDER)  # fmt: skip
    up = (study.draws["theta"][..., 0] > 0.5).mean(axis=1)
    assert np.all((up > 0.4) & (up < 0.95)), up  # each tempered chain visits both
    # the pooled weight's sd over seeds is ~0.04 here (0.05 for 2 x 1,100 draws, 10 seeds)
    assert abs(up.mean() - _grid_upper()) < 0.1, (up.mean(), _grid_upper())  # 0.678
    rates = np.array(study.settings["swap_rate"])
    assert rates.shape == (4, 3) and np.all((rates > 0.2) & (rates < 1))


def test_seeded_placement_free_recorded_and_plain_untouched(tmp_path, capsys):
    from gpmsa.cli.main import main

    kw = {"n_samples": 40, "n_burn": 5, "n_chains": 2, "seed": 5, "tune_rounds": 2,
          "tune_levels": 4}  # fmt: skip
    a = _study(temperatures=3, swap_every=2, **kw)
    b = _study(temperatures=3, swap_every=2, **{**kw, "n_jobs": 2})
    for k, v in a.draws.items():
        np.testing.assert_array_equal(b.draws[k], v)
    s = a.settings
    assert s["temperatures"] == [1.0, 2.0, 4.0] and s["swap_every"] == 2
    assert np.array(s["swap_rate"]).shape == (2, 2)
    path = a.save(tmp_path / "t.gpmsastudy")
    back = gpmsa.load_study(path)
    assert back.settings["swap_rate"] == s["swap_rate"]
    assert back.settings["temperatures"] == s["temperatures"]
    assert main(["info", str(path)]) == 0
    assert (
        "tempering:       3 temperatures [1, 2, 4], a swap round every 2" in capsys.readouterr().out
    )
    plain = _study(**kw)
    assert "temperatures" not in plain.settings and "swap_rate" not in plain.settings
    assert not np.array_equal(plain.draws["theta"], a.draws["theta"])
    more = _study(n_samples=10, n_chains=2, seed=6, init=a, tune_rounds=1, tune_levels=2)
    assert more.settings["temperatures"] == [1.0, 2.0, 4.0]  # continued tempered (s74)
    assert more.settings["swap_every"] == 2 and more.settings["continued_from"]


def test_hierarchical_and_fit_study_tempered():
    t = np.linspace(0.1, 0.9, 12)[:, None]
    x = np.tile([[0.0], [1.0]], (6, 1))
    sim = gpmsa.SimData(x=x, t=t, y=(x + 2 * t), t_names=["E"])
    prm = {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [1e4], "lamWOs": [1e4]}
    emu = gpmsa.Emulator.from_params(sim, prm)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        hier = gpmsa.calibrate_study([emu] * 3, [[[0.5]], [[0.2]], [[0.7]]],
                                     [[1.5], [1.2], [1.1]], hierarchical=["E"], n_samples=60,
                                     n_burn=10, seed=2, tune_rounds=3, temperatures=2)  # fmt: skip
        obs = [gpmsa.ObsData(x=[[0.5]], y=[[1.5]]), gpmsa.ObsData(x=[[0.2]], y=[[1.2]])]
        fitted = gpmsa.fit_study([sim, sim], obs, shared=["E"], n_iter=40, seed=2,
                                 tune_rounds=2, tune_levels=3, temperatures=(1, 3))  # fmt: skip
    assert np.all(np.isfinite(hier.draws["mu"])) and np.all(hier.draws["lam"] > 0)
    assert np.array(hier.settings["swap_rate"]).shape == (1, 1)
    assert fitted.settings["temperatures"] == [1.0, 3.0]
    for member in fitted.members:
        assert member.settings["temperatures"] == [1.0, 3.0]
        assert member.settings["swap_rate"] == fitted.settings["swap_rate"]


def test_exchange_swaps_whole_study_states():
    """Two copies exchange study elements, groups and each model's likelihood state; each
    copy's models stay consistent with its study elements."""
    from gpmsa.studies import sampler

    study = _study(n_samples=5, n_burn=0, seed=1, tune=False)
    problems = [sampler_problem(study, i) for i in range(2)]
    rng = np.random.default_rng(0)
    start = [dict(p.init) for p in problems]
    empty = np.empty(0)
    a = StudyState(problems, study.layout, study.hyper, start, np.array([0.2]), empty, empty, rng)
    b = StudyState(problems, study.layout, study.hyper, start, np.array([0.5]), empty, empty, rng)
    b.beta = 0.25
    assert [s.beta for s in b.states] == [0.25, 0.25]
    la, lb = a.loglik, b.loglik
    assert lb < la - 50  # t = 0.5 lies between the modes
    acc = np.zeros(1)
    sampler.tempering.swap([a, b], (1.0, 0.25), np.array([np.exp(0.75 * (lb - la)) * 1.01]), acc)
    assert acc[0] == 0 and a.g[0] == 0.2
    sampler.tempering.swap([a, b], (1.0, 0.25), np.array([np.exp(0.75 * (lb - la)) * 0.99]), acc)
    assert acc[0] == 1 and a.g[0] == 0.5 and b.g[0] == 0.2 and a.loglik == lb and b.loglik == la
    for st in (a, b):
        assert all(s.lik.params["theta"][0] == st.g[0] for s in st.states)
    assert a.beta == 1.0 and b.beta == 0.25


def sampler_problem(study, i):
    """Model ``i``'s calibration problem as ``calibrate_study`` builds it (lamOs held)."""
    from gpmsa.calibration.calibrate import calibration_fixed, calibration_problem

    emus, obs = _models()
    held = calibration_fixed(emus[i], {"lamOs": 1.0}, None)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ReductionWarning)  # the loose precision of "b"
        return calibration_problem(emus[i], obs[i], None, fixed=held)


@pytest.mark.parametrize(
    ("kw", "words"),
    [({"temperatures": 0}, "temperatures"), ({"temperatures": [2.0, 4.0]}, "exactly 1"),
     ({"swap_every": 3}, "swap_every=3 needs temperatures"),
     ({"temperatures": 2, "swap_every": 50}, "swap_every=50 exceeds n_samples=20")],
)  # fmt: skip
def test_refused_by_name(kw, words):
    with pytest.raises(GPMSAError, match=words):
        _study(n_samples=20, n_burn=2, seed=1, **kw)


def test_continuation_refused():
    src = _study(n_samples=10, n_burn=0, seed=1, tune=False)
    with pytest.raises(GPMSAError, match="tune=False with a tempered continuation"):
        _study(n_samples=10, seed=2, init=src, temperatures=2, tune=False)
    sims = [gpmsa.SimData(t=T, y=10 * (T - 0.5) ** 2, t_names=["t"])] * 2
    obs = [gpmsa.ObsData(y=Y_A)] * 2
    with pytest.raises(GPMSAError, match="swap_every=9 exceeds n_iter=5"):
        gpmsa.fit_study(sims, obs, shared=["t"], n_iter=5, temperatures=2, swap_every=9)
