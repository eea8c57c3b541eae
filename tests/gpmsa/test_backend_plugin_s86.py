"""A backend of one's own (``gpmsa.backends.register``), as a third party plugs it in: a module of
their project that wraps the numpy sampler runs ``fit``, ``calibrate`` and the Calibrator's MCMC
path; its emulator file loads, is described and continues where the plug-in is not registered;
built-in names, a module without ``sample``, a result that is not the chains asked for, and model
extensions or tempering the plug-in does not declare are refused by name (session 86: before,
registering meant editing the private ``_REGISTRY``, a wrong result was an AttributeError or
KeyError or was recorded as it came, a constraint went to a sampler that may ignore it, and the
Calibrator refused the options a ``**options`` sampler takes)."""

import sys
import types
import warnings

import numpy as np
import pytest
from _backend_cases import installed_plugin, road_data
from _calib_cases import road_emulator, road_obs

import gpmsa
from gpmsa import backends
from gpmsa.backends import numpy_backend
from gpmsa.cli.main import main
from gpmsa.errors import GPMSAError
from gpmsa.mcmc.sampler import Chains

pytestmark = pytest.mark.filterwarnings("ignore::gpmsa.ConvergenceWarning")

PLUGIN = '''
"""A third party's backend: numpy's sampler, its own option ``note`` set aside."""
from gpmsa.backends import numpy_backend

CALLS = []


def sample(problem, *, n_iter, n_chains=1, tune=True, step_widths=None, seed=None,
           progress=False, note=None, **options):
    CALLS.append({"note": note, **options})
    return numpy_backend.sample(problem, n_iter=n_iter, n_chains=n_chains, tune=tune,
                                step_widths=step_widths, seed=seed, progress=progress, **options)
'''
TUNING = {"tune_rounds": 1, "tune_levels": 3}


@pytest.fixture
def registry(monkeypatch):
    """The registry restored after the test (a plug-in registered in it forgotten)."""
    monkeypatch.setattr(backends, "_REGISTRY", dict(backends._REGISTRY))


@pytest.fixture
def plugin(registry, monkeypatch, tmp_path):
    """``mybackend_s86.py`` in the user's project, registered by its import path as "mine"."""
    yield installed_plugin(monkeypatch, tmp_path, "mybackend_s86", PLUGIN)
    sys.modules.pop("mybackend_s86", None)


def _toy(result=None, **attrs) -> types.ModuleType:
    """A plug-in module whose ``sample`` returns ``result(chains)`` of numpy's chains."""
    module = types.ModuleType("toy_backend_s86")

    def sample(problem, *, n_iter, n_chains=1, tune=True, step_widths=None, seed=None,
               progress=False, **options):  # fmt: skip
        chains = numpy_backend.sample(problem, n_iter=n_iter, n_chains=n_chains, tune=tune,
                                      step_widths=step_widths, seed=seed, **options)  # fmt: skip
        return chains if result is None else result(chains)

    module.sample = sample
    vars(module).update(attrs)
    return module


def test_a_plugin_fits_as_the_sampler_it_wraps(plugin):
    sim, _ = road_data()
    emu = gpmsa.fit(sim, n_iter=12, seed=3, backend="mine", note="x", **TUNING)
    twin = gpmsa.fit(sim, n_iter=12, seed=3, **TUNING)
    for k in twin.draws:
        np.testing.assert_array_equal(emu.draws[k], twin.draws[k])
    assert emu.settings["backend"] == "mine"
    assert emu.settings["backend_options"] == {"note": "x", **TUNING}
    assert plugin.CALLS[-1] == {"note": "x", **TUNING}


def test_a_plugin_calibrates_as_the_sampler_it_wraps(plugin):
    emu_c, (x, y) = road_emulator(), road_obs()
    post = gpmsa.calibrate(emu_c, x, y, n_samples=60, n_burn=10, seed=4, backend="mine",
                           **TUNING)  # fmt: skip
    same = gpmsa.calibrate(emu_c, x, y, n_samples=60, n_burn=10, seed=4, fast=False, **TUNING)
    np.testing.assert_array_equal(post.samples["GD"], same.samples["GD"])
    assert post.info["backend"] == "mine" and post.info["engine"] == "backend"
    cal = gpmsa.Calibrator(emu_c, backend="mine", seed=4,
                           mcmc_options={"n_samples": 60, "n_burn": 10, "note": "y"})  # fmt: skip
    assert cal.method == "mcmc"  # before: "unknown keyword(s) ['note']", and 'options' listed
    assert cal.update(x, y).info["backend_options"] == {"note": "y"}


def test_a_file_fitted_by_a_plugin_loads_and_continues_without_it(plugin, tmp_path, capsys):
    sim, _ = road_data()
    emu = gpmsa.fit(sim, n_iter=12, seed=3, backend="mine", **TUNING)
    path = emu.save(tmp_path / "mine.gpmsa")
    del backends._REGISTRY["mine"]  # another machine: the plug-in not there
    loaded = gpmsa.load(path)
    assert loaded.settings["backend"] == "mine" and "mine" not in backends.names()
    np.testing.assert_array_equal(loaded.predict([[1.0]], [[400.0]])[0], emu.predict(
        [[1.0]], [[400.0]])[0])  # fmt: skip
    assert main(["info", str(path)]) == 0
    assert "backend=mine" in capsys.readouterr().out
    more = gpmsa.fit(sim, n_iter=12, seed=5, init=loaded, **TUNING)
    assert more.settings["backend"] == "numpy"
    assert more.settings["continued_from"] == loaded.model_sha256


@pytest.mark.parametrize("name", ["numpy", "torch", "pyro"])
def test_a_built_in_name_is_refused(registry, name):
    with pytest.raises(GPMSAError, match=f"{name!r} is a built-in backend's name"):
        backends.register(name, _toy())
    assert backends._REGISTRY[name][0] == f"gpmsa.backends.{name}_backend"


def test_a_module_without_its_sample_is_refused(registry, monkeypatch):
    for name in ("", "  ", 3, None):
        with pytest.raises(GPMSAError, match="name must be a non-empty string"):
            backends.register(name, _toy())
    with pytest.raises(GPMSAError, match="'none': .* has no callable sample"):
        backends.register("none", types.SimpleNamespace(sample=None))

    def sample(problem, n_iter):
        raise AssertionError("not to be called")

    with pytest.raises(GPMSAError, match=r"its sample takes no \['n_chains', 'tune'"):
        backends.register("few", types.SimpleNamespace(sample=sample))
    monkeypatch.setitem(sys.modules, "empty_backend_s86", types.ModuleType("empty_backend_s86"))
    backends.register("empty", "empty_backend_s86")  # a path: checked when first used
    sim, _ = road_data()
    with pytest.raises(GPMSAError, match="'empty': <module 'empty_backend_s86'> has no callable"):
        gpmsa.fit(sim, n_iter=10, backend="empty")
    backends.register("gone", "no_such_backend_s86")
    with pytest.raises(GPMSAError, match="'gone' is registered but no_such_backend_s86 does not"):
        gpmsa.fit(sim, n_iter=10, backend="gone")


def _fewer(chains: Chains) -> Chains:
    return Chains({k: v[:, 1:] for k, v in chains.draws.items()}, chains.log_post[:, 1:],
                  chains.accept_rate, chains.step_widths, chains.info)  # fmt: skip


def _without_lamwos(chains: Chains) -> Chains:
    draws = {k: v for k, v in chains.draws.items() if k != "lamWOs"}
    return Chains(draws, chains.log_post, chains.accept_rate, chains.step_widths, chains.info)


@pytest.mark.parametrize(
    ("result", "match"),
    [
        (lambda c: (c.draws, c.log_post), "its sample returned a tuple, not a gpmsa.mcmc.sampler"),
        (_fewer, r"n_chains x n_iter = 2 x 12 sweeps .*: log_post has shape \(2, 11\)"),
        (_without_lamwos, r"no draws of \['lamWOs'\]"),
    ],
)
def test_a_wrong_result_is_refused_by_name(registry, result, match):
    """Before: an AttributeError ('tuple' object has no attribute 'check_finite'), a KeyError
    ('lamWOs'), or fewer draws recorded as the settings' n_iter (fewer chains as n_chains)."""
    backends.register("bad", _toy(result))
    sim, obs = road_data()
    with pytest.raises(GPMSAError, match=match):
        gpmsa.fit(sim, n_iter=12, n_chains=2, seed=1, backend="bad", **TUNING)
    if result is not _without_lamwos:  # (calibration's parameters: theta, lamOs, the fixed)
        with pytest.raises(GPMSAError, match=match):
            gpmsa.calibrate(road_emulator(), *road_obs(), n_samples=12, n_burn=1, n_chains=2,
                            seed=1, backend="bad", **TUNING)  # fmt: skip


def test_undeclared_extensions_and_tempering_are_refused_before_sampling(registry):
    calls = []
    backends.register("toy", _toy(lambda c: calls.append(1) or c))
    sim, obs = road_data()
    allowed = {"constraint": lambda t: t[0] > 300.0, "n_iter": 12, "seed": 1, **TUNING}
    with pytest.raises(GPMSAError, match=r"'toy' does not declare support for \['theta constr"):
        gpmsa.fit(sim, obs, backend="toy", **allowed)
    with pytest.raises(GPMSAError, match=r"does not declare support for \['held elements'\]"):
        gpmsa.fit(sim, n_iter=12, backend="toy", fixed={"betaU": {(0, 0): 1.0}})
    with pytest.raises(GPMSAError, match="temperatures: parallel tempering runs on the numpy"):
        gpmsa.fit(sim, n_iter=12, backend="toy", temperatures=[1, 2])
    with pytest.raises(GPMSAError, match="temperatures: parallel tempering runs on the numpy"):
        gpmsa.calibrate(road_emulator(), *road_obs(), backend="toy", temperatures=[1, 2])
    with pytest.raises(GPMSAError, match="'toy' runs its chains in one process: it takes no n_j"):
        gpmsa.fit(sim, n_iter=12, backend="toy", n_chains=2, n_jobs=2)
    assert calls == []
    backends.register("toy", _toy(lambda c: calls.append(1) or c, SUPPORTS=("theta constraint",)))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.AtBoundWarning)
        emu = gpmsa.fit(sim, obs, backend="toy", **allowed)
    assert calls == [1] and emu.settings["constraint"] is True
    assert np.all(emu.calibration["theta_native"] > 300.0)


def test_a_plugin_without_options_refuses_them_by_name(registry):
    def sample(problem, *, n_iter, n_chains=1, tune=True, step_widths=None, seed=None,
               progress=False):  # fmt: skip
        return numpy_backend.sample(problem, n_iter=n_iter, n_chains=n_chains, tune=tune,
                                    step_widths=step_widths, seed=seed)  # fmt: skip

    backends.register("plain", types.SimpleNamespace(sample=sample))
    emu = road_emulator()
    with pytest.raises(GPMSAError, match="backend 'plain' takes no tune_rounds="):
        gpmsa.calibrate(emu, *road_obs(), backend="plain", tune_rounds=2)
    with pytest.raises(GPMSAError, match="backend 'plain' takes no tune_levels="):
        gpmsa.Calibrator(emu, backend="plain", mcmc_options={"tune_levels": 3})
    with pytest.raises(GPMSAError, match=r"unknown keyword\(s\) \['note'\]"):
        gpmsa.Calibrator(emu, backend="plain", mcmc_options={"note": 3})
    with pytest.raises(GPMSAError, match=r"unknown option\(s\) \['note'\] for the 'plain'"):
        gpmsa.fit(road_data()[0], n_iter=12, backend="plain", note=3)
    post = gpmsa.calibrate(emu, *road_obs(), n_samples=20, n_burn=2, seed=1, backend="plain")
    assert post.info["backend"] == "plain"


@pytest.mark.parametrize("key", ["log_prior", "x_obs", "extrapolate", "emulator", "n_iter"])
def test_a_plugins_calibrator_refuses_its_own_keywords_in_mcmc_options(plugin, key):
    """Before: built, then its first update raised "TypeError: sample_calibration() got
    multiple values for keyword argument ...": a ``**options`` sampler let them through."""
    with pytest.raises(GPMSAError, match=rf"mcmc_options: unknown keyword\(s\) \['{key}'\]"):
        gpmsa.Calibrator(road_emulator(), backend="mine", mcmc_options={key: 1})
