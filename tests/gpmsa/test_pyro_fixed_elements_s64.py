"""Held single elements on the pyro backend: ``fit(..., backend="pyro", fixed={"betaU": {(1, 0):
0.5}})`` samples a site of the free elements and scatters them with the held values. The model's
density is the numpy reference's; held elements are exact in every draw and left out of the
diagnostics; the free elements' posterior is the numpy backend's; continuation and the file
record work; fits without held elements draw exactly as before."""

import functools
import warnings

import numpy as np
import pytest

pyro = pytest.importorskip("pyro")
torch = pytest.importorskip("torch")

from test_discrepancy_groups_s61 import BASIS, GROUPS, _data  # noqa: E402

import gpmsa  # noqa: E402
from gpmsa.backends import pyro_backend as pb  # noqa: E402
from gpmsa.model.likelihood import log_posterior  # noqa: E402
from gpmsa.model.problem import prepare  # noqa: E402
from tests.gpmsa.test_backend_agreement import assert_agree  # noqa: E402
from tests.gpmsa.test_fixed_elements_s63 import _problem  # noqa: E402

HELD = {"betaU": {(1, 0): 0.5}}
EMU = {"betaU": [[0.3], [0.6], [0.2]], "lamUz": 0.8, "lamWs": 900.0, "lamWOs": 1000.0}


def _toy():
    """A joint-fit toy: 12 runs of a scalar output, x in [0, 1], a in [0, 2], b in [1, 3]."""
    rng = np.random.default_rng(4)
    x, t = rng.uniform(size=(12, 1)), rng.uniform(size=(12, 2)) * 2.0 + [0.0, 1.0]
    y = x + t[:, :1] * 0.5 + t[:, 1:] ** 2 * 0.2
    sim = gpmsa.SimData(x=x, t=t, y=y, t_names=["a", "b"])
    xo = np.array([[0.2], [0.5], [0.8]])
    return sim, gpmsa.ObsData(x=xo, y=xo + 0.5 + 0.2 * 4.0)


def _fit(*args, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # short chains: convergence warnings
        return gpmsa.fit(*args, **kw)


@functools.cache
def _pyro_held():
    """A simulator-only pyro fit with betaU[1,0] held (2 chains x 120 draws, short trees to
    keep it fast: ESS ~90 each)."""
    sim, _ = _toy()
    return _fit(sim, backend="pyro", fixed=HELD, n_iter=120, n_burn=20, n_warmup=60,
                max_tree_depth=4, n_chains=2, seed=3)  # fmt: skip


# --- (a) no held elements: the draws of the code before ------------------------------------------
def test_fits_without_held_elements_draw_as_before():
    """Sums of the draws of a default simulator-only fit and of a calibration with the emulator
    fixed whole (seed 7, 2 chains x 10 draws), computed with the code before held elements
    were sampled on pyro (one NUTS step more or less would move them far past the tolerance)."""
    sim, obs = _toy()
    short = {"backend": "pyro", "seed": 7, "n_iter": 10, "n_warmup": 10, "n_chains": 2}
    emu = _fit(sim, **short)
    before = {"betaU": 9.919086215693499, "lamUz": 7.398113289549634,
              "lamWs": 18039.95231195273, "lamWOs": 18319.496438958944}  # fmt: skip
    for k, v in before.items():
        np.testing.assert_allclose(emu.draws[k].sum(), v, rtol=1e-12)
    # the log posteriors to 1e-10: OpenBLAS's kernel (Sandybridge here) moves them by ~4e-12
    np.testing.assert_allclose(emu.log_post.sum(), 740.5016769750844, rtol=1e-10)
    np.testing.assert_allclose(emu.settings["step_widths"]["lamWs"],
                               [[0.284700264365863], [0.2574671612237942]], rtol=1e-12)  # fmt: skip
    cal = _fit(sim, obs, fixed=EMU, **short)
    # to 1e-10: torch's MKL kernel (AVX512, AVX2 or SSE4.2 by the host) moves them by up to 2e-12
    for k, v in {"theta": 13.375217259112802, "lamOs": 16910.59187843946}.items():
        np.testing.assert_allclose(cal.calibration[k].sum(), v, rtol=1e-10)
    np.testing.assert_allclose(cal.log_post.sum(), 130.2119734725245, rtol=1e-10)
    assert np.all(np.isnan(cal.settings["step_widths"]["lamWs"]))


# --- the model ----------------------------------------------------------------------------------
def test_model_density_with_held_elements_is_the_numpy_log_posterior():
    """A site of the free elements only; scattered with the held values, the model's density is
    numpy's log posterior (which leaves the held elements' priors out)."""
    prob = _problem().with_fixed({"lamVz": {1: 1e4}, "betaU": {(1, 0): 0.7}})
    model = pb.PyroModel(prob)
    rng = np.random.default_rng(1)
    for _ in range(3):
        params, sites = {}, {}
        for name, val in prob.init.items():
            v = val * rng.uniform(0.7, 1.3, val.shape)
            for idx in prob.fixed_elements.get(name, ()):
                v[idx] = val[idx]
            params[name] = np.clip(v, 0.05, 0.95) if name == "theta" else v
        for name in model.free:
            v = params[name]
            if name in model.held:
                v = v.reshape(-1)[model.held[name][0].numpy()]
            rho = name in ("betaU", "betaV")
            sites[f"{name}_rho" if rho else name] = torch.as_tensor(np.exp(-v / 4) if rho else v)
        assert sites["betaU_rho"].shape == (5,) and sites["lamVz"].shape == (1,)
        trace = pyro.poutine.trace(pyro.poutine.condition(model, data=sites)).get_trace()
        np.testing.assert_allclose(
            float(trace.log_prob_sum()), log_posterior(prob, params), rtol=1e-9, atol=1e-7
        )
        full = model.params({k: v.unsqueeze(0) for k, v in sites.items()})
        assert float(full["betaU"][0, 1, 0]) == 0.7 and float(full["lamVz"][0, 1]) == 1e4


def test_a_free_lamvz_site_takes_its_own_groups_bounds():
    """Per-group lamVz priors: the free group's site is bounded by its own prior only, so a
    held group may have an infinite upper bound beside a free group's finite one (which the
    whole parameter's site refuses)."""
    data, obs = _data()
    pri = gpmsa.Priors(lamVz=[gpmsa.GammaPrior(1.0, 1e-3, 0.0, 50.0),
                              gpmsa.GammaPrior(1.0, 1e-3, 10.0)])  # fmt: skip
    prob = prepare(data, obs, discrepancy=BASIS, discrepancy_groups=GROUPS, priors=pri).problem
    with pytest.raises(gpmsa.GPMSAError, match="mix finite and infinite ones"):
        pb.PyroModel(prob)
    support = pb.PyroModel(prob.with_fixed({"lamVz": {1: 1e4}})).support["lamVz"]
    assert (support.lower_bound, support.upper_bound) == (0.0, 50.0)


# --- (b) held elements exact, diagnostics leave them out ----------------------------------------
def test_held_element_is_exact_in_every_draw_and_left_out_of_the_diagnostics():
    emu = _pyro_held()
    assert np.all(emu.draws["betaU"][:, 1, 0] == 0.5)
    assert np.unique(emu.draws["betaU"][:, 0, 0]).size > 50  # the free ones move
    assert emu.settings["fixed"] == {"betaU": {"elements": [[1, 0]], "values": [0.5]}}
    widths = np.array(emu.settings["step_widths"]["betaU"])
    assert np.all(np.isnan(widths[:, 1, 0])) and np.all(widths[:, [0, 2], 0] > 0)
    diag = emu.diagnostics["betaU"]
    assert np.isnan(diag["accept"][1]) and np.isnan(diag["rhat"][1]) and diag["sd"][1] == 0.0
    assert not np.isnan(diag["accept"][0])
    conv = emu.convergence
    assert "betaU[1,0]" not in conv["flagged"] and conv["max_rhat"][0] != "betaU[1,0]"
    assert np.isfinite(conv["max_rhat"][1]) and conv["max_rhat"][1] < 1.1


# --- (c) the free elements' posterior is numpy's ------------------------------------------------
def test_free_elements_posterior_agrees_with_numpy():
    """betaU[1,0] held at 0.5 on both backends; the other betaU, lamUz, lamWs, lamWOs agree in
    mean and sd within 4 Monte-Carlo standard errors."""
    sim, _ = _toy()
    got = _pyro_held()
    ref = _fit(sim, fixed=HELD, n_iter=5000, n_chains=2, seed=4, n_keep=10_000)
    assert np.all(ref.draws["betaU"][:, 1, 0] == 0.5)
    n_a, n_b = got.settings["n_chains"], ref.settings["n_chains"]
    for name in ("betaU", "lamUz", "lamWs", "lamWOs"):
        a = got.draws[name].reshape(n_a, -1, got.draws[name][0].size)
        b = ref.draws[name].reshape(n_b, -1, ref.draws[name][0].size)
        for k in range(a.shape[2]):
            if name == "betaU" and k == 1:
                continue
            assert_agree(a[:, :, k], b[:, :, k], f"{name}[{k}]")


def test_a_held_theta_element_by_name_calibrates_as_numpy():
    """A calibration (emulator fixed whole) with theta's b held by name at 2.0: b is exact, a and
    lamOs agree with the numpy backend's."""
    sim, obs = _toy()
    fixed = {**EMU, "theta": {"b": 2.0}}
    got = _fit(sim, obs, fixed=fixed, backend="pyro", n_iter=200, n_warmup=100,
               max_tree_depth=4, n_chains=2, seed=5)  # fmt: skip
    ref = _fit(sim, obs, fixed=fixed, n_iter=5000, n_chains=2, seed=6, n_keep=10_000)
    assert np.all(got.calibration["theta_native"][:, 1] == 2.0)
    assert got.settings["fixed"]["theta"] == ref.settings["fixed"]["theta"]
    for name, k in (("theta", 0), ("lamOs", 0)):
        a, b = got.calibration[name][:, k], ref.calibration[name][:, k]
        assert_agree(a.reshape(2, -1), b.reshape(2, -1), f"{name}[{k}]")
    assert "theta[1]" not in got.convergence["flagged"]


# --- (d) continuation, (e) the file record ------------------------------------------------------
def test_a_pyro_fit_with_held_elements_round_trips_and_continues(tmp_path):
    emu = _pyro_held()
    back = gpmsa.load(emu.save(tmp_path / "held.gpmsa"))
    assert back.settings["fixed"] == emu.settings["fixed"]
    np.testing.assert_array_equal(back.draws["betaU"], emu.draws["betaU"])
    sim, _ = _toy()
    more = _fit(sim, backend="pyro", fixed=HELD, n_iter=10, n_warmup=10, n_chains=2, seed=8,
                init=back)  # fmt: skip
    assert more.settings["continued_from"] == back.model_sha256
    assert np.all(more.draws["betaU"][:, 1, 0] == 0.5)
    with pytest.raises(gpmsa.GPMSAError, match="its fixed parameters differ"):
        _fit(sim, backend="pyro", fixed={"betaU": {(1, 0): 0.6}}, n_iter=10, n_chains=2,
             init=back)  # fmt: skip
