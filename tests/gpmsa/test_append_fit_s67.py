"""``gpmsa.fit(..., init=emu, append=True)``: SEPIA's second ``do_mcmc(n)`` and GPM/SA's
``gpmmcmc(pout, n)``, which append the new samples to the old. The returned emulator holds the
source's retained draws followed, chain by chain, by the continuation's, thinned by the source's
step from its last kept draw, so each pooled chain is evenly spaced in sweeps; its point
estimate, diagnostics and convergence are over the pooled chains."""

import functools
import warnings

import numpy as np
import pytest
from _emulator_edit import replaced

import gpmsa
from gpmsa.cli.main import main
from gpmsa.mcmc.diagnostics import _arviz

CHAINS = 2


@functools.cache
def _data():
    rng = np.random.default_rng(1)
    x, t = rng.random((30, 1)), rng.random((30, 1))
    data = gpmsa.SimData(x=x, t=t, y=np.sin(3 * x) + t**2, x_names=["x"], t_names=["t"])
    xo = np.array([[0.2], [0.5], [0.7]])
    obs = gpmsa.ObsData(x=xo, y=np.sin(3 * xo) + 0.16)
    return data, obs


def _fit(joint: bool = True, **kw):
    data, obs = _data()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        return gpmsa.fit(data, obs if joint else None, n_chains=CHAINS, n_jobs=1, **kw)


@functools.cache
def _source(joint: bool = True):
    """60 sweeps a chain, 12 burnt, n_keep=40: thin 3, 16 draws a chain."""
    return _fit(joint, n_iter=60, seed=0, tune_rounds=3, tune_levels=5, n_keep=40)


def _by_chain(v) -> np.ndarray:
    v = np.asarray(v)
    return v.reshape(CHAINS, v.shape[0] // CHAINS, *v.shape[1:])


def _expected(first, every, thin: int) -> np.ndarray:
    """The source's draws, then every thin-th sweep of a continuation that kept every sweep."""
    both = np.concatenate([_by_chain(first), _by_chain(every)[:, thin - 1 :: thin]], axis=1)
    return both.reshape(-1, *np.shape(first)[1:])


@pytest.mark.parametrize("joint", [True, False])
def test_appended_draws_are_the_sources_then_the_continuations_at_its_step(joint):
    src = _source(joint)
    thin = src.settings["thin"]
    assert thin == 3 and src.n_draws == 32
    pooled = _fit(joint, n_iter=40, seed=1, init=src, append=True)
    every = _fit(joint, n_iter=40, seed=1, init=src, n_keep=CHAINS * 40)  # the same chains
    assert every.settings["thin"] == 1
    assert pooled.n_draws == CHAINS * (16 + 40 // thin)
    for k, v in pooled.draws.items():
        np.testing.assert_array_equal(v, _expected(src.draws[k], every.draws[k], thin))
    np.testing.assert_array_equal(pooled.log_post, _expected(src.log_post, every.log_post, thin))
    if joint:  # theta (unit and native) and lamOs, pooled alike
        assert set(pooled.calibration) == {"theta", "theta_native", "lamOs"}
        for k, v in pooled.calibration.items():
            np.testing.assert_array_equal(
                v, _expected(src.calibration[k], every.calibration[k], thin)
            )
    else:
        assert pooled.calibration is None
    s = pooled.settings
    assert (s["n_iter"], s["n_burn"], s["thin"]) == (40, 0, thin)
    assert s["appended_to"] == s["continued_from"] == src.model_sha256
    assert (s["appended_after"], s["pooled_sweeps"], s["sweeps_run"]) == (16, 48 + 40, 60 + 40)
    for k, v in pooled.params.items():  # the point estimate: the pooled draws' mean
        np.testing.assert_allclose(v, pooled.draws[k].mean(axis=0), rtol=1e-12)


def test_pooled_diagnostics_are_arviz_on_the_pooled_chains():
    src = _source()
    pooled = _fit(n_iter=40, seed=1, init=src, append=True)
    az = _arviz()
    idata = pooled.to_arviz()
    assert idata.posterior.sizes["chain"] == CHAINS and idata.posterior.sizes["draw"] == 29
    rhat, ess = az.rhat(idata), az.ess(idata)
    record = pooled.convergence
    assert record["n_chains"] == CHAINS and record["n_draws"] == 29
    for k in ("betaU", "lamUz", "lamWs", "lamWOs", "theta", "lamOs"):
        np.testing.assert_allclose(record["rhat"][k], np.ravel(rhat[k].values), rtol=1e-12)
        np.testing.assert_allclose(record["ess"][k], np.ravel(ess[k].values), rtol=1e-12)
        draws = pooled.draws.get(k, (pooled.calibration or {}).get(k))
        mean = draws.reshape(draws.shape[0], -1).mean(0)
        np.testing.assert_allclose(pooled.diagnostics[k]["mean"], mean, rtol=1e-12)
    every = _fit(n_iter=40, seed=1, init=src, n_keep=CHAINS * 40)
    for k in ("lamUz", "theta"):  # acceptance: both parts', weighted by their sweeps
        both = (np.array(src.diagnostics[k]["accept"]) * 60
                + np.array(every.diagnostics[k]["accept"]) * 40) / 100  # fmt: skip
        np.testing.assert_allclose(pooled.diagnostics[k]["accept"], both, rtol=1e-12)


def test_an_append_repeats_with_its_seed_round_trips_and_appends_again(tmp_path, capsys):
    src = _source()
    one = _fit(n_iter=20, seed=5, init=src, append=True)
    two = _fit(n_iter=20, seed=5, init=src, append=True)
    assert one.model_sha256 == two.model_sha256
    path = one.save(tmp_path / "pooled.gpmsa")
    back = gpmsa.load(path)
    assert back.model_sha256 == one.model_sha256 and back.settings == one.settings
    assert main(["info", str(path)]) == 0
    shown = capsys.readouterr().out
    assert "appended_after=16" in shown and "pooled_sweeps=68" in shown
    assert f"{CHAINS} chains x 22 draws" in shown
    again = _fit(n_iter=30, seed=6, init=back, append=True)  # an appended fit appended to
    s = again.settings
    assert (s["appended_after"], s["pooled_sweeps"], s["sweeps_run"]) == (22, 98, 110)
    for k, v in again.draws.items():
        np.testing.assert_array_equal(_by_chain(v)[:, :22], _by_chain(back.draws[k]))


def test_what_cannot_be_appended_is_refused_naming_the_argument():
    src = _source()
    refused = {
        "pass init=that emulator": {"n_iter": 20, "append": True},
        r"n_burn must be 0 or None, got 5": {"init": src, "n_burn": 5},
        r"pass n_chains=2": {"init": src, "n_chains": 3},
        r"pass tune=False": {"init": src, "tune": True},
        r"x 20 sweeps: pass n_keep=12": {"init": src, "n_keep": 40},
        r"n_iter=2 keeps none; pass n_iter >= 3": {"init": src, "n_iter": 2},
        r"append must be True or False, got 'yes'": {"init": src, "append": "yes"},
    }
    data, obs = _data()
    for message, kw in refused.items():
        args = {"n_iter": 20, "n_chains": CHAINS, "seed": 1, "append": True, **kw}
        with pytest.raises(gpmsa.GPMSAError, match=message):
            gpmsa.fit(data, obs, **args)
    unthinned = replaced(src, settings={k: v for k, v in src.settings.items() if k != "thin"})
    with pytest.raises(gpmsa.GPMSAError, match=r"records none \(settings\['thin'\] = None\)"):
        gpmsa.fit(data, obs, n_iter=20, n_chains=CHAINS, init=unthinned, append=True)
    other = gpmsa.Priors(lamOs=gpmsa.GammaPrior(2.0, 0.001))
    with pytest.raises(gpmsa.GPMSAError, match="its priors differ"):
        gpmsa.fit(data, obs, n_iter=20, n_chains=CHAINS, init=src, append=True, priors=other)
    matched = _fit(n_iter=20, seed=1, init=src, append=True, n_keep=12)  # the step's own count
    assert matched.n_draws == 32 + 12


def test_the_pooled_draws_count_against_the_memory_limit(monkeypatch):
    import gpmsa.fitting.fit as fit_mod

    src = _source()
    seen = []
    real = fit_mod.check_memory
    monkeypatch.setattr(fit_mod, "check_memory", lambda n, what: seen.append(n) or real(n, what))
    _fit(n_iter=3, seed=1, init=src)  # the continuation alone
    monkeypatch.setattr(gpmsa.limits, "MAX_MEMORY_BYTES", seen[-1] + 1)
    _fit(n_iter=3, seed=1, init=src)
    with pytest.raises(gpmsa.ResourceLimitError, match="appending to 34 retained draws"):
        _fit(n_iter=3, seed=1, init=src, append=True)
