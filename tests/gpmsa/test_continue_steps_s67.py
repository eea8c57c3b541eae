"""A continuation proposes the precisions as its source's chains did (SEPIA: after
``tune_step_sizes`` every later ``do_mcmc`` steps them uniformly with the tuned widths; untuned,
GPM/SA's proportional step, which ignores the width). Shown with recorded precision widths
made tiny: a uniform step of width 1e-9 leaves a precision within 1e-9 x sweeps of its start,
a proportional step (width max(1, x/3)) moves it by O(1)."""

import functools

import numpy as np
import pytest
from _continue_cases import continue_data as _data
from _continue_cases import continue_fit as _fit
from _emulator_edit import replaced

import gpmsa

PRECISIONS = ("lamUz", "lamWs", "lamWOs", "lamOs")
BACKENDS = [
    "numpy",
    pytest.param("torch", marks=pytest.mark.skipif(
        not __import__("importlib").util.find_spec("torch"), reason="torch not installed")),
]  # fmt: skip


@functools.cache
def _source(backend: str, tune: bool):
    warm = {"warmup": 5} if backend == "torch" and tune else {}
    return _fit(n_iter=30, tune=tune, tune_rounds=2, tune_levels=5, backend=backend, **warm)


def _tiny(emu, drop_key: bool = False):
    """``emu`` with its precisions' recorded widths 1e-9 (and, ``drop_key``, its settings as a
    file written before ``proportional_steps`` was recorded)."""
    settings = dict(emu.settings)
    widths = dict(settings["step_widths"])
    for name in PRECISIONS:
        widths[name] = (np.array(widths[name], dtype=float) * 0 + 1e-9).tolist()
    settings["step_widths"] = widths
    if drop_key:
        settings.pop("proportional_steps")
    return replaced(emu, settings=settings)


def _moved(emu, name: str) -> float:
    """The largest spread of ``name``'s kept draws within one chain."""
    draws = emu.calibration[name] if name == "lamOs" else emu.draws[name]
    per_chain = draws.reshape(2, -1, *draws.shape[1:])
    return float(np.max(per_chain.max(axis=1) - per_chain.min(axis=1)))


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("drop_key", [False, True])
def test_a_tuned_fit_continues_with_uniform_steps_of_its_recorded_widths(backend, drop_key):
    source = _source(backend, True)
    assert source.settings["proportional_steps"] is False
    more = _fit(n_iter=20, init=_tiny(source, drop_key), backend=backend)
    assert more.settings["tune"] is False
    assert more.settings["proportional_steps"] is False
    for name in PRECISIONS:  # 20 uniform steps of width 1e-9 at most
        assert _moved(more, name) < 1e-7, name


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("drop_key", [False, True])
def test_an_untuned_fit_continues_with_gpmsa_proportional_steps(backend, drop_key):
    source = _source(backend, False)
    assert source.settings["proportional_steps"] is True
    more = _fit(n_iter=20, init=_tiny(source, drop_key), backend=backend)
    assert more.settings["proportional_steps"] is True
    assert _moved(more, "lamUz") > 1e-3  # the width is ignored


@pytest.mark.parametrize("backend", BACKENDS)
def test_the_choice_given_wins_and_retuning_steps_uniformly(backend):
    source = _tiny(_source(backend, True))
    told = _fit(n_iter=20, init=source, backend=backend, proportional_steps=True)
    assert told.settings["proportional_steps"] is True
    assert _moved(told, "lamUz") > 1e-3
    warm = {"warmup": 5} if backend == "torch" else {}
    retuned = _fit(n_iter=20, init=source, backend=backend, tune=True, tune_rounds=2, **warm)
    assert retuned.settings["proportional_steps"] is False


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("tune", [False, True])
def test_a_fresh_sample_by_default_is_the_one_of_proportional_steps_not_tune(backend, tune):
    data, obs = _data()
    problem = gpmsa.prepare(data, obs).problem
    module = gpmsa.backends.get(backend)
    kw = {"n_iter": 15, "n_chains": 2, "seed": 3, "tune": tune, "tune_rounds": 1, "tune_levels": 5}
    if backend == "torch":
        kw["warmup"] = 3  # torch's warm-up sweeps step as its sampling sweeps do
    default = module.sample(problem, **kw)
    explicit = module.sample(problem, proportional_steps=not tune, **kw)
    assert default.info["proportional_steps"] is (not tune)
    for name, draws in default.draws.items():
        np.testing.assert_array_equal(draws, explicit.draws[name])
    other = module.sample(problem, proportional_steps=tune, **kw)
    assert not np.array_equal(other.draws["lamUz"], default.draws["lamUz"])


def test_pyro_takes_no_proportional_steps():
    pytest.importorskip("pyro")
    data, _ = _data()
    with pytest.raises(gpmsa.GPMSAError, match=r"unknown option\(s\) \['proportional_steps'\]"):
        gpmsa.fit(data, n_iter=8, backend="pyro", proportional_steps=False)


def test_a_bad_choice_is_named_given_or_recorded():
    data, obs = _data()
    problem = gpmsa.prepare(data, obs).problem
    with pytest.raises(gpmsa.GPMSAError, match=r"proportional_steps must be None \(not tune\), "
                       r"True or False, got 'no'"):  # fmt: skip
        gpmsa.backends.get("numpy").sample(problem, n_iter=3, proportional_steps="no")
    source = _source("numpy", True)
    damaged = replaced(source, settings={**source.settings, "proportional_steps": "no"})
    with pytest.raises(gpmsa.GPMSAError, match=r"settings\['proportional_steps'\] must be true"):
        _fit(n_iter=5, init=damaged)
