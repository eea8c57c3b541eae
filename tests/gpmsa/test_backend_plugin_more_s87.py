"""A backend of one's own, finished (session 87): a Calibrator on a plug-in refuses, when built,
an extension the plug-in does not declare (before: only at its first update, after the
observations had come); ``gpmsa.backends.unregister`` removes a plug-in; a fit on a plug-in
records its module's identity and version beside the built-ins' packages, and a plug-in whose
metadata is broken still fits, saves, loads and is described."""

import sys
import types

import numpy as np
import pytest
from _backend_cases import installed_plugin, road_data
from _calib_cases import categorical_emulator, road_emulator, road_obs, two_param_emulator

import gpmsa
from gpmsa import backends
from gpmsa._version import library_versions
from gpmsa.backends import numpy_backend
from gpmsa.cli.main import main
from gpmsa.errors import GPMSAError
from gpmsa.fitting.emulator import Emulator

pytestmark = pytest.mark.filterwarnings("ignore::gpmsa.ConvergenceWarning")

TUNING = {"tune_rounds": 1, "tune_levels": 3}
UNDECLARED = r"backend 'toy' does not declare support for \['{}'\] \(its module's SUPPORTS"


@pytest.fixture
def registry(monkeypatch):
    """The registry restored after the test (a plug-in registered in it forgotten)."""
    monkeypatch.setattr(backends, "_REGISTRY", dict(backends._REGISTRY))


def _toy(calls: list | None = None, **attrs) -> types.ModuleType:
    """A plug-in module whose ``sample`` is numpy's (each call appended to ``calls``)."""
    module = types.ModuleType("toy_backend_s87")

    def sample(problem, *, n_iter, n_chains=1, tune=True, step_widths=None, seed=None,
               progress=False, **options):  # fmt: skip
        if calls is not None:
            calls.append(problem.extensions)
        return numpy_backend.sample(problem, n_iter=n_iter, n_chains=n_chains, tune=tune,
                                    step_widths=step_widths, seed=seed, **options)  # fmt: skip

    module.sample = sample
    vars(module).update(attrs)
    return module


def _mean_basis_emulator() -> Emulator:
    rng = np.random.default_rng(0)
    x, t = rng.random(16), rng.random(16)
    sim = gpmsa.SimData(x[:, None], t[:, None], (x + t)[:, None], x_names=["x"], t_names=["t"])
    return Emulator.from_params(sim, {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [1e3],
                                      "lamWOs": [1e3]}, mean_basis="linear")  # fmt: skip


def _over_300(t) -> bool:
    return t[0] > 300.0


CASES = {  # extension -> (emulator, Calibrator arguments)
    "theta constraint": (road_emulator, {"constraint": _over_300}),
    "categorical inputs": (categorical_emulator, {}),
    "mean_basis": (_mean_basis_emulator, {}),
    "held elements": (two_param_emulator, {"mcmc_options": {"fixed": {"theta": {"a": 0.5}}}}),
}


@pytest.mark.parametrize("extension", CASES)
@pytest.mark.parametrize("how", ["backend", "mcmc_options"])
def test_a_plugins_calibrator_refuses_an_undeclared_extension_when_built(registry, extension,
                                                                         how):  # fmt: skip
    """Before: built, then refused at the first update (the observations reduced first)."""
    backends.register("toy", _toy())
    make, kwargs = CASES[extension]
    kwargs = {**kwargs, "mcmc_options": dict(kwargs.get("mcmc_options", {}))}
    if how == "backend":
        kwargs["backend"] = "toy"
    else:
        kwargs["mcmc_options"]["backend"] = "toy"
    with pytest.raises(GPMSAError, match=UNDECLARED.format(extension)):
        gpmsa.Calibrator(make(), method="mcmc", **kwargs)
    for method in ("auto", "mcmc"):  # declared: built, "auto" choosing MCMC on a plug-in
        backends.register("toy", _toy(SUPPORTS=(extension,)))
        assert gpmsa.Calibrator(make(), method=method, **kwargs).method == "mcmc"


def test_a_calibrator_refused_when_built_updates_once_its_plugin_declares(registry):
    """Refused before any observation; declared, its update samples with the constraint;
    theta held whole (a dict naming every element) is no held element, as in the update's
    problem."""
    calls = []
    backends.register("toy", _toy(calls))
    options = {"n_samples": 40, "n_burn": 5, **TUNING}
    with pytest.raises(GPMSAError, match=UNDECLARED.format("theta constraint")):
        gpmsa.Calibrator(road_emulator(), backend="toy", constraint=_over_300,
                         mcmc_options=options)  # fmt: skip
    backends.register("toy", _toy(calls, SUPPORTS=("theta constraint",)))
    cal = gpmsa.Calibrator(road_emulator(), backend="toy", seed=2, constraint=_over_300,
                           mcmc_options=options)  # fmt: skip
    post = cal.update(*road_obs())
    assert calls == [("theta constraint",)]
    assert np.all(post.samples["GD"] > 300.0)
    whole = {"fixed": {"theta": {"a": 0.5, "b": 0.5}}}
    assert gpmsa.Calibrator(two_param_emulator(), backend="toy", mcmc_options=whole).method == (
        "mcmc")  # fmt: skip


def test_unregister_removes_a_plugin_and_refuses_others(registry):
    backends.register("toy", _toy())
    gpmsa.backends.unregister("toy")
    assert "toy" not in backends.names()
    with pytest.raises(GPMSAError, match="unknown backend 'toy'"):
        gpmsa.fit(road_data()[0], n_iter=12, backend="toy")
    for name in ("numpy", "torch", "pyro"):
        with pytest.raises(GPMSAError, match=f"unregister: {name!r} is a built-in backend"):
            backends.unregister(name)
        assert name in backends.names()
    for name in ("toy", "", 3):
        with pytest.raises(GPMSAError, match=rf"unregister: no plug-in {name!r} is registered"):
            backends.unregister(name)
    assert "unregister" in backends.__all__


PLUGIN = '''
"""A third party's backend with a version: numpy's sampler."""
from gpmsa.backends import numpy_backend

__version__ = "2.5.1"


def sample(problem, *, n_iter, n_chains=1, tune=True, step_widths=None, seed=None,
           progress=False, **options):
    return numpy_backend.sample(problem, n_iter=n_iter, n_chains=n_chains, tune=tune,
                                step_widths=step_widths, seed=seed, progress=progress, **options)
'''


@pytest.fixture
def plugin(registry, monkeypatch, tmp_path):
    """``mybackend_s87.py`` (``__version__`` 2.5.1) in the user's project, registered as "mine"."""
    yield installed_plugin(monkeypatch, tmp_path, "mybackend_s87", PLUGIN)
    sys.modules.pop("mybackend_s87", None)


def test_a_fit_on_a_plugin_records_its_version_in_the_file(plugin, tmp_path, capsys):
    emu = gpmsa.fit(road_data()[0], n_iter=12, seed=3, backend="mine", **TUNING)
    assert emu.settings["versions"]["backend mine"] == "mybackend_s87 2.5.1"
    assert emu.settings["versions"]["numpy"] == np.__version__
    path = emu.save(tmp_path / "mine.gpmsa")
    backends.unregister("mine")  # another machine: the plug-in not there
    assert gpmsa.load(path).settings["versions"] == emu.settings["versions"]
    assert main(["info", str(path)]) == 0
    assert "backend mine mybackend_s87 2.5.1" in capsys.readouterr().out


def test_a_plugins_version_falls_back_to_its_distribution_then_unknown(monkeypatch, request):
    from importlib import metadata

    from gpmsa._version import _distributions

    request.addfinalizer(_distributions.cache_clear)  # (the map is kept a process)

    np_module = types.ModuleType("numpy.fake_backend_s87")  # numpy's distribution provides it
    assert library_versions("dist", np_module)["backend dist"] == (
        f"numpy.fake_backend_s87 {metadata.version('numpy')}")  # fmt: skip
    monkeypatch.setattr(metadata, "packages_distributions", lambda: {"numpy": ["numpy-x"]})
    monkeypatch.setattr(metadata, "version", lambda dist: {"numpy-x": "9.1"}[dist])
    _distributions.cache_clear()
    assert library_versions("dist", np_module)["backend dist"] == (
        "numpy.fake_backend_s87 9.1 (numpy-x)")  # fmt: skip
    bare = types.SimpleNamespace(sample=_toy().sample)  # no name, no version
    assert library_versions("bare", bare)["backend bare"] == "unknown"
    assert not any(k.startswith("backend") for k in library_versions("numpy"))


class _Unprintable:
    def __str__(self) -> str:
        raise RuntimeError("no version")


def _raising_getattr(name: str):
    if name == "__version__":
        raise RuntimeError("broken metadata")
    raise AttributeError(name)


@pytest.mark.parametrize(
    ("attrs", "record"),
    [({"__version__": _Unprintable()}, "toy_backend_s87 unknown"),
     ({"__getattr__": _raising_getattr}, "toy_backend_s87 unknown"),
     ({"__version__": "1." + "9" * 1000}, "toy_backend_s87 1." + "9" * 182)],
    ids=["unprintable", "raising", "long"],
)  # fmt: skip
def test_a_plugins_broken_metadata_never_fails_a_fit(registry, tmp_path, capsys, attrs, record):
    backends.register("odd", _toy(**attrs))
    emu = gpmsa.fit(road_data()[0], n_iter=12, seed=3, backend="odd", **TUNING)
    assert emu.settings["versions"]["backend odd"] == record  # (200 characters at most)
    assert emu.settings["versions"]["gpmsa"] == gpmsa.__version__
    path = emu.save(tmp_path / "odd.gpmsa")
    assert gpmsa.load(path).settings["versions"] == emu.settings["versions"]
    assert main(["info", str(path)]) == 0
    capsys.readouterr()


def test_a_plugin_of_no_installed_package_rebuilds_the_distribution_map_once(monkeypatch):
    from importlib import metadata

    from gpmsa import _version

    builds = []
    monkeypatch.setattr(metadata, "packages_distributions", lambda: builds.append(1) or {})
    monkeypatch.setattr(_version, "_NO_DISTRIBUTION", set())
    _version._distributions.cache_clear()
    try:
        local = types.ModuleType("my_local_backend_s87")  # a file beside the user's script
        for _ in range(3):
            assert library_versions("local", local)["backend local"] == (
                "my_local_backend_s87 unknown")  # fmt: skip
        assert len(builds) == 2  # the first build, and one more in case it was installed since
    finally:
        _version._distributions.cache_clear()
