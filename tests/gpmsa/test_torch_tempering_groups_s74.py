"""Parallel tempering on the torch backend with chain groups (session 74: ``temperatures=`` with
``chain_groups`` > 1 or an ``executor``; ``torch_backend._grouped_sweeps``, ``_tempered_draws``).

Tuning runs in one batch (every chain's K copies, as without groups); then each group holds
whole chains, rows c K + k of all their copies, and tempers within itself from its own stream
(child n_chains + g of the seed's SeedSequence, as a plain grouped run's). So, as for plain
runs, a grouped tempered run has the one batch's tuned widths and starts but other draws, and
its draws depend on ``chain_groups`` and the seed, not on ``n_jobs`` or the executor.
"""

import warnings
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
from _backend_cases import multi_data
from _tempering_cases import two_mode_case as _sym_case

import gpmsa
from gpmsa import backends
from gpmsa.errors import GPMSAError, ResourceLimitError
from gpmsa.mcmc.parallel import available_cpus
from gpmsa.model.likelihood import log_posterior
from gpmsa.model.problem import prepare

torch = pytest.importorskip("torch")

KW = {"n_iter": 10, "n_chains": 4, "seed": 21, "warmup": 3, "tune_stages": 1, "tune_rounds": 1,
      "tune_levels": 3}  # fmt: skip


def _problem():
    return gpmsa.prepare(multi_data()[0]).problem


def _sample(problem, **kw):
    return backends.get("torch").sample(problem, **{**KW, **kw})


def test_grouped_tempered_draws_depend_on_the_groups_and_seed_only():
    problem = _problem()
    runs = [_sample(problem, temperatures=3, chain_groups=2, n_jobs=1)]
    if available_cpus() >= 2:
        runs.append(_sample(problem, temperatures=3, chain_groups=2, n_jobs=2))
    with ThreadPoolExecutor(2) as ex:
        runs.append(_sample(problem, temperatures=3, chain_groups=2, executor=ex))
    first = runs[0]
    info = first.info
    assert info["chain_groups"] == 2 and info["temperatures"] == [1.0, 2.0, 4.0]
    assert first.draws["betaU"].shape[:2] == (4, 10) and first.log_post.shape == (4, 10)
    rates = np.asarray(info["swap_rate"])
    assert rates.shape == (4, 2) and np.all((rates >= 0) & (rates <= 1)) and rates.any()
    assert np.isfinite(first.accept_rate["betaU"]).all()
    for other in runs[1:]:
        for name, val in first.draws.items():
            assert np.array_equal(other.draws[name], val), name
        assert np.array_equal(other.log_post, first.log_post)
        assert np.array_equal(other.info["swap_rate"], info["swap_rate"])
    for c in range(4):  # the kept rows are each chain's T = 1 copy, its caches its own
        params = {k: v[c, -1] for k, v in first.draws.items()}
        assert np.isclose(first.log_post[c, -1], log_posterior(problem, params), rtol=1e-9)


def test_grouped_tempered_run_relates_to_one_batch_as_a_plain_one():
    """Tuning in one batch: the same widths and starts as the one batch; the draws from the
    groups' streams, other than the one batch's; plain runs alike."""
    problem = _problem()
    for temps in (None, [1.0, 3.0]):
        one = _sample(problem, temperatures=temps)
        grouped = _sample(problem, temperatures=temps, chain_groups=2, n_jobs=1)
        for name, val in one.step_widths.items():
            np.testing.assert_array_equal(grouped.step_widths[name], val)
        for name, val in one.info["starts"].items():
            np.testing.assert_array_equal(grouped.info["starts"][name], val)
        assert not np.array_equal(grouped.log_post, one.log_post)  # other streams
        assert ("swap_rate" in grouped.info) == (temps is not None)
        if temps is not None:
            assert np.shape(grouped.info["swap_rate"]) == np.shape(one.info["swap_rate"]) == (4, 1)


def test_fit_and_calibrate_take_groups_with_temperatures():
    sim, obs = _sym_case()
    opts = {"tune_rounds": 1, "tune_levels": 3, "tune_stages": 1, "warmup": 2}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = gpmsa.fit(sim, obs, n_iter=12, n_burn=2, n_chains=4, seed=1, backend="torch",
                        theta_init=[0.2], temperatures=4, swap_every=2, chain_groups=2,
                        n_jobs=1, **opts)  # fmt: skip
        post = gpmsa.calibrate(emu, obs, n_samples=12, n_burn=2, n_chains=4, seed=2,
                               backend="torch", fast=False, temperatures=[1.0, 4.0],
                               chain_groups=2, n_jobs=1, **opts)  # fmt: skip
    s = emu.settings
    assert s["temperatures"] == [1.0, 2.0, 4.0, 8.0] and s["swap_every"] == 2
    assert np.shape(s["swap_rate"]) == (4, 3) and s["backend_options"]["chain_groups"] == 2
    assert post.info["temperatures"] == [1.0, 4.0] and np.shape(post.info["swap_rate"]) == (4, 1)
    assert post.chains["t0"].shape == (4, 10) and post.info["backend_options"]["chain_groups"] == 2
    assert emu.calibration["theta_native"].shape == (40, 1)


def test_bad_combinations_are_still_refused_by_name():
    problem = _problem()
    cases = [
        ({"chain_groups": 2, "device": "cuda"}, "run CPU worker processes; device='cuda'"),
        ({"chain_groups": 2, "num_threads": 2}, "each group's process runs one thread"),
        ({"chain_groups": 5}, r"chain_groups must be an integer in \[1, n_chains=4\]"),
        ({"n_jobs": 2}, "n_jobs=2 with chain_groups=1"),
        ({"chain_groups": 2, "swap_every": 11}, "swap_every=11 exceeds n_iter=10"),
    ]
    for kw, msg in cases:
        with pytest.raises(GPMSAError, match=msg):
            _sample(problem, temperatures=2, **kw)
    # (adapt_ladder with chain_groups: taken since session 74, test_torch_adaptive_ladder_s74)


def test_memory_check_counts_every_copy_with_groups(monkeypatch):
    sim, obs = _sym_case()
    problem = prepare(sim, obs).problem
    tb = backends.get("torch")
    seen = []
    monkeypatch.setattr(tb, "check_memory", lambda n, what: seen.append((n, what)))
    tb.check_batch_memory(problem, 100, 2, torch.float64)
    tb.check_batch_memory(problem, 100, 2, torch.float64, copies=4)
    plain, hot = seen
    monkeypatch.undo()
    monkeypatch.setattr(gpmsa.limits, "MAX_MEMORY_BYTES", (plain[0] + hot[0]) / 2)
    with pytest.raises(ResourceLimitError, match="at 4 temperatures"):
        gpmsa.fit(sim, obs, n_iter=100, n_chains=2, backend="torch", temperatures=4,
                  chain_groups=2, n_jobs=1)  # fmt: skip
