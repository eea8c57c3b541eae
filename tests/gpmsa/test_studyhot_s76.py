"""A tempered study's hot copies (session 76, gpmsa.studies.hot): ``calibrate_study`` and
``fit_study(..., temperatures=)`` record each chain's hot copies (the study state and its
widths) in the study file, checked on loading, and a continuation at the same ladder resumes
every copy where it stopped, untuned (before: every copy re-tuned, ``tune_rounds`` x
``tune_levels`` sweeps a copy). Fresh studies draw as before; the two-mode case is
test_study_tempering_s73's."""

import hashlib
import warnings

import numpy as np
import pytest
from test_study_tempering_s73 import LADDER, _study, sampler_problem

import gpmsa
from gpmsa.errors import GPMSAError
from gpmsa.io.container import ENVELOPE, STUDY_FORMAT, read_raw, write_raw
from gpmsa.studies import hot, sampler

SMALL = {"tune_rounds": 2, "tune_levels": 3}


def _source(**kw):
    return _study(n_samples=20, n_burn=0, n_chains=2, seed=4, temperatures=LADDER,
                  **{**SMALL, **kw})  # fmt: skip


def _digest(study) -> str:
    """The sampled draws' digest, rounded to 12 decimals and without ``log_post``: the BLAS
    kernel a host picks (OpenBLAS's Haswell, SkylakeX, Sandybridge) moves theta by an ulp and
    the log posterior by ~1e-9 here, so raw bytes differ between hosts with equal draws."""
    data = b"".join((np.round(study.draws[k], 12) + 0.0).tobytes()
                    for k in sorted(study.draws) if k != "log_post")  # fmt: skip
    return hashlib.sha256(data).hexdigest()[:16]


def test_fresh_seeded_studies_draw_as_before():
    """Digests of the draws computed before the record existed (HEAD 7bb020d, equal under
    the three OpenBLAS kernels above)."""
    kw = {"n_samples": 30, "n_burn": 0, "n_chains": 2, "seed": 4, "tune_rounds": 2}
    assert _digest(_study(temperatures=LADDER, **kw)) == "71b14961e5a6701d"
    assert _digest(_study(**kw)) == "dbe2cd6ca35a04c5"


def test_tempered_study_records_its_hot_copies_and_its_continuation_resumes_them(tmp_path):
    src = _source()
    states, widths = (src.settings[k] for k in ("hot_states", "hot_step_widths"))
    assert np.shape(states["theta"]) == (2, 3, 1) and np.shape(states["mu"]) == (2, 3, 0)
    assert set(states["members"]) == {"a", "b"}  # lamOs held: nothing else sampled
    assert set(widths) == set(src.settings["accept_rate"])
    assert np.all(np.array(widths["t"]) > 0) and np.shape(widths["t"]) == (2, 3)
    back = gpmsa.load_study(src.save(tmp_path / "s.gpmsastudy"))
    assert back.settings["hot_states"] == states and back.settings["hot_step_widths"] == widths
    more = _study(n_samples=10, n_chains=2, seed=5, init=back, **SMALL)
    assert more.settings["tune"] is False and more.settings["proportional_steps"] is False
    assert more.settings["temperatures"] == LADDER and "hot_states" in more.settings
    same = _study(n_samples=10, n_chains=2, seed=5, init=back, tune=False, **SMALL)
    np.testing.assert_array_equal(same.draws["theta"], more.draws["theta"])


def test_hot_copies_start_at_the_recorded_states_with_their_widths():
    src = _source()
    problems = [sampler_problem(src, i) for i in range(2)]
    start = ([dict(p.init) for p in problems], np.array([0.3]), np.empty(0), np.empty(0))
    hot_in = [((start[0], np.array([0.2 + 0.2 * k]), start[2], start[3]),
               np.array([0.05 * (k + 1)])) for k in range(3)]  # fmt: skip
    out = sampler.run_study_chain(
        problems, src.layout, src.hyper, 1, tune=False, seed=np.random.SeedSequence(1),
        start=start, widths=np.array([0.1]), temperatures=tuple(LADDER), swap_every=5,
        hot=hot_in,
    )  # fmt: skip
    np.testing.assert_array_equal(out["hot"]["widths"], [w for _, w in hot_in])
    assert np.all(np.abs(out["hot"]["theta"][:, 0] - [0.2, 0.4, 0.6]) < 0.5)  # one sweep on


def test_the_fit_study_and_hierarchical_case_resume():
    t = np.linspace(0.1, 0.9, 12)[:, None]
    x = np.tile([[0.0], [1.0]], (6, 1))
    sim = gpmsa.SimData(x=x, t=t, y=(x + 2 * t), t_names=["E"])
    obs = [gpmsa.ObsData(x=[[0.5]], y=[[1.5]]), gpmsa.ObsData(x=[[0.2]], y=[[1.2]])]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        kw = {"hierarchical": ["E"], "n_chains": 2, "temperatures": (1, 3), **SMALL}
        src = gpmsa.fit_study([sim, sim], obs, n_iter=10, seed=2, **kw)
        states = src.settings["hot_states"]
        assert np.shape(states["mu"]) == (2, 1, 1)
        assert {"betaU", "lamUz", "lamWOs", "lamOs"} <= set(states["members"]["model0"])
        more = gpmsa.fit_study([sim, sim], obs, n_iter=5, seed=3, init=src,
                               **{**kw, "temperatures": None})  # fmt: skip
    assert more.settings["tune"] is False and more.settings["temperatures"] == [1.0, 3.0]
    assert "hot_states" not in more.members[0].settings  # the study's record alone


@pytest.mark.parametrize(
    "change",
    [{"tune": True}, {"temperatures": [1, 5]}, {"adapt_ladder": True, "temperatures": [1, 2, 4]}],
)
def test_another_ladder_or_tuning_re_tunes_as_before(change):
    src = _source()
    more = _study(n_samples=5, n_chains=2, seed=5, init=src, **{**SMALL, **change})
    assert more.settings["tune"] is True


def test_a_file_without_the_record_re_tunes_and_refuses_tune_false():
    src = _source()
    for key in ("hot_states", "hot_step_widths"):
        del src.settings[key]  # as written before session 76
    more = _study(n_samples=5, n_chains=2, seed=5, init=src, **SMALL)
    assert more.settings["tune"] is True
    with pytest.raises(GPMSAError, match="does not resume its hot copies"):
        _study(n_samples=5, n_chains=2, seed=5, init=src, tune=False)


def test_a_record_above_max_hot_values_is_left_out(monkeypatch):
    monkeypatch.setattr(hot, "MAX_HOT_VALUES", 10)
    src = _source()
    assert "hot_states" not in src.settings and "hot_step_widths" not in src.settings
    assert _study(n_samples=5, n_chains=2, seed=5, init=src, **SMALL).settings["tune"] is True


def _damaged(tmp_path, edit):
    path = _source().save(tmp_path / "s.gpmsastudy")
    manifest, arrays = read_raw(path, formats=(STUDY_FORMAT,))
    manifest = {k: v for k, v in manifest.items() if k not in ENVELOPE}
    edit(manifest["settings"])
    write_raw(path, manifest, arrays, fmt=STUDY_FORMAT)
    return path


def _set(part, key, value):
    def edit(settings):
        settings[part][key] = value

    return edit


@pytest.mark.parametrize(
    ("edit", "message"),
    [
        (_set("hot_states", "theta", [[[0.5]]]),
         r"settings.hot_states.theta: has shape \[1, 1, 1\]"),
        (_set("hot_states", "theta", [[[0.5]] * 3, [[0.5], [0.5], [None]]]),
         "settings.hot_states.theta: must be finite"),
        (_set("hot_step_widths", "t", [[0.1] * 3, [0.1, 0.0, 0.1]]),
         r"settings.hot_step_widths\['t'\]: must be finite numbers > 0"),
        (_set("hot_states", "members", {"a": {}}), "settings.hot_states.members: must be"),
        (lambda s: s.pop("hot_step_widths"), "settings.hot_step_widths: a tempered study records"),
    ],
)  # fmt: skip
def test_a_damaged_record_is_refused_on_loading(tmp_path, edit, message):
    with pytest.raises(gpmsa.EmulatorFileError, match=message):
        gpmsa.load_study(_damaged(tmp_path, edit))


def test_a_record_that_does_not_fit_is_refused_by_the_continuation():
    src = _source()
    src.settings["hot_states"]["theta"] = [[[1.5]] * 3] * 2  # outside (0, 1): no prior mass
    with pytest.raises(GPMSAError, match="init=study: its recorded hot copies .*no finite log"):
        _study(n_samples=5, n_chains=2, seed=5, init=src)
