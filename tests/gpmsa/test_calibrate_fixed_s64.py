"""``calibrate(..., fixed=)``, ``calibrate_study(..., fixed=)`` and ``fit_study(..., fixed=)``:
calibration parameters held at known values (SEPIA's ``SepiaParam.fixed``), as ``gpmsa.fit``'s
``fixed=`` holds them: a known theta element (``{"theta": {"E": 2.1}}``), a known observation
precision (``{"lamOs": 1.0}``), a discrepancy group switched off (``{"lamVz": {1: 1e6}}``).

Before: none of the three took ``fixed=``. Without it every draw is as before, bit for bit
(pinned below from the code before the change)."""

import functools
import warnings

import numpy as np
import pytest
from test_discrepancy_groups_s61 import BASIS, GROUPS, _data, _emulator

import gpmsa
from gpmsa import GPMSAError
from gpmsa.calibration.observations import fixed_gp, reduce
from gpmsa.calibration.sampler import CalibrationSampler
from tests._extras import PYRO, backend_param
from tests.gpmsa._calib_cases import (
    categorical_emulator,
    road_emulator,
    road_obs,
    two_param_emulator,
    vector_emulator,
)

RUN = {"n_samples": 60, "n_burn": 10, "tune_rounds": 3, "tune_levels": 4}
XO, YO = [[0.3], [0.7]], [[0.9], [1.2]]


def _calibrate(emu, *args, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # short toy chains: not converged
        return gpmsa.calibrate(emu, *args, **{**RUN, **kw})


def _study_sim():
    t = np.linspace(0.1, 0.9, 12)[:, None]
    x = np.tile([[0.0], [1.0]], (6, 1))
    return gpmsa.SimData(x=x, t=t, y=(x + 2 * t), t_names=["E"])


def _study_emulator():
    prm = {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [1e4], "lamWOs": [1e4]}
    return gpmsa.Emulator.from_params(_study_sim(), prm)


def _cal_study(**kw):
    emu = _study_emulator()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gpmsa.calibrate_study([emu, emu], [[[0.5]], [[0.2]]], [[1.5], [1.2]],
                                     **{"shared": ["E"], "seed": 1, **RUN, **kw})  # fmt: skip


def _fit_study(**kw):
    sim = _study_sim()
    obs = [gpmsa.ObsData(x=[[0.5]], y=[[1.5]]), gpmsa.ObsData(x=[[0.2]], y=[[1.2]])]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        run = {"shared": ["E"], "n_iter": 60, "seed": 2, "tune_rounds": 3, "tune_levels": 4}
        return gpmsa.fit_study([sim, sim], obs, **{**run, **kw})


# --- without fixed=: the draws as before, bit for bit ---------------------------------------------
PINNED = {
    "road_fast": {"GD": (21182.981039264436, 430.23197869614364),
                  "lamOs": (27672.127297756382, 649.9026022947629)},
    "two_fast": {"a": (23.3707711833349, 0.2260115910905389),
                 "b": (39.02031176850356, 0.47763459254287777),
                 "lamOs": (27604.70658884323, 98.37706541202883)},
    "two_generic": {"a": (11.902723787689075, 0.2390998923728764),
                    "b": (19.45988847059652, 0.4043662433133585),
                    "lamOs": (40255.94713034367, 377.9975668543882)},
    "vec_disc": {"betaV": (0.8892587103404477, 0.00798427467236458),
                 "lamOs": (9424.06255710246, 5.5883592316356605),
                 "lamVz": (3728.5420741799576, 107.1849087871575),
                 "t": (4.816056135500444, 0.04860914549618545)},
    "two_torch": {"a": (11.900437531908707, 0.2359942797159444),
                  "b": (19.534067734322218, 0.3977294980847253),
                  "lamOs": (123570.17215548182, 337.5821027375291)},
    "cal_study": {"E": (24.96836495424457, 0.5506123857038336),
                  "lamOs[model0]": (22638.362078458926, 905.6806671329254),
                  "lamOs[model1]": (24590.636710722953, 70.73330810406148)},
    "fit_study": {"E": (23.798621377177234, 0.5393477493132769),
                  "lamOs[model0]": (21765.163728640226, 520.0182933315374),
                  "lamOs[model1]": (84329.93082044201, 690.9493581011933)},
}  # fmt: skip
"""(sum, last draw) of each posterior's draws, from the code before calibrate took fixed=."""


def _pinned_runs(**fx):
    x, y = road_obs()
    two = two_param_emulator()
    yv = np.linspace(0.5, 1.2, 8)[None, :]
    return {
        "road_fast": lambda: _calibrate(road_emulator(), x, y, seed=1, **fx),
        "two_fast": lambda: _calibrate(two, XO, YO, seed=2, n_chains=2, **fx),
        "two_generic": lambda: _calibrate(two, XO, YO, seed=3, fast=False, **fx),
        "vec_disc": lambda: _calibrate(vector_emulator(), [[0.4]], yv, seed=4,
                                       discrepancy="constant", **fx),
        "two_torch": lambda: _calibrate(two, XO, YO, seed=5, backend="torch", **fx),
        "cal_study": lambda: _cal_study(**fx).posterior,
        "fit_study": lambda: _fit_study(**fx).posterior,
    }  # fmt: skip


@pytest.mark.parametrize("case", [backend_param(case, backend="torch" if "torch" in case else None)
                                  for case in sorted(PINNED)])  # fmt: skip
def test_default_draws_are_those_before_fixed_existed(case):
    post = _pinned_runs()[case]()
    for name, (total, last) in PINNED[case].items():
        np.testing.assert_allclose(post.samples[name].sum(), total, rtol=1e-12)
        np.testing.assert_allclose(post.samples[name][-1], last, rtol=1e-12)
    again = _pinned_runs(fixed=None)[case]()  # fixed=None: the same path
    for name in PINNED[case]:
        np.testing.assert_array_equal(again.samples[name], post.samples[name])
    assert "fixed" not in post.info


def test_an_empty_fixed_dict_draws_as_none():
    a = _calibrate(two_param_emulator(), XO, YO, seed=2)
    b = _calibrate(two_param_emulator(), XO, YO, seed=2, fixed={})
    for name in a.names:
        np.testing.assert_array_equal(a.samples[name], b.samples[name])
    assert b.info["fixed"] == {}


# --- a held theta element: exactly its value, the others sampled ----------------------------------
ENGINES = [{}, {"fast": False}, backend_param({"backend": "torch"}, backend="torch")]


@pytest.mark.parametrize("engine", ENGINES, ids=["fast", "numpy", "torch"])
@pytest.mark.parametrize("given", [{"a": 0.4}, {0: 0.4}])
def test_a_held_theta_element_is_its_value_in_every_draw(engine, given):
    post = _calibrate(two_param_emulator(), XO, YO, seed=1, n_chains=2, fixed={"theta": given},
                      **engine)  # fmt: skip
    assert np.all(post.samples["a"] == 0.4) and np.all(post.chains["a"] == 0.4)
    assert post.mean("a") == 0.4 and post.sd("a") == 0.0
    assert post.quantile("a", 0.9) == 0.4
    assert post.sd("b") > 0.01 and post.sd("lamOs") > 0  # the others sampled
    std = two_param_emulator().standardizer
    unit = (0.4 - std.t_min[0]) / (std.t_max[0] - std.t_min[0])
    assert post.info["fixed"] == {"theta": {"elements": [[0]], "values": [pytest.approx(unit)]}}
    # a held element is not judged for convergence (constant draws are not "stuck")
    assert "a" not in post.info["convergence"]["flagged"]


PYRO_ENGINE = backend_param({"backend": "pyro"}, backend="pyro")


@pytest.mark.parametrize("engine", ENGINES + [PYRO_ENGINE],
                         ids=["fast", "numpy", "torch", "pyro"])  # fmt: skip
def test_the_whole_theta_and_lamos_held(engine):
    run = {**RUN, **engine}
    if engine.get("backend") == "pyro":  # NUTS: no GPM/SA tuning
        run = {"n_samples": 40, "n_burn": 10, "n_warmup": 60, "max_tree_depth": 4, **engine}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        post = gpmsa.calibrate(two_param_emulator(), XO, YO, seed=1, **run,
                               fixed={"theta": {"a": 0.4, "b": 0.6}})  # fmt: skip
        lam = gpmsa.calibrate(two_param_emulator(), XO, YO, seed=1, **run, fixed={"lamOs": 50.0})
    assert np.all(post.samples["a"] == 0.4) and np.all(post.samples["b"] == 0.6)
    assert post.sd("lamOs") > 0
    assert len(post.info["fixed"]["theta"]) == 2  # named every element: held whole
    assert np.all(lam.samples["lamOs"] == 50.0) and lam.sd("a") > 0
    assert lam.info["fixed"] == {"lamOs": [50.0]}


@PYRO
def test_pyro_holds_a_single_theta_element():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        post = gpmsa.calibrate(two_param_emulator(), XO, YO, n_samples=40, n_burn=10, seed=1,
                               backend="pyro", n_warmup=20,
                               fixed={"theta": {"a": 0.4}})  # fmt: skip
    assert np.all(post.samples["a"] == 0.4) and post.sd("a") == 0.0 and post.sd("b") > 0
    fast = gpmsa.calibrate(two_param_emulator(), XO, YO, n_samples=40, n_burn=10, seed=1,
                           fixed={"theta": {"a": 0.4}})  # fmt: skip
    assert post.info["fixed"] == fast.info["fixed"]  # {"theta": {"elements": [[0]], ...}}
    assert post.info["fixed"]["theta"]["elements"] == [[0]]


# --- correctness: the conditional posterior, against a grid ---------------------------------------
A0, B0 = 0.4, 0.6
X3 = np.array([[0.2], [0.5], [0.8]])
Y3 = np.sin(2 * X3 + 1.5 * A0) + 0.8 * B0 * X3 + np.array([[0.01], [-0.02], [0.015]])


def _grid_parts():
    """The calibration's log posterior pieces (the fast sampler's own terms) on unit theta."""
    emu = two_param_emulator()
    s = CalibrationSampler([fixed_gp(emu, emu.params)], reduce(emu, X3, Y3, False), emu.priors)
    std = emu.standardizer
    return s, np.asarray(std.t_min), np.asarray(std.t_max)


def _moments(axis_unit, logp, lo, hi):
    w = np.exp(logp - logp.max())
    w /= np.trapezoid(w, axis_unit)
    native = lo + axis_unit * (hi - lo)
    mean = np.trapezoid(w * native, axis_unit)
    return mean, np.sqrt(np.trapezoid(w * (native - mean) ** 2, axis_unit))


def _whitened(s, theta):
    """The fast sampler's whitened (e, y2) (``ThetaPredictive.at``) at many unit thetas (G, 2)
    at once: log p(u | theta, lamOs) = -0.5 sum(log(e + 1/lamOs) + y2 / (e + 1/lamOs))."""
    pred = s.preds[0]
    mean, cov = pred._dense(theta)  # (G, d), (G, d, d)
    lw = np.linalg.solve(pred.L, np.eye(pred.d))  # L^-1 of the 3 x 3 observation factor
    e, vecs = np.linalg.eigh(lw @ cov @ lw.T)
    y = np.einsum("gji,gj->gi", vecs, (pred.z - mean) @ lw.T)
    return np.maximum(e, 0.0), y * y


def _loglik_grid(e, y2, lam):
    v = e[..., None] + 1.0 / np.asarray(lam)
    return -0.5 * np.sum(np.log(v) + y2[..., None] / v, axis=-2)


@functools.cache
def _b_given_a():
    """Mean and sd of b given a = A0, lamOs integrated out on a log grid: the posterior of b in a
    calibration where a is truly known."""
    s, lo, hi = _grid_parts()
    au = (A0 - lo[0]) / (hi[0] - lo[0])
    bu = np.linspace(0, 1, 401)[1:-1]
    lam = np.exp(np.linspace(np.log(1e-2), np.log(1e6), 600))
    lp_lam = np.array([s._log_prior_lamos(v) for v in lam]) + np.log(lam)  # d lamOs = lam d log
    e, y2 = _whitened(s, np.column_stack([np.full(bu.size, au), bu]))
    lp = _loglik_grid(e, y2, lam) + lp_lam  # (b, lamOs)
    lp = np.log(np.trapezoid(np.exp(lp - lp.max()), np.log(lam), axis=1))
    lp += [s._log_prior_theta([au, b]) for b in bu]
    return _moments(bu, lp, lo[1], hi[1])


@functools.cache
def _theta_grid():
    """The parts of `_a_given_lamos` that do not depend on lamOs (1 s), made once: the unit
    axis, the whitened (e, y2) and theta's log prior on its 399 x 399 grid."""
    s, _, _ = _grid_parts()
    g = np.linspace(0, 1, 401)[1:-1]
    aa, bb = np.meshgrid(g, g, indexing="ij")
    e, y2 = _whitened(s, np.column_stack([aa.ravel(), bb.ravel()]))
    prior = np.array([[s._log_prior_theta([a, b]) for b in g] for a in g])
    return g, e, y2, prior


@functools.cache
def _a_given_lamos(lam):
    """Mean and sd of a with lamOs = ``lam`` known, b integrated out on the grid."""
    _, lo, hi = _grid_parts()
    g, e, y2, prior = _theta_grid()
    lp = _loglik_grid(e, y2, [lam])[:, 0].reshape(g.size, g.size)
    lp += prior
    with np.errstate(divide="ignore"):  # far tails: zero mass
        marginal = np.log(np.trapezoid(np.exp(lp - lp.max()), g, axis=1))
    return _moments(g, marginal, lo[0], hi[0])


@pytest.mark.parametrize("engine", [{}, {"fast": False}], ids=["fast", "numpy"])
def test_a_held_element_gives_the_posterior_of_the_others_with_it_known(engine):
    mean, sd = _b_given_a()  # 0.6084, 0.0326; a free: b 0.619 +- 0.051
    post = gpmsa.calibrate(two_param_emulator(), X3, Y3, n_samples=10_000, n_burn=1000, seed=3,
                           fixed={"theta": {"a": A0}}, **engine)  # fmt: skip
    assert abs(post.mean("b") - mean) < 0.1 * sd
    assert abs(post.sd("b") / sd - 1) < 0.1


@pytest.mark.parametrize("engine", [{}, {"fast": False}], ids=["fast", "numpy"])
def test_a_held_lamos_gives_the_posterior_with_it_known(engine):
    free = gpmsa.calibrate(two_param_emulator(), X3, Y3, n_samples=2000, n_burn=500, seed=4,
                           **engine)  # fmt: skip
    sds = {}
    for lam in (5.0, 1000.0):  # the free lamOs posterior's median is ~130
        mean, sd = _a_given_lamos(lam)
        post = gpmsa.calibrate(two_param_emulator(), X3, Y3, n_samples=8000, n_burn=1000,
                               seed=3, fixed={"lamOs": lam}, **engine)  # fmt: skip
        assert np.all(post.samples["lamOs"] == lam)
        assert abs(post.mean("a") - mean) < 0.1 * sd
        assert abs(post.sd("a") / sd - 1) < 0.1
        sds[lam] = post.sd("a")
    # a smaller observation precision widens theta's posterior, a larger one narrows it
    assert sds[1000.0] < 0.8 * free.sd("a") < free.sd("a") < 0.8 * sds[5.0]


# --- discrepancy parameters, by element -----------------------------------------------------------
@pytest.mark.parametrize("backend", ["numpy", backend_param("torch")])
def test_one_discrepancy_group_switched_off(backend):
    data, obs = _data()
    warmup = {"warmup": 10} if backend == "torch" else {}  # 100 a tuning stage: 2/3 of the time
    post = _calibrate(_emulator(), obs, seed=2, backend=backend, discrepancy=BASIS,
                      discrepancy_groups=GROUPS, fixed={"lamVz": {1: 1e6}}, **warmup)  # fmt: skip
    assert np.all(post.samples["lamVz[1]"] == 1e6)
    assert post.sd("lamVz[0]") > 0 and post.sd("betaV[0,1]") > 0
    assert post.info["fixed"] == {"lamVz": {"elements": [[1]], "values": [1e6]}}
    beta = _calibrate(_emulator(), obs, seed=2, backend=backend, discrepancy=BASIS,
                      discrepancy_groups=GROUPS, fixed={"betaV": {(0, 1): 0.5}},
                      **warmup)  # fmt: skip
    assert np.all(beta.samples["betaV[0,1]"] == 0.5) and beta.sd("betaV[0,0]") > 0


# --- what calibrate refuses, and how it says so ---------------------------------------------------
@pytest.mark.parametrize(
    ("fixed", "kw", "match"),
    [
        ({"betaU": 1.0}, {}, r"betaU is an emulator parameter, which calibrate does not sample.*"
                             r"gpmsa.fit\(\.\.\., fixed="),
        ({"lamWOs": 1e4}, {}, "lamWOs is an emulator parameter"),
        ({"lamVz": 1e6}, {}, "lamVz is a discrepancy parameter and this calibration has no "
                             "discrepancy: give discrepancy="),
        ({"betaV": {0: 1.0}}, {}, "betaV is a discrepancy parameter"),
        ({"a": 0.4}, {}, r"unknown parameter 'a' \('a' is a calibration parameter: "
                         r"fixed=\{'theta': \{'a': v\}\}\); calibrate holds \['theta', 'lamOs'\]"),
        ({"lamUs": 1.0}, {}, r"unknown parameter 'lamUs'; calibrate holds"),
        ([("lamOs", 1.0)], {}, "fixed must be None or a dict"),
        ({"theta": {"c": 0.4}}, {}, r"unknown calibration parameter 'c'; give a name of \['a', "
                                    r"'b'\] or a position 0..1"),
        ({"theta": {2: 0.4}}, {}, r"fixed\['theta'\]: element index 2 is out of range"),
        ({"theta": {"a": 0.4, 0: 0.5}}, {}, "two entries name element 0"),
        ({"theta": {"a": 5.0}}, {}, r"fixed\['theta'\] a=5 lies outside the open range"),
        ({"theta": {"a": np.nan}}, {}, "must be finite"),
        ({"theta": [0.4]}, {}, r"fixed\['theta'\] must have 2 values"),
        ({"lamOs": -1.0}, {}, r"fixed\['lamOs'\] = \[-1.\] lies outside its prior's bounds"),
        ({"lamOs": [1.0, 2.0]}, {}, r"fixed\['lamOs'\] must be a scalar or have shape \(1,\)"),
        ({"lamOs": {1: 2.0}}, {}, r"fixed\['lamOs'\]: element index 1 is out of range"),
        ({"lamOs": 1.0}, {"fast": False}, None),
        ({"lamOs": -1.0}, {"fast": False}, r"lies outside its prior's bounds"),
        ({"theta": {"a": 0.3}}, {"constraint": lambda t: t[0] > 0.5},
         r"^fixed theta \(held elements\): the theta constraint rejects"),
    ],
)  # fmt: skip
def test_bad_fixed_values_are_refused_by_name(fixed, kw, match):
    if match is None:
        _calibrate(two_param_emulator(), XO, YO, fixed=fixed, **kw)
        return
    with pytest.raises(GPMSAError, match=match):
        _calibrate(two_param_emulator(), XO, YO, fixed=fixed, **kw)


def test_emulator_draws_and_log_prior_still_take_the_fast_sampler():
    from tests.gpmsa._calib_cases import with_draws

    emu = with_draws(two_param_emulator())
    post = _calibrate(emu, XO, YO, seed=1, emulator_params="draws", fixed={"theta": {"b": 0.6}},
                      log_prior=lambda t: -((t[:, 0] - 0.3) ** 2))  # fmt: skip
    assert post.info["engine"] == "fast" and np.all(post.samples["b"] == 0.6)
    assert post.sd("a") > 0


# --- studies --------------------------------------------------------------------------------------
def test_calibrate_study_holds_a_shared_element_and_a_models_lamos():
    study = _cal_study(fixed={"theta": {"E": 0.5}}, n_chains=2)
    assert np.all(study.posterior.samples["E"] == 0.5) and study.posterior.sd("E") == 0.0
    assert study.posterior.sd("lamOs[model0]") > 0
    assert study.settings["fixed"] == {"model0": {"theta": [0.5]}, "model1": {"theta": [0.5]}}
    assert study.settings["held"] == ["E"] and "E" not in study.convergence["flagged"]
    per = _cal_study(fixed=[{"lamOs": 30.0}, None], shared=[])
    assert np.all(per.posterior.samples["lamOs[model0]"] == 30.0)
    assert per.posterior.sd("lamOs[model1]") > 0 and per.posterior.sd("E[model0]") > 0
    assert np.all(per.member_posterior("model0").samples["lamOs"] == 30.0)
    own = _cal_study(fixed=[{"theta": {"E": 0.5}}, None], shared=[])
    assert np.all(own.posterior.samples["E[model0]"] == 0.5) and own.posterior.sd("E[model1]") > 0


def test_a_study_refuses_a_shared_element_held_by_some_models_or_at_two_values():
    with pytest.raises(GPMSAError, match=r"E is shared, held by some of its models but not by "
                       r"\['model1'\]"):  # fmt: skip
        _cal_study(fixed=[{"theta": {"E": 0.5}}, None])
    with pytest.raises(GPMSAError, match="the models sharing E hold it at different values"):
        _cal_study(fixed=[{"theta": {"E": 0.5}}, {"theta": {"E": 0.6}}])
    with pytest.raises(GPMSAError, match="fixed has 3 entries for 2 models"):
        _cal_study(fixed=[None, None, None])
    with pytest.raises(GPMSAError, match=r"model 'model1': fixed\['betaU'\]: betaU is an "
                       "emulator parameter"):  # fmt: skip
        _cal_study(fixed=[None, {"betaU": 1.0}])


def test_fit_study_holds_emulator_and_calibration_parameters(tmp_path):
    study = _fit_study(fixed={"lamWOs": 1e4, "lamOs": 20.0, "betaU": {(0, 0): 0.5}}, n_chains=2)
    for emu in study.members:
        assert np.all(emu.draws["lamWOs"] == 1e4) and emu.params["lamWOs"][0] == 1e4
        assert np.all(emu.draws["betaU"][:, 0, 0] == 0.5) and np.ptp(emu.draws["betaU"][:, 1]) > 0
        assert np.all(emu.calibration["lamOs"] == 20.0)
        assert emu.settings["fixed"] == {"betaU": {"elements": [[0, 0]], "values": [0.5]},
                                         "lamOs": [20.0], "lamWOs": [1e4]}  # fmt: skip
    assert np.all(study.posterior.samples["lamOs[model1]"] == 20.0)
    assert "lamOs[model0]" in study.settings["held"]
    study.save(tmp_path / "s.gpmsa")
    back = gpmsa.load_study(tmp_path / "s.gpmsa")
    assert back.settings["fixed"] == study.settings["fixed"]
    assert back.members[0].settings["fixed"] == study.members[0].settings["fixed"]
    held = _fit_study(fixed={"theta": {"E": 0.5}})
    assert np.all(held.posterior.samples["E"] == 0.5)
    assert np.all(held.members[1].calibration["theta_native"] == 0.5)


# --- Posterior summaries of a held parameter ------------------------------------------------------
def test_summaries_of_equal_draws_are_their_value():
    post = gpmsa.Posterior({"E": np.full(4000, 2.1), "k": np.linspace(0, 1, 4000)})
    assert post.mean("E") == 2.1 and post.sd("E") == 0.0  # np.mean: 2.100000000000001
    assert post.mean("k") == np.mean(np.linspace(0, 1, 4000))


def test_a_categorical_theta_held_at_a_level_by_the_fast_sampler():
    emu = categorical_emulator()
    x_obs = np.linspace(0.1, 0.9, 5)[:, None]
    post = _calibrate(emu, x_obs, x_obs[:, 0] - 0.7, seed=1, fixed={"theta": {"t0": 1}})
    assert np.all(post.samples["t0"] == 1.0) and post.info["fixed"] == {"theta": [0.5]}
    with pytest.raises(GPMSAError, match="categorical calibration parameter t0 must be one of"):
        _calibrate(emu, x_obs, x_obs[:, 0], fixed={"theta": {"t0": 1.5}})


def test_a_calibrator_holds_fixed_on_mcmc_and_refuses_it_on_the_grid():
    emu = two_param_emulator()
    with pytest.raises(GPMSAError, match=r"mcmc_options\['fixed'\].*exact grid.*method='mcmc'"):
        gpmsa.Calibrator(emu, mcmc_options={"fixed": {"theta": {"a": 0.4}}})
    cal = gpmsa.Calibrator(emu, method="mcmc", seed=2,
                           mcmc_options={"fixed": {"theta": {"a": 0.4}}, **RUN})  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        post = cal.update(XO, YO)
    assert np.all(post.samples["a"] == 0.4) and post.sd("b") > 0
