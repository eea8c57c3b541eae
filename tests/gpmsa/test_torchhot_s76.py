"""A torch tempered fit records its hot copies and its continuation resumes them (session 76).

Before, only the numpy backend recorded each hot copy's last state and widths (settings
"hot_states", "hot_step_widths"); a torch tempered fit recorded neither, and its continuation
(and a torch continuation of a numpy source) started every copy at the chain's last kept state
and re-tuned them all (``tune_stages`` x (``warmup`` + ``tune_rounds`` x ``tune_levels``)
sweeps per copy). Measured on the two-mode case (ladder (1, 4, 16, 64), 4 chains, 500 sweeps
then 500 continued, 8 seeds, load 1.3-2.7 on 2 cores): the resumed continuation took 1.74 s
against the re-tuned one's 5.46 s (ratio 0.32; 3 seeds, load 2.0-2.4), 2 of 32 chains changed
mode at the join (re-tuned: 16 of 32), and the resumed draws' share in the upper mode was
0.484 against the exact 1/2 (± 0.018, bulk ESS 798; per seed 0.34-0.59, re-tuned 0.37-0.66,
pooled 0.515). The record has one layout on both backends, so either continues the other's
file.
"""

import numpy as np
import pytest
from _tempering_cases import check_resumed_hot_copies, fit_two_mode
from _tempering_cases import two_mode_case as _case

from gpmsa.errors import GPMSAError
from gpmsa.mcmc.sampler import default_widths
from gpmsa.model.problem import prepare

torch_backend = pytest.importorskip("gpmsa.backends.torch_backend")

SMALL = {"tune_rounds": 1, "tune_levels": 2}
WARM = {"warmup": 2, "tune_stages": 1}  # torch's tuning, kept short


def _fit(backend="torch", **kw):
    where = {"n_jobs": 1} if backend == "numpy" else {}
    return fit_two_mode(backend=backend, **where, **kw)


def _source(backend="torch", **kw):
    warm = WARM if backend == "torch" else {}
    return _fit(backend, n_iter=20, n_chains=2, seed=3, temperatures=3, **SMALL, **warm, **kw)


def _counted(monkeypatch) -> list:
    """Count the torch batch's sweeps (each sweeps every row once)."""
    calls, sweep = [], torch_backend.BatchState.sweep

    def counted(self, *args):
        calls.append(1)
        return sweep(self, *args)

    monkeypatch.setattr(torch_backend.BatchState, "sweep", counted)
    return calls


def test_torch_tempered_fit_records_its_hot_copies_and_its_continuation_resumes_them(
    tmp_path, monkeypatch
):
    src = _source()
    widths = np.array(src.settings["hot_step_widths"]["theta"])
    assert np.all(widths[0] == widths[1])  # torch: copy k's widths shared by the chains
    sweeps = _counted(monkeypatch)
    more = _fit(n_iter=10, n_chains=2, init=src, seed=4)
    assert len(sweeps) == 10  # no sweep before the first draw (re-tuned: 10 more here)
    check_resumed_hot_copies(src, more, _fit, tmp_path / "t.gpmsa")


def test_each_backend_resumes_the_others_hot_copies(monkeypatch):
    numpy_source = _source("numpy")
    sweeps = _counted(monkeypatch)
    from_numpy = _fit(n_iter=10, n_chains=2, init=numpy_source, seed=4)
    assert from_numpy.settings["tune"] is False and len(sweeps) == 10
    src = _source()
    from_torch = _fit("numpy", n_iter=10, n_chains=2, init=src, seed=4)
    assert from_torch.settings["tune"] is False
    assert from_torch.settings["hot_step_widths"] == src.settings["hot_step_widths"]


def test_other_torch_continuations_tune_as_before():
    src = _source()
    kw = {"n_iter": 10, "n_chains": 2, "init": src, "seed": 4, **SMALL, **WARM}
    for other in ({"temperatures": [1, 5]}, {"tune": True}, {"step_widths": {"theta": 0.1}}):
        assert _fit(**kw, **other).settings["tune"] is True, other
    for key in ("hot_states", "hot_step_widths"):  # a file without the record
        del src.settings[key]
    assert _fit(**kw).settings["tune"] is True
    with pytest.raises(GPMSAError, match="does not resume its hot copies"):
        _fit(n_iter=10, n_chains=2, init=src, tune=False)


def test_rows_start_at_the_hot_copies_given_and_groups_record_theirs():
    """``hot_copies``: row c K + k starts at chain c's hot copy k; with steps of 1e-12 one
    sweep (and its swaps, which only exchange rows) leaves every chain's K states where they
    started. The chain groups' workers return their hot copies' states too."""
    sim, obs = _case()
    problem = prepare(sim, obs).problem
    tiny = {n: np.full(v.shape, 1e-12) for n, v in default_widths(problem).items()}
    given = np.array([[[0.1], [0.3]], [[0.6], [0.9]]])  # (chains, hot copies, 1)
    state = {n: np.broadcast_to(v, (2, 2, *v.shape)) for n, v in problem.init.items()}
    steps = {n: np.broadcast_to(v, (2, 2, *v.shape)) for n, v in tiny.items()}
    hot = {"starts": {**state, "theta": given}, "widths": steps}
    init = {n: np.stack([v, v]) for n, v in problem.init.items()}
    init["theta"] = np.array([[0.2], [0.7]])
    for groups in (1, 2):
        out = torch_backend.sample(problem, n_iter=1, n_chains=2, tune=False, step_widths=tiny,
                                   seed=1, init=init, temperatures=3, hot_copies=hot,
                                   chain_groups=groups)  # fmt: skip
        rows = np.concatenate([out.draws["theta"][:, -1:], out.info["hot_states"]["theta"]], 1)
        np.testing.assert_allclose(np.sort(rows[..., 0], 1), [[0.1, 0.2, 0.3], [0.6, 0.7, 0.9]],
                                   atol=1e-9)  # fmt: skip
        assert np.all(out.info["hot_step_widths"]["theta"] == 1e-12)
    with pytest.raises(GPMSAError, match="hot_copies needs temperatures="):
        torch_backend.sample(problem, n_iter=1, tune=False, hot_copies=hot)
    wrong = r"hot_copies\['starts'\]\['\w+'\] must have shape \(1, 1, "  # 1 chain, not 2
    with pytest.raises(GPMSAError, match=wrong):
        torch_backend.sample(problem, n_iter=1, tune=False, temperatures=2, hot_copies=hot)
