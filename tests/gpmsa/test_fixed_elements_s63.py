"""Fixing single elements of a parameter array (SEPIA's per-element ``SepiaParam.fixed``):
``fit(..., fixed={"lamVz": {1: 1e4}})`` holds those elements and samples the others, on the
numpy and torch backends (pyro: test_pyro_fixed_elements_s64.py); the whole-array form draws
exactly as before; the checks, the file record, ``gpmsa info`` and the continuation check."""

import functools
import warnings

import numpy as np
import pytest
from test_discrepancy_groups_s61 import BASIS, GROUPS, _data

import gpmsa
from gpmsa import GPMSAError
from gpmsa.backends import get as backend_module
from gpmsa.cli.main import main
from gpmsa.mcmc.sampler import ChainState, elements
from gpmsa.model.likelihood import log_likelihood, log_posterior
from gpmsa.model.problem import prepare
from tests._extras import backend_param, needs

HELD = {"lamVz": {1: 1e4}, "betaU": {(1, 0): 0.7}}
RUN = {"tune_rounds": 2, "tune_levels": 3}
TORCH = {"warmup": 10, "tune_stages": 1}  # short: the torch default warms up 3 x 100 sweeps


def _fit(fixed, backend="numpy", **kw):
    data, obs = _data()
    args = {"n_iter": 80, "n_chains": 2, "seed": 5, "n_keep": 160,
            **{"numpy": RUN, "torch": {**RUN, **TORCH}}.get(backend, {}), **kw}  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the toy's short chains are not converged
        return gpmsa.fit(data, obs, discrepancy=BASIS, discrepancy_groups=GROUPS, fixed=fixed,
                         backend=backend, **args)  # fmt: skip


@functools.cache
def _problem():
    data, obs = _data()
    return prepare(data, obs, discrepancy=BASIS, discrepancy_groups=GROUPS).problem


def _theta2():
    """A joint-fit toy with two calibration parameters a in [0, 2], b in [1, 3]."""
    rng = np.random.default_rng(4)
    x, t = rng.uniform(size=(24, 1)), rng.uniform(size=(24, 2)) * 2.0 + [0.0, 1.0]
    y = x + t[:, :1] * 0.5 + t[:, 1:] ** 2 * 0.2
    sim = gpmsa.SimData(x=x, t=t, y=y, t_names=["a", "b"])
    xo = np.array([[0.2], [0.5], [0.8]])
    return sim, gpmsa.ObsData(x=xo, y=xo + 0.5 + 0.2 * 4.0)


def _theta2_fit(fixed, **kw):
    sim, obs = _theta2()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gpmsa.fit(sim, obs, fixed=fixed, **{"n_iter": 60, "seed": 3, "tune": False, **kw})


# --- the whole-array form is unchanged -----------------------------------------------------------
def test_whole_array_fixing_draws_as_before():
    """The draws of a whole-array fix, seed 5, summed per array: the values computed with the
    code before per-element fixing existed (one accepted proposal more or less would move them
    far beyond the tolerance)."""
    emu = _fit({"lamVz": [20.0, 1e4]})
    before = {"betaU": 637.2144072852357, "lamUz": 292.52716304267847,
              "lamWOs": 380395.86810862494, "lamWs": 896610.0069361024}  # fmt: skip
    for k, v in before.items():
        np.testing.assert_allclose(emu.draws[k].sum(), v, rtol=1e-12)
    cal = {"theta": 50.28310916769502, "betaV": 640.4126922110979, "lamOs": 153577.16242460115}
    for k, v in cal.items():
        np.testing.assert_allclose(emu.calibration[k].sum(), v, rtol=1e-12)
    # the log posterior to 1e-10: OpenBLAS's kernel (Sandybridge here) moves it by ~2e-12
    np.testing.assert_allclose(emu.log_post.sum(), 140180.97847410757, rtol=1e-10)
    assert emu.settings["fixed"] == {"lamVz": [20.0, 1e4]}


@pytest.mark.parametrize("backend", ["numpy", backend_param("torch")])
def test_a_dict_of_every_element_is_the_whole_array(backend):
    whole = _fit({"lamVz": [20.0, 1e4], "betaU": 0.5}, backend, n_iter=40, n_chains=1, n_keep=40)
    every = {"lamVz": {1: 1e4, (0,): 20.0},
             "betaU": {(i, j): 0.5 for i in range(2) for j in range(3)}}  # fmt: skip
    each = _fit(every, backend, n_iter=40, n_chains=1, n_keep=40)
    for k in whole.draws:
        np.testing.assert_array_equal(each.draws[k], whole.draws[k])
    for k in whole.calibration:
        np.testing.assert_array_equal(each.calibration[k], whole.calibration[k])
    np.testing.assert_array_equal(each.log_post, whole.log_post)
    assert each.settings["fixed"] == whole.settings["fixed"]


def test_a_theta_dict_by_name_or_position_of_every_element_is_the_whole_vector():
    whole = _theta2_fit({"theta": [0.5, 2.0]})
    for given in ({"b": 2.0, "a": 0.5}, {0: 0.5, "b": 2.0}):
        each = _theta2_fit({"theta": given})
        np.testing.assert_array_equal(each.calibration["theta"], whole.calibration["theta"])
        np.testing.assert_array_equal(each.log_post, whole.log_post)


# --- held elements ------------------------------------------------------------------------------
@pytest.mark.parametrize("backend", ["numpy", backend_param("torch")])
def test_held_elements_stay_at_their_values_while_the_others_move(backend):
    """Every sweep of every (dispersed) chain, tuning skipped for the held elements (widths and
    acceptance NaN there), their starts at the values."""
    prob = _problem().with_fixed(HELD)
    assert prob.fixed == frozenset() and prob.fixed_elements == {
        "lamVz": frozenset({(1,)}), "betaU": frozenset({(1, 0)})}  # fmt: skip
    assert ("lamVz", (1,)) not in elements(prob) and ("lamVz", (0,)) in elements(prob)
    more = TORCH if backend == "torch" else {}
    chains = backend_module(backend).sample(prob, n_iter=60, n_chains=3, seed=2, **RUN, **more)
    lam, beta = chains.draws["lamVz"], chains.draws["betaU"]
    assert np.all(lam[:, :, 1] == 1e4) and np.all(beta[:, :, 1, 0] == 0.7)
    assert np.all(np.ptp(lam[:, :, 0], axis=1) > 0) and np.all(np.ptp(beta[:, :, 0, 0], axis=1) > 0)
    assert np.all(np.ptp(beta[:, :, 1, 1], axis=1) > 0)  # the held one's neighbours move
    for name, idx in (("lamVz", (1,)), ("betaU", (1, 0))):
        assert np.all(np.isnan(chains.step_widths[name][(slice(None), *idx)]))
        assert np.all(np.isnan(chains.accept_rate[name][(slice(None), *idx)]))
    assert np.all(np.isfinite(chains.step_widths["lamVz"][:, 0]))
    starts = chains.info["starts"]
    assert np.all(starts["lamVz"][:, 1] == 1e4) and len(np.unique(starts["lamVz"][:, 0])) == 3


def test_the_log_posterior_leaves_out_the_held_elements_prior():
    """Held elements add nothing (as fixed parameters): the numpy log posterior is the
    log-likelihood plus the free elements' priors."""
    prob = _problem().with_fixed(HELD)
    prm = {k: v.copy() for k, v in prob.init.items()}
    pri = prob.priors
    free = sum(pri.log_prior(k, prm[k]) for k in prob.sampled if k not in ("lamVz", "betaU"))
    free += pri.scalar_log_prior("lamVz", 0)(prm["lamVz"][0])
    free += sum(pri.scalar_log_prior("betaU")(x) for i, x in np.ndenumerate(prm["betaU"])
                if i != (1, 0))  # fmt: skip
    want = log_likelihood(prob, prm) + free
    np.testing.assert_allclose(log_posterior(prob, prm), want, rtol=1e-13)
    state = ChainState(prob, prm, np.random.default_rng(0))
    np.testing.assert_allclose(state.log_post(), want, rtol=1e-13)


@needs("torch")
def test_the_torch_log_posterior_leaves_out_the_held_elements_prior():
    """torch's log posterior with held elements agrees with numpy's (which the test above
    checks against the log-likelihood plus the free elements' priors)."""
    import torch

    from gpmsa.backends.torch_backend import BatchState

    prob = _problem().with_fixed(HELD)
    want = log_posterior(prob, {k: v.copy() for k, v in prob.init.items()})
    torch_lp = BatchState(prob, 1, torch.float64, "cpu").log_post()
    np.testing.assert_allclose(float(torch_lp[0]), want, rtol=1e-10)


def test_a_fit_keeps_held_elements_exactly_and_does_not_judge_their_convergence():
    emu = _fit(HELD)
    assert np.all(emu.calibration["lamVz"][:, 1] == 1e4) and np.ptp(emu.calibration["lamVz"][:, 0])
    assert np.all(emu.draws["betaU"][:, 1, 0] == 0.7) and emu.params["betaU"][1, 0] == 0.7
    assert emu.settings["fixed"] == {"betaU": {"elements": [[1, 0]], "values": [0.7]},
                                     "lamVz": {"elements": [[1]], "values": [1e4]}}  # fmt: skip
    flagged = emu.convergence["flagged"]
    assert "lamVz[1]" not in flagged and "betaU[1,0]" not in flagged and "lamVz[0]" in flagged


def test_one_theta_element_held_by_name():
    emu = _theta2_fit({"theta": {"b": 2.0}})
    theta = emu.calibration["theta"]
    assert np.all(theta[:, 1] == theta[0, 1]) and np.ptp(theta[:, 0]) > 0
    np.testing.assert_allclose(emu.calibration["theta_native"][:, 1], 2.0, rtol=1e-15)
    assert emu.settings["fixed"] == {"theta": {"elements": [[1]], "values": [theta[0, 1]]}}
    same = _theta2_fit({"theta": {1: 2.0}})
    np.testing.assert_array_equal(same.calibration["theta"], theta)


def test_an_int_names_the_row_of_a_one_column_parameter():
    data, _ = _data()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a = gpmsa.fit(data, n_iter=30, seed=1, n_pc=1, tune=False, fixed={"betaU": {1: 0.3}})
        b = gpmsa.fit(data, n_iter=30, seed=1, n_pc=1, tune=False, fixed={"betaU": {(1, 0): 0.3}})
    np.testing.assert_array_equal(a.draws["betaU"], b.draws["betaU"])
    assert np.all(a.draws["betaU"][:, 1, 0] == 0.3) and np.ptp(a.draws["betaU"][:, 0, 0]) > 0


# --- the checks ---------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("fixed", "match"),
    [
        (
            {"lamVz": {2: 1.0}},
            r"fixed\['lamVz'\]: element index 2 is out of range; lamVz takes an "
            r"int in 0..1 \(lamVz has shape \(2,\)\)",
        ),
        ({"lamVz": {-1: 1.0}}, r"element index -1 is out of range; lamVz takes an int in 0..1"),
        (
            {"betaU": {(2, 0): 1.0}},
            r"fixed\['betaU'\]: element index \(2, 0\) is out of range; "
            r"betaU takes a tuple \(i, j\) with i in 0..1 and j in 0..2",
        ),
        (
            {"betaU": {1: 1.0}},
            r"fixed\['betaU'\]: element index 1 must be a tuple \(i, j\) with "
            r"i in 0..1 and j in 0..2 \(betaU has shape \(2, 3\)\): an int names a row only "
            r"where there is one column",
        ),
        ({"betaU": {(1,): 1.0}}, r"element index \(1,\) has 1 entries; betaU takes a tuple"),
        ({"lamVz": {"1": 1.0}}, r"fixed\['lamVz'\]: element index '1' must be an int in 0..1"),
        ({"lamVz": {1.0: 1.0}}, r"element index 1.0 must be an int"),
        ({"lamVz": {True: 1.0}}, r"element index True must be an int"),
        ({"lamVz": {1: np.inf}}, r"fixed\['lamVz'\]\[1\] must be finite, got inf"),
        ({"lamVz": {1: [1.0, 2.0]}}, r"fixed\['lamVz'\]\[1\] must be a single number"),
        (
            {"lamVz": {1: -3.0}},
            r"fixed\['lamVz'\]: element lamVz\[1\] = -3 lies outside its "
            r"prior's bounds \(0, inf\)",
        ),
        (
            {"lamWOs": {0: 1e6}},
            r"element lamWOs\[0\] = 1e\+06 lies outside its prior's bounds "
            r"\(60, 100000\)",
        ),
        (
            {"betaU": {(0, 1): 0.0}},
            r"element betaU\[0,1\] = 0 lies outside its prior's bounds "
            r"\(0, inf\)",
        ),
        (
            {"lamVz": {1: 5.0, (1,): 6.0}},
            r"fixed\['lamVz'\]: the entries 1 and \(1,\) both name "
            r"element lamVz\[1\]",
        ),
        ({"lamVz": {}}, r"fixed\['lamVz'\] is an empty dict"),
        ({"lamFoo": {0: 1.0}}, r"fixed: unknown parameter 'lamFoo'"),
    ],
)
def test_bad_element_fixes_are_refused_naming_parameter_index_and_range(fixed, match):
    with pytest.raises(GPMSAError, match=match):
        _problem().with_fixed(fixed)


def test_bad_theta_elements_are_refused_in_native_units():
    for fixed, match in (
        (
            {"c": 1.0},
            r"unknown calibration parameter 'c'; give a name of \['a', 'b'\] or a "
            r"position 0..1",
        ),
        ({"a": 1.0, 0: 1.2}, r"fixed\['theta'\]: two entries name element 0 \('a' and 0\)"),
        ({"b": 3.5}, r"fixed\['theta'\] b=3.5 lies outside the open range \(1.0\d*, 2.9\d*\)"),
        (
            {2: 1.5},
            r"fixed\['theta'\]: element index 2 is out of range; theta takes an int in "
            r"0..1",
        ),
        ({"a": np.nan}, r"fixed\['theta'\]\[0\] must be finite"),
    ):
        with pytest.raises(GPMSAError, match=match):
            _theta2_fit({"theta": fixed}, n_iter=5)


def test_a_held_theta_element_must_satisfy_the_constraint_at_the_start():
    with pytest.raises(GPMSAError, match="fixed theta"):
        _theta2_fit({"theta": {"b": 2.9}}, n_iter=5, constraint=lambda th: th[1] < 2.5)


def test_a_start_the_constraint_refuses_beside_a_held_element_points_at_theta_init():
    """Held b = 2 with a at the design's centre (about 1.08) breaks a + b < 2.5: theta_init=
    moves a (the advice), and then the fit runs with b held."""
    fixed, below = {"theta": {"b": 2.0}}, lambda th: th[0] + th[1] < 2.5
    with pytest.raises(GPMSAError, match=r"fixed theta \(held elements\): .* pass theta_init="):
        _theta2_fit(fixed, n_iter=5, constraint=below)
    emu = _theta2_fit(fixed, n_iter=5, constraint=below, theta_init={"a": 0.3, "b": 2.0})
    assert np.all(emu.calibration["theta_native"][:, 1] == 2.0)


# --- the file, info and continuing --------------------------------------------------------------
def test_held_elements_round_trip_show_in_info_and_guard_continuation(tmp_path, capsys):
    emu = _fit(HELD, n_iter=40)
    path = emu.save(tmp_path / "held.gpmsa")
    back = gpmsa.load(path)
    assert back.settings["fixed"] == emu.settings["fixed"]
    assert main(["info", str(path)]) == 0
    line = next(s for s in capsys.readouterr().out.splitlines() if s.startswith("fixed:"))
    assert line == ("fixed:           betaU[1,0]=0.7, lamVz[1]=10000.0 (single elements: the "
                    "others sampled)"), line  # fmt: skip
    more = _fit(HELD, n_iter=20, n_burn=0, n_keep=40, init=back)
    assert np.all(more.calibration["lamVz"][:, 1] == 1e4)
    for other in ({"lamVz": {1: 2e4}, "betaU": {(1, 0): 0.7}}, {"lamVz": [20.0, 1e4]}, None):
        with pytest.raises(GPMSAError, match="its fixed parameters differ"):
            _fit(other, n_iter=20, n_keep=40, init=back)


def test_info_prints_a_held_theta_element_native_by_name(tmp_path, capsys):
    emu = _theta2_fit({"theta": {"b": 2.0}})
    assert main(["info", str(emu.save(tmp_path / "t.gpmsa"))]) == 0
    line = next(s for s in capsys.readouterr().out.splitlines() if s.startswith("fixed:"))
    assert line.startswith("fixed:           theta (native)=[b=2]"), line


def test_info_prints_a_record_it_does_not_read_as_it_is():
    """A ``settings["fixed"]`` entry that is not a whole parameter's values nor well-formed held
    elements is printed raw (a file is not trusted; never a crash)."""
    from gpmsa.cli.info import _fixed_cell

    assert _fixed_cell({}, "lamVz", {"elements": [[1]], "values": ["x"]}, None) == (
        'lamVz={"elements": [[1]], "values": ["x"]}')  # fmt: skip
    assert _fixed_cell({}, "lamVz", {"elements": [[True]], "values": [1.0]}, None) == (
        'lamVz={"elements": [[true]], "values": [1.0]}')  # fmt: skip
    assert _fixed_cell({}, "lamVz", [20.0, 1e4], None) == "lamVz=[20.0, 10000.0]"
    theta = {"names": {"t": ["a"]}}  # a position past the names: by position, unit scale
    assert _fixed_cell(theta, "theta", {"elements": [[3]], "values": [0.5]}, None) == "theta[3]=0.5"


def test_a_categorical_theta_element_is_held_only_at_a_level():
    from tests.gpmsa.test_models_cat import _level_case

    sim, x_obs, y_mid = _level_case()
    obs = gpmsa.ObsData(x_obs, y_mid)
    with pytest.raises(GPMSAError, match="fixed theta: categorical calibration parameter"):
        gpmsa.fit(sim, obs, n_iter=5, fixed={"theta": {0: 1.5}})
    each = gpmsa.fit(sim, obs, n_iter=20, seed=0, fixed={"theta": {0: 2}})
    whole = gpmsa.fit(sim, obs, n_iter=20, seed=0, fixed={"theta": [2]})
    assert np.all(each.calibration["theta_native"] == 2.0)
    np.testing.assert_array_equal(each.log_post, whole.log_post)
