"""A continuation (``gpmsa.fit(..., init=emu)``) runs on with the step widths its chains were
tuned to, as SEPIA's second ``do_mcmc``, instead of tuning again; recorded per-chain widths can
be passed back as ``step_widths``."""

import functools
import warnings

import numpy as np
import pytest
from _continue_cases import continue_data as _data
from _continue_cases import continue_fit as _fit
from _emulator_edit import replaced

import gpmsa

WARMUP = {"numpy": {}, "torch": {"warmup": 10}}
"""torch's warm-up before each of its 3 tuning stages: 10 sweeps, not 100 (3 s of the test's 5
on torch); the widths it tunes are what these tests pass on, whatever they are."""


@functools.cache
def _tuned(backend: str = "numpy"):
    return _fit(n_iter=60, tune_rounds=3, backend=backend, **WARMUP[backend])


@pytest.mark.parametrize("backend", ["numpy", "torch"])
def test_a_continuation_keeps_its_chains_tuned_widths_without_tuning(backend):
    if backend == "torch":
        pytest.importorskip("torch")
    first = _tuned(backend)
    recorded = first.settings["step_widths"]
    more = _fit(n_iter=40, init=first, backend=backend)
    assert more.settings["tune"] is False
    for name, w in more.settings["step_widths"].items():  # the tuned widths, per chain, as used
        np.testing.assert_array_equal(np.array(w, dtype=float), np.array(recorded[name], float))
    told = _fit(n_iter=40, init=first, backend=backend, tune=False, step_widths=recorded)
    for name, draws in more.draws.items():
        np.testing.assert_array_equal(draws, told.draws[name])
    retuned = _fit(n_iter=40, init=first, backend=backend, tune=True, tune_rounds=2,
                   **WARMUP[backend])  # fmt: skip
    assert retuned.settings["tune"] is True
    assert not np.array_equal(retuned.draws["betaU"], more.draws["betaU"])


def test_recorded_widths_pass_back_with_their_gaps_after_a_file_round_trip(tmp_path):
    data, obs = _data()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        first = gpmsa.fit(data, obs, n_iter=60, seed=0, n_chains=2, tune_rounds=3,
                          fixed={"lamWOs": 1e3})  # fmt: skip
    first.save(tmp_path / "a.gpmsa")
    loaded = gpmsa.load(tmp_path / "a.gpmsa")
    recorded = loaded.settings["step_widths"]
    assert recorded["lamWOs"] == [[None], [None]]  # a fixed parameter has no width
    more = _fit(n_iter=30, init=loaded, fixed={"lamWOs": 1e3})
    direct = _fit(n_iter=30, init=loaded, fixed={"lamWOs": 1e3}, tune=False,
                  step_widths=recorded)  # fmt: skip
    np.testing.assert_array_equal(more.draws["lamUz"], direct.draws["lamUz"])


def test_a_fresh_fit_still_tunes_and_per_chain_widths_are_checked():
    emu = _fit(n_iter=20, tune_rounds=2)
    assert emu.settings["tune"] is True
    with pytest.raises(gpmsa.GPMSAError, match=r"\(2, 2, 1\), one per chain\), got \(3, 2, 1\)"):
        _fit(n_iter=10, tune=False, step_widths={"betaU": np.full((3, 2, 1), 0.2)})
    with pytest.raises(gpmsa.GPMSAError, match=r"step_widths\['lamUz'\] must be finite and > 0"):
        _fit(n_iter=10, tune=False, step_widths={"lamUz": [[1.0], [None]]})


def test_a_damaged_width_record_is_named_with_the_way_out():
    first = _tuned()
    record = {k: v for k, v in first.settings.items() if k != "step_widths"}
    record["step_widths"] = {"betaU": [[0.1, 0.2, 0.3]]}
    damaged = replaced(first, settings=record)
    with pytest.raises(gpmsa.GPMSAError, match=r"recorded step widths .*pass step_widths= or tune"):
        _fit(n_iter=10, init=damaged)


def test_one_chain_takes_its_start_in_the_parameter_s_shape():
    data, _ = _data()
    problem = gpmsa.prepare(data).problem
    start = {"lamUz": [0.8], "betaU": [[0.7], [0.3]]}
    chains = gpmsa.backends.get("numpy").sample(problem, n_iter=3, seed=0, init=start, tune=False)
    np.testing.assert_array_equal(chains.info["starts"]["lamUz"], [[0.8]])
    np.testing.assert_array_equal(chains.info["starts"]["betaU"], [[[0.7], [0.3]]])
    with pytest.raises(
        gpmsa.GPMSAError, match=r"must have shape \(2, [^)]*\) \(chains, \*shape\), got"
    ):
        gpmsa.backends.get("numpy").sample(problem, n_iter=3, n_chains=2, seed=0, init=start)
    with pytest.raises(gpmsa.GPMSAError, match=r"init\['lamUz'\] must be a numeric array"):
        gpmsa.backends.get("numpy").sample(problem, n_iter=3, seed=0, init={"lamUz": ["a"]})


def test_a_pyro_fit_continues_with_tuning_not_with_its_nuts_step_size():
    """pyro records its NUTS step size as "step_widths": not a Metropolis width, so a numpy
    continuation of a pyro fit tunes (from GPM/SA's widths) as before continuations kept widths."""
    pytest.importorskip("pyro")
    data, _ = _data()
    first = gpmsa.fit(data, n_iter=20, backend="pyro", seed=0, n_warmup=10)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        more = gpmsa.fit(data, n_iter=10, init=first, seed=1, tune_rounds=2)
        fresh = gpmsa.fit(data, n_iter=10, init=first, seed=1, tune_rounds=2, tune=True)
    assert more.settings["tune"] is True
    for name, draws in fresh.draws.items():
        np.testing.assert_array_equal(more.draws[name], draws)


def test_tune_true_retunes_from_gpmsa_widths_past_a_damaged_record():
    """The way out the damaged-record error names: tune=True tunes as a fresh fit does, from
    GPM/SA's initial widths, without reading the record."""
    first = _tuned()
    record = {k: v for k, v in first.settings.items() if k != "step_widths"}
    record["step_widths"] = {"betaU": [[0.1, 0.2, 0.3]]}
    damaged = replaced(first, settings=record)
    again = _fit(n_iter=10, init=damaged, tune=True, tune_rounds=2)
    same = _fit(n_iter=10, init=first, tune=True, tune_rounds=2, step_widths={})
    assert again.settings["tune"] is True
    for name, draws in same.draws.items():
        np.testing.assert_array_equal(again.draws[name], draws)


def test_a_continuation_given_its_own_widths_tunes_from_them_as_before():
    """Only the recorded widths skip tuning: step_widths= for some parameters (the others at
    GPM/SA's initial widths) tunes from them by default, as every fit did before the record
    was kept; tune=False runs them untuned."""
    first = _tuned()
    some = {"lamUz": 0.3}
    more = _fit(n_iter=10, init=first, step_widths=some, tune_rounds=2)
    told = _fit(n_iter=10, init=first, step_widths=some, tune_rounds=2, tune=True)
    assert more.settings["tune"] is True
    for name, draws in told.draws.items():
        np.testing.assert_array_equal(more.draws[name], draws)
    untuned = _fit(n_iter=10, init=first, step_widths=some, tune=False)
    assert np.all(np.array(untuned.settings["step_widths"]["lamUz"]) == 0.3)
