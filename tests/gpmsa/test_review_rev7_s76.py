"""Review of e9993e8 (tempered studies' hot copies, session 76): a continuation across a basis
whose columns are the source's reordered (one sign flipped) resumes each hot copy at its
source state and widths, mapped; a damaged record's message names the values it refuses."""

import functools
import warnings

import numpy as np
import pytest
from _basis_cases import basis_obs, basis_sim
from test_studyhot_s76 import _damaged, _set

import gpmsa
from gpmsa.model.problem import prepare
from gpmsa.studies import run
from gpmsa.studies.sampler import StudyState

KW = {"labels": ["a", "b"], "shared": ["t"], "n_chains": 2, "tune_rounds": 2, "tune_levels": 3}


@functools.cache
def _fit_source():
    sim, obs = basis_sim(), [basis_obs(0.05 * k) for k in range(2)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # short chains
        return gpmsa.fit_study([sim] * 2, obs, n_iter=12, n_keep=4, seed=0, temperatures=(1, 3),
                               **KW)  # fmt: skip


def test_a_reordered_basis_resumes_each_hot_copy_mapped(monkeypatch):
    src = _fit_source()
    sim, obs = basis_sim(), [basis_obs(0.05 * k) for k in range(2)]
    K = src.members[0].K[:, ::-1] * [1.0, -1.0]  # swapped, one sign flipped
    seen = {}
    real = run.sample_study

    def spy(*args, **kw):
        seen.update(kw)
        return real(*args, **kw)

    monkeypatch.setattr(run, "sample_study", spy)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        more = gpmsa.fit_study([sim] * 2, obs, n_iter=4, seed=1, init=src, basis=K, **KW)
    assert more.settings["tune"] is False  # resumed, untuned
    here = [prepare(sim, o, basis=K).problem for o in obs]
    there = [prepare(sim, o, basis=src.members[0].K).problem for o in obs]
    states, widths = src.settings["hot_states"], src.settings["hot_step_widths"]
    for c in range(2):
        (start, w), = seen["hot_copies"][c]  # fmt: skip
        old = [{**m, **{n: np.array(v)[c, 0] for n, v in states["members"][lab].items()}}
               for m, lab in zip(start[0], ("a", "b"), strict=True)]  # fmt: skip
        np.testing.assert_array_equal(start[0][0]["lamUz"], old[0]["lamUz"][::-1])
        lp = StudyState(here, src.layout, src.hyper, *start, np.random.default_rng(0)).log_post()
        ref = StudyState(there, src.layout, src.hyper, old, *start[1:], np.random.default_rng(0))
        assert lp == pytest.approx(ref.log_post(), rel=1e-10)
        names = list(more.settings["accept_rate"])  # this run's sweep order
        at = {n: w[i] for i, n in enumerate(names)}
        assert at["a.lamUz[0]"] == widths["a.lamUz[1]"][c][0]
        assert at["b.betaU[1, 0]"] == widths["b.betaU[1, 1]"][c][0]


def test_a_damaged_widths_message_shows_the_value_it_refuses(tmp_path):
    path = _damaged(tmp_path, _set("hot_step_widths", "t", [[0.1] * 3, [0.1, -2.0, 0.1]]))
    with pytest.raises(gpmsa.EmulatorFileError, match=r"hot_step_widths\['t'\]: .*-2\.0"):
        gpmsa.load_study(path)
