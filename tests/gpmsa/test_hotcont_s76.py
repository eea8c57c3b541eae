"""A tempered fit's continuation resumes every hot copy where it stopped (session 76).

Before, the emulator recorded the T = 1 copy alone, so ``gpmsa.fit(data, init=emu)`` of a
tempered fit started every hot copy at the chain's last kept state and re-tuned them all
(``tune_rounds`` x ``tune_levels`` sweeps per copy, 1,000 by default) before its first draw.
Measured on the two-mode case (ladder (1, 4, 16, 64), 24 seeds, one chain, 500 sweeps then 500
continued): that warm-up took 0.74 s of the continuation's 1.23 s (a fresh fit of 500: 1.41
s), the chain's widths were re-tuned (24 of 24 differ from the source's), and 5 of 24 chains
changed mode across the join (a long run: 6.4% of its sweeps). A numpy tempered fit now
records each hot copy's last state and widths (settings "hot_states", "hot_step_widths"), and
its continuation at the same ladder runs on from them untuned: 0.38 s (a fresh fit 1.13 s), the
source's widths, 0 of 24 changes of mode across the join.
"""

import numpy as np
import pytest
from _tempering_cases import check_resumed_hot_copies, fit_two_mode
from _tempering_cases import two_mode_case as _case

import gpmsa
from gpmsa.errors import GPMSAError
from gpmsa.mcmc import tempering
from gpmsa.mcmc.diagnostics import ess
from gpmsa.mcmc.sampler import ChainState, default_widths, sample
from gpmsa.model.problem import prepare
from tests.gpmsa.test_file_hostile import read_members, write_members

LADDER = [1.0, 4.0, 16.0, 64.0]
SMALL = {"tune_rounds": 1, "tune_levels": 2}


def _fit(**kw):
    return fit_two_mode(**{"n_jobs": 1, **kw})


def _source():
    return _fit(n_iter=20, n_chains=2, seed=3, temperatures=3, **SMALL)


def test_tempered_fit_records_its_hot_copies_and_its_continuation_resumes_them(tmp_path):
    src = _source()
    more = _fit(n_iter=10, n_chains=2, init=src, seed=4)
    check_resumed_hot_copies(src, more, _fit, tmp_path / "t.gpmsa")
    assert more.settings["proportional_steps"] is False  # as the tuned source stepped


def test_copies_start_at_the_states_and_widths_given():
    """``run_tempered_chain``'s ``copies``: each hot copy starts at its state, runs at its
    widths (no sweep: the record is exactly what was given)."""
    sim, obs = _case()
    problem = prepare(sim, obs).problem
    rng = np.random.default_rng(0)
    base = default_widths(problem)
    copies = []
    for k in (1, 2):
        start = {n: np.array(v, dtype=float) for n, v in problem.init.items()}
        start["theta"] = np.array([0.1 * k])
        copies.append((start, {n: v * (k + 1) for n, v in base.items()}))
    record: dict = {}
    tempering.run_tempered_chain(
        problem, 0, lambda at: ChainState(problem, problem.init if at is None else at, rng),
        temperatures=(1.0, 2.0, 4.0), swap_every=1, tune=False, widths=base, rng=rng,
        tune_rounds=1, tune_levels=2, record=record, copies=copies,
    )  # fmt: skip
    states, widths = record["hot"]
    assert [float(st["theta"][0]) for st in states] == [0.1, 0.2]
    np.testing.assert_array_equal(widths[1]["theta"], base["theta"] * 3)


def test_appended_resumed_continuation_pools_to_the_exact_weight():
    """test_tempered_continuation_s74's case: 2 chains x 250 tempered, 250 appended (seed
    15), now resumed: no warm-up between the parts."""
    src = _fit(n_iter=250, n_chains=2, n_burn=50, n_keep=400, theta_init=[0.2], tune_rounds=2,
               seed=15, temperatures=LADDER)  # fmt: skip
    out = _fit(n_iter=250, n_chains=2, init=src, append=True, seed=115)
    assert out.settings["tune"] is False
    up = out.calibration["theta_native"][:, 0].reshape(2, -1) > 0.5
    new = up[:, 200:].mean(axis=1)
    assert np.all((new > 0.05) & (new < 0.95)), new  # each chain in both modes
    n_eff = sum(ess(u.astype(float)) for u in up)
    assert abs(up.mean() - 0.5) < 3 * np.sqrt(0.25 / n_eff), (up.mean(), n_eff)
    # the join: each chain's first continued draw in its last kept draw's mode
    assert np.array_equal(up[:, 200], up[:, 199])


def test_without_a_record_or_at_another_ladder_it_tunes_as_before():
    src = _source()
    kw = {"n_iter": 10, "n_chains": 2, "init": src, "seed": 4, **SMALL}
    for other in ({"temperatures": [1, 5]}, {"tune": True},
                  {"step_widths": {"theta": 0.1}}, {"adapt_ladder": True}):  # fmt: skip
        assert _fit(**kw, **other).settings["tune"] is True, other
    for key in ("hot_states", "hot_step_widths"):  # a file written before session 76
        del src.settings[key]
    old = _fit(**kw)
    assert old.settings["tune"] is True and "hot_states" in old.settings
    with pytest.raises(GPMSAError, match="does not resume its hot copies"):
        _fit(n_iter=10, n_chains=2, init=src, tune=False)


def test_plain_fits_record_no_hot_copies():
    plain = _fit(n_iter=10, n_chains=2, seed=1, **SMALL)
    assert "hot_states" not in plain.settings
    sim, obs = _case()
    chains = sample(prepare(sim, obs).problem, n_iter=5, seed=1, **SMALL)
    assert "hot_states" not in chains.info


def _damaged(tmp_path, key, name, value):
    manifest, arrays = read_members(_source().save(tmp_path / "t.gpmsa"))
    manifest["settings"][key][name] = value
    return write_members(tmp_path / "bad.gpmsa", manifest, arrays)


@pytest.mark.parametrize(
    ("key", "name", "value", "message"),
    [
        ("hot_states", "theta", [[[0.5]]], r"hot_states\['theta'\]: has shape \[1, 1, 1\], "
         r"expected \[2, 2, 1\]"),
        ("hot_states", "lamOs", [[[1.0], [None]], [[1.0], [1.0]]], r"hot_states\['lamOs'\]: must "
         "be finite"),
        ("hot_step_widths", "theta", [[[0.1], [-1.0]], [[0.1], [0.1]]], r"hot_step_widths\["
         r"'theta'\]: must be numbers > 0"),
        ("hot_states", "nope", [[[1.0]]], r"hot_states\['nope'\]: names no parameter"),
    ],
)  # fmt: skip
def test_a_damaged_record_is_refused_on_loading(tmp_path, key, name, value, message):
    with pytest.raises(gpmsa.EmulatorFileError, match=message):
        gpmsa.load(_damaged(tmp_path, key, name, value))


def test_a_damaged_record_in_memory_is_refused_by_the_continuation(tmp_path):
    src = _source()
    src.settings["hot_states"]["lamWOs"] = [[[-1.0], [1.0]], [[1.0], [1.0]]]  # no prior mass
    with pytest.raises(GPMSAError, match=r"init=emulator: its recorded hot copies .*lamWOs"):
        _fit(n_iter=10, n_chains=2, init=src, seed=4)
    src.settings["hot_states"]["lamWOs"] = [[[1.0]]]
    with pytest.raises(GPMSAError, match=r"hot_copies\['starts'\]\['lamWOs'\] must have shape"):
        _fit(n_iter=10, n_chains=2, init=src, seed=4)
    del src.settings["hot_step_widths"]
    with pytest.raises(GPMSAError, match="settings.hot_step_widths"):
        src.save(tmp_path / "never-written.gpmsa")


def test_a_record_above_max_hot_values_is_left_out_and_its_continuation_warms_up(monkeypatch):
    """The record lives in the JSON manifest (limit 16 MiB): a fit whose hot copies hold more
    than ``MAX_HOT_VALUES`` numbers records none (a review found that a large tempered fit could
    pass the manifest's limit, which it could be saved within before), and its continuation
    tunes its copies as one without the record does."""
    import gpmsa.fitting.fit as fit_module

    monkeypatch.setattr(fit_module, "MAX_HOT_VALUES", 10)
    src = _source()
    assert "hot_states" not in src.settings and "hot_step_widths" not in src.settings
    more = _fit(n_iter=10, n_chains=2, init=src, seed=4, **SMALL)
    assert more.settings["tune"] is True and "hot_states" not in more.settings
