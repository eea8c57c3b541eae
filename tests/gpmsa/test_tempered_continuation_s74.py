"""Tempered continuation (session 74): ``gpmsa.fit(..., init=emu)`` of a tempered fit runs on
at its ladder (or ``temperatures=``), every copy of a chain started at the chain's last kept
state and tuned at its temperature (from the recorded T = 1 widths) while the copies warm up,
swapping, before any draw is kept.

The two-mode case of test_tempering_s72: y = 10 (t - 0.5)^2 on a design symmetric about
t = 0.5, observed near 0.9, so the posterior is exactly symmetric under t -> 1 - t and
P(t > 0.5) = 1/2. A plain fit started at t = 0.2 never leaves its mode; a tempered one, and its
tempered continuation, visit both.
"""

import numpy as np
import pytest
from _tempering_cases import fit_two_mode as _fit
from _tempering_cases import two_mode_case as _case

import gpmsa
from gpmsa.errors import GPMSAError
from gpmsa.mcmc.diagnostics import ess
from gpmsa.mcmc.sampler import sample
from gpmsa.model.problem import prepare

LADDER = [1.0, 4.0, 16.0, 64.0]
SMALL = {"tune_rounds": 1, "tune_levels": 2}


def _upper(emu, n_chains: int) -> np.ndarray:
    return emu.calibration["theta_native"][:, 0].reshape(n_chains, -1) > 0.5


def test_appended_tempered_continuation_pools_to_the_exact_weight(tmp_path):
    """A tempered fit of 2 chains x 250 sweeps (200 kept), appended to by a tempered
    continuation of 250 (its default: the source's ladder)."""
    src = _fit(n_iter=250, n_chains=2, n_burn=50, n_keep=400, theta_init=[0.2], tune_rounds=2,
               seed=15, temperatures=LADDER)  # fmt: skip
    out = _fit(n_iter=250, n_chains=2, init=src, append=True, tune_rounds=2, seed=115)
    up = _upper(out, 2)
    assert up.shape == (2, 450)
    new = up[:, 200:].mean(axis=1)  # the continuation's own: each chain in both modes
    assert np.all((new > 0.05) & (new < 0.95)), new  # 0.36, 0.19 (re-tuned before s76: 0.26, 0.69)
    n_eff = sum(ess(u.astype(float)) for u in up)  # 15 (rank-normalised bulk ESS per chain)
    # 0.362 (s74, re-tuned: 0.471). Resumed (s76), the continued sweeps are the long run's: of
    # seeds 0-15 of this size, 4 leave a chain's continued draws outside (0.05, 0.95) (one run
    # of 500, its last 250: 7); elsewhere |z| <= 2.44 but one 3.46 (one run of 500: 2.72)
    p = up.mean()
    assert abs(p - 0.5) < 3 * np.sqrt(0.25 / n_eff), (p, n_eff)
    np.testing.assert_array_equal(out.calibration["theta"][:200], src.calibration["theta"][:200])
    s = out.settings  # recorded as a fresh tempered fit records it
    assert s["temperatures"] == LADDER and s["swap_every"] == 1
    assert s["tune"] is False  # every copy resumed where it stopped (session 76): untuned
    rates = np.array(s["swap_rate"])
    assert rates.shape == (2, 3) and np.all((rates > 0.02) & (rates < 1))
    assert s["continued_from"] == src.model_sha256 and s["appended_to"] == src.model_sha256
    assert s["appended_after"] == 200 and s["thin"] == 1 and out.n_draws == 900
    back = gpmsa.load(out.save(tmp_path / "c.gpmsa"))
    assert back.settings["temperatures"] == LADDER


def test_plain_fit_continued_with_a_ladder_crosses():
    plain = _fit(n_iter=300, n_burn=0, n_keep=300, theta_init=[0.2], tune_rounds=2, seed=1)
    assert not _upper(plain, 1).any()  # stuck in its mode
    more = _fit(n_iter=400, n_keep=400, init=plain, temperatures=LADDER, tune_rounds=2, seed=2)
    assert 0.05 < _upper(more, 1).mean() < 0.95  # 0.47
    assert more.settings["temperatures"] == LADDER and more.settings["tune"] is True
    assert more.settings["continued_from"] == plain.model_sha256


def test_default_ladder_override_and_opt_out():
    src = _fit(n_iter=20, n_chains=2, seed=3, temperatures=3, swap_every=2, **SMALL)
    kw = {"n_iter": 10, "n_chains": 2, "init": src, "seed": 4}
    again = _fit(**kw, **SMALL)
    assert again.settings["temperatures"] == [1.0, 2.0, 4.0]
    assert again.settings["swap_every"] == 2 and again.settings["tune"] is False  # resumed
    other = _fit(**kw, temperatures=[1, 5], **SMALL)
    assert other.settings["temperatures"] == [1.0, 5.0] and other.settings["swap_every"] == 1
    plain = _fit(**kw, temperatures=None)  # as before s74: untuned, at the recorded widths
    assert "temperatures" not in plain.settings and plain.settings["tune"] is False
    assert plain.settings["step_widths"] == src.settings["step_widths"]


def test_adapted_ladders_continue_per_chain():
    src = _fit(n_iter=20, n_chains=2, seed=3, temperatures=3, adapt_ladder=True, **SMALL)
    ladders = src.settings["adapted_temperatures"]
    assert ladders[0] != ladders[1]
    more = _fit(n_iter=10, n_chains=2, init=src, seed=4, **SMALL)
    assert more.settings["adapted_temperatures"] == ladders
    assert more.settings["temperatures"] == [1.0, 2.0, 4.0]  # the ladder they started from


def test_a_ladder_per_chain_is_each_chains_own():
    """Chain c at ladder c draws exactly what it draws in a run at that one ladder."""
    sim, obs = _case()
    problem = prepare(sim, obs).problem
    kw = {"n_iter": 15, "n_chains": 2, "seed": 7, "n_jobs": 1, **SMALL}
    both = sample(problem, temperatures=np.array([[1.0, 3.0], [1.0, 9.0]]), **kw)
    assert both.info["temperatures"] == [[1.0, 3.0], [1.0, 9.0]]
    for c, ladder in enumerate(([1.0, 3.0], [1.0, 9.0])):
        one = sample(problem, temperatures=ladder, **kw)
        np.testing.assert_array_equal(both.log_post[c], one.log_post[c])
        np.testing.assert_array_equal(both.info["swap_rate"][c], one.info["swap_rate"][c])
    with pytest.raises(GPMSAError, match="one ladder per chain must have 2 rows"):
        sample(problem, temperatures=np.ones((3, 2)) * [1.0, 2.0], **kw)


def _convergence_text(got) -> str:
    """The first ConvergenceWarning's text: Python >= 3.12 may record a DeprecationWarning
    first ("This process ... is multi-threaded, use of fork() may lead to deadlocks": the two
    chains' workers forked beside tqdm's monitor thread)."""
    return next(str(w.message) for w in got if issubclass(w.category, gpmsa.ConvergenceWarning))


def test_warning_names_the_ladder():
    sim, obs = _case()
    kw = {"n_iter": 20, "n_chains": 2, "seed": 3, **SMALL}
    with pytest.warns(gpmsa.ConvergenceWarning) as got:
        src = gpmsa.fit(sim, obs, temperatures=3, swap_every=2, **kw)
    text = _convergence_text(got)
    assert ("continue these: gpmsa.fit(..., init=the returned emulator, temperatures=[1, 2, 4], "
            "swap_every=2), tempered as these chains ran") in text  # fmt: skip
    with pytest.warns(gpmsa.ConvergenceWarning) as got:
        gpmsa.fit(sim, obs, init=src, append=True, **{**kw, "n_iter": 10})
    assert "append=True, temperatures=[1, 2, 4], swap_every=2)" in _convergence_text(got)
    with pytest.warns(gpmsa.ConvergenceWarning) as got:
        gpmsa.fit(sim, obs, temperatures=3, adapt_ladder=True, **kw)
    assert (
        "by default at each chain's adapted ladder (settings['adapted_temperatures']"
        in _convergence_text(got)
    )
    with pytest.warns(gpmsa.ConvergenceWarning) as got:
        gpmsa.fit(sim, obs, **kw)  # plain: as before
    assert "continue these: gpmsa.fit(..., init=the returned emulator)." in _convergence_text(got)


def test_refusals_name_the_problem():
    sim, obs = _case()
    src = _fit(n_iter=20, n_chains=2, seed=3, temperatures=3, **SMALL)
    for key in ("hot_states", "hot_step_widths"):  # as a file written before session 76
        del src.settings[key]
    with pytest.raises(GPMSAError, match="tune=False with a tempered continuation"):
        gpmsa.fit(sim, obs, n_iter=10, n_chains=2, init=src, tune=False)
    src.settings["temperatures"] = [2.0, 4.0]  # a damaged record (settings is a plain dict)
    with pytest.raises(GPMSAError, match="its tempering record .* is damaged"):
        gpmsa.fit(sim, obs, n_iter=10, n_chains=2, init=src)


def test_torch_continues_each_chains_ladder():
    pytest.importorskip("torch")
    sim, obs = _case()
    src = _fit(n_iter=20, n_chains=2, seed=3, temperatures=3, adapt_ladder=True, **SMALL)
    kw = {"n_iter": 10, "n_chains": 2, "init": src, "seed": 4, "backend": "torch", "warmup": 2,
          "tune_stages": 1, **SMALL}  # fmt: skip
    more = _fit(**kw)
    assert more.settings["adapted_temperatures"] == src.settings["adapted_temperatures"]
    assert np.array(more.settings["swap_rate"]).shape == (2, 2)
    with pytest.raises(GPMSAError, match="torch backend adapts from one ladder"):
        gpmsa.fit(sim, obs, adapt_ladder=True, **kw)


def test_tempered_study_continuation_pools_to_the_grid():
    """calibrate_study's case of test_study_tempering_s73 (two models sharing t, P(t > 0.5)
    0.678 on an exact grid): a tempered study appended to by its (default) tempered
    continuation; 8 seeds of this size: |z| <= 1.06 (re-tuned, before s76). Resumed (s76, its
    hot copies where they stopped), seeds 0-21: |z| <= 1.49 but one 3.93 (mean share 0.677),
    one chain's continued share outside (0.3, 0.95) (0.96)."""
    from test_study_tempering_s73 import LADDER as STUDY_LADDER
    from test_study_tempering_s73 import _grid_upper, _study

    src = _study(n_samples=500, n_burn=100, n_chains=2, seed=2, tune_rounds=2,
                 temperatures=STUDY_LADDER)  # fmt: skip
    out = _study(n_samples=500, n_chains=2, seed=102, tune_rounds=2, init=src, append=True)
    up = out.draws["theta"][..., 0] > 0.5
    assert up.shape == (2, 900)
    new = up[:, 400:].mean(axis=1)
    assert np.all((new > 0.3) & (new < 0.95)), new  # 0.63, 0.66 (s74, re-tuned: 0.66, 0.62)
    p, n_eff = up.mean(), sum(ess(u.astype(float)) for u in up)  # 0.652, 116 (s74: 0.651, 142)
    assert abs(p - _grid_upper()) < 3 * np.sqrt(p * (1 - p) / n_eff), (p, n_eff)
    s = out.settings
    assert s["temperatures"] == STUDY_LADDER and s["swap_every"] == 1
    assert s["tune"] is False  # every copy resumed where it stopped (session 76): untuned
    assert np.array(s["swap_rate"]).shape == (2, 3) and s["appended_after"] == 400
    for key in ("hot_states", "hot_step_widths"):  # as a file written before session 76
        del src.settings[key]
    with pytest.raises(GPMSAError, match="tune=False with a tempered continuation"):
        _study(n_samples=10, n_chains=2, init=src, tune=False)


def test_adapted_study_continues_per_chain():
    from test_study_tempering_s73 import _study

    src = _study(n_samples=20, n_burn=0, n_chains=2, seed=1, temperatures=3, adapt_ladder=True,
                 **SMALL)  # fmt: skip
    ladders = src.settings["adapted_temperatures"]
    more = _study(n_samples=10, n_chains=2, seed=2, init=src, **SMALL)
    assert more.settings["adapted_temperatures"] == ladders and ladders[0] != ladders[1]
    assert more.settings["temperatures"] == [1.0, 2.0, 4.0]
    other = _study(n_samples=10, n_chains=2, seed=2, init=src, temperatures=[1, 3], **SMALL)
    assert other.settings["temperatures"] == [1.0, 3.0]
    assert "adapted_temperatures" not in other.settings


def test_temperatures_one_continues_plain():
    """temperatures=1 (one temperature) is the way out of a tempered source's ladder: a study
    has no other (None is its default), and it appends untuned at the recorded widths as a
    plain study's continuation does (refused before: tune=False with a tempered continuation)."""
    from test_study_tempering_s73 import _study

    src = _study(n_samples=20, n_burn=0, n_chains=2, seed=1, temperatures=3, **SMALL)
    more = _study(n_samples=10, n_chains=2, seed=2, init=src, temperatures=1, tune=False,
                  append=True)  # fmt: skip
    assert "temperatures" not in more.settings and more.settings["tune"] is False
    assert more.draws["theta"].shape[1] == 30
    fit_src = _fit(n_iter=20, n_chains=2, seed=3, temperatures=3, **SMALL)
    plain = _fit(n_iter=10, n_chains=2, init=fit_src, seed=4, temperatures=1)
    assert "temperatures" not in plain.settings and plain.settings["tune"] is False
    with pytest.raises(GPMSAError, match=r"temperatures must be an integer in \[1, 32\], got 0"):
        _fit(n_iter=10, n_chains=2, seed=4, temperatures=0)
