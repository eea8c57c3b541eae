"""Continuing a fit's chains (``gpmsa.fit(..., init=emulator)``) and explicit starts (``init`` as
a dict name -> (n_chains, *shape)) on every backend."""

import functools
import warnings

import numpy as np
import pytest
from _continue_cases import continue_data

import gpmsa
from gpmsa import backends
from gpmsa.fitting.fit import continued_starts
from gpmsa.model.problem import prepare


def _data():
    return continue_data(0)


@functools.cache
def _fit(joint: bool):
    data, obs = _data()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        return gpmsa.fit(data, obs if joint else None, n_iter=120, seed=0, n_chains=3, tune=False)


@pytest.mark.parametrize("joint", [False, True])
def test_continued_starts_are_each_chains_last_kept_draw(joint):
    data, obs = _data()
    emu = _fit(joint)
    prep = prepare(data, obs if joint else None)
    got = continued_starts(emu, prep.problem, prep.K, obs if joint else None, 3)
    per = emu.log_post.size // 3
    assert set(got) == set(prep.problem.init)
    for name, val in got.items():
        cal = emu.calibration or {}
        source = cal if name in cal else emu.draws
        np.testing.assert_array_equal(val, np.asarray(source[name])[[per - 1, 2 * per - 1, -1]])


@pytest.mark.parametrize("backend", ["numpy", "torch", "pyro"])
def test_given_starts_start_every_backends_chains(backend):
    if backend != "numpy":
        pytest.importorskip(backend)
    data, _ = _data()
    problem = prepare(data).problem
    given = {"lamUz": np.array([[0.8], [3.0]]), "betaU": np.full((2, 2, 1), 0.7)}
    kw = {"n_warmup": 3, "tune": True} if backend == "pyro" else {"tune": False}  # NUTS adapts
    chains = backends.get(backend).sample(problem, n_iter=4, n_chains=2, seed=0, init=given, **kw)
    assert chains.info["init"] == "given"
    np.testing.assert_allclose(chains.info["starts"]["lamUz"], given["lamUz"], rtol=1e-6)
    np.testing.assert_allclose(chains.info["starts"]["lamWs"][0], problem.init["lamWs"])


def test_fit_continues_and_records_it():
    data, _ = _data()
    emu = _fit(False)
    more = gpmsa.fit(data, n_iter=60, seed=1, n_chains=3, tune=False, init=emu)
    assert more.settings["init"] == "given"
    assert more.settings["continued_from"] == emu.model_sha256
    assert more.settings["n_burn"] == 0 and more.log_post.size == 3 * 60  # past burn-in already


@pytest.mark.parametrize(
    ("change", "match"),
    [
        ({"n_chains": 2}, r"continues its 3 chain\(s\): pass n_chains=3"),
        ({"obs": None}, "is a joint fit: pass its observations"),
        ({"n_pc": 1, "y": "vector"}, "other simulation runs"),
    ],
)
def test_continuing_refuses_another_setup(change, match):
    data, obs = _data()
    emu = _fit(True)
    kw = {"n_iter": 10, "seed": 0, "n_chains": change.get("n_chains", 3), "tune": False}
    if change.get("y") == "vector":
        data = gpmsa.SimData(x=data.x, t=data.t, y=np.hstack([data.y, 2 * data.y]),
                             x_names=["x"], t_names=["t"])  # fmt: skip
        obs = gpmsa.ObsData(x=obs.x, y=np.hstack([obs.y, 2 * obs.y]))
    with pytest.raises(gpmsa.GPMSAError, match=match):
        gpmsa.fit(data, change.get("obs", obs), init=emu, **kw)


def test_a_start_outside_the_prior_or_of_the_wrong_shape_is_refused():
    data, _ = _data()
    problem = prepare(data).problem
    sample = backends.get("numpy").sample
    with pytest.raises(gpmsa.GPMSAError, match=r"init\['lamUz'\] must have shape \(2, 1\)"):
        sample(problem, n_iter=2, n_chains=2, init={"lamUz": [1.0, 2.0]})
    with pytest.raises(gpmsa.GPMSAError, match="lamUz .* outside the bounds"):
        sample(problem, n_iter=2, n_chains=2, init={"lamUz": [[0.1], [1.0]]})
    with pytest.raises(gpmsa.GPMSAError, match="unknown parameter"):
        sample(problem, n_iter=2, n_chains=2, init={"theta": [[0.5], [0.5]]})
    with pytest.raises(gpmsa.GPMSAError, match="from_params"):
        emu = gpmsa.Emulator.from_params(data, _fit(False).params)
        gpmsa.fit(data, n_iter=10, n_chains=1, init=emu)


def test_the_convergence_warning_points_at_continuing():
    data, _ = _data()
    with pytest.warns(gpmsa.ConvergenceWarning, match=r"init=the returned emulator"):
        gpmsa.fit(data, n_iter=30, seed=0, n_chains=2, tune=False)


@pytest.mark.parametrize(
    ("first", "then", "what"),
    [
        ({"mean_basis": "linear"}, {}, "mean_basis"),
        ({"fixed": {"lamWOs": 5e4}}, {}, "fixed parameters"),
        ({}, {"priors": gpmsa.Priors(lamUz=gpmsa.GammaPrior(5.0, 4.0, 0.3))}, "priors"),
    ],
)
def test_continuing_another_model_is_refused(first, then, what):
    """A continuation of another model (walkthrough) ran as one, burn-in 0 and all."""
    data, _ = _data()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = gpmsa.fit(data, n_iter=20, seed=0, n_chains=2, tune=False, **first)
    with pytest.raises(gpmsa.GPMSAError, match=f"another model: its {what} differ"):
        gpmsa.fit(data, n_iter=10, seed=0, n_chains=2, tune=False, init=emu, **then)
