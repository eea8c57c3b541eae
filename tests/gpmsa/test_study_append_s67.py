"""``calibrate_study(..., init=study, append=True)`` and ``fit_study(..., init=study,
append=True)``: as ``gpmsa.fit``'s ``append``, the source's kept draws followed, chain by chain,
by the continuation's sweeps at the source's step (a calibration study's: every sweep); n_burn
0, diagnostics and convergence over the pooled chains; the study file's counts accept it."""

import functools
import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.cli.main import main
from tests.gpmsa._study_cases import emulator, observations, sim_data

C = 2


def _data(n_models: int):
    rng = np.random.default_rng(3)
    pairs = [observations(0.3 + 0.1 * k, 4, 0.05, rng) for k in range(n_models)]
    return [x for x, _ in pairs], [y for _, y in pairs]


def _calibrate(n_samples, seed, **kw):
    xs, ys = _data(2)
    args = {"labels": ["a", "b"], "hierarchical": ["t"], "tune_rounds": 3, "tune_levels": 3,
            "n_chains": C, "n_samples": n_samples, "seed": seed, **kw}  # fmt: skip
    with warnings.catch_warnings():  # short chains: not converged
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        return gpmsa.calibrate_study([emulator()] * 2, xs, ys, **args)


def _fit(n_iter, seed, **kw):
    xs, ys = _data(2)
    obs = [gpmsa.ObsData(x=x, y=y) for x, y in zip(xs, ys, strict=True)]
    args = {"labels": ["a", "b"], "shared": ["t"], "tune_rounds": 3, "tune_levels": 3,
            "n_chains": C, "n_iter": n_iter, "seed": seed, **kw}  # fmt: skip
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # short chains, few observations
        return gpmsa.fit_study([sim_data()] * 2, obs, **args)


@functools.cache
def _cal_source():
    return _calibrate(30, 1, n_burn=10)  # 20 draws a chain


@functools.cache
def _fit_source():
    return _fit(40, 1, n_keep=16)  # 8 burnt, thin 4: 8 draws a chain


def _then(first, every, thin: int) -> np.ndarray:
    """(C, N, ...) ``first``, then every thin-th sweep of a continuation that kept every one."""
    return np.concatenate([first, every[:, thin - 1 :: thin]], axis=1)


def _flat(v) -> np.ndarray:
    v = np.asarray(v)
    return v.reshape(C, v.shape[0] // C, *v.shape[1:])


def test_an_appended_calibration_study_is_its_source_then_the_continuation():
    src = _cal_source()
    assert "betaV_0" not in src.draws and src.draws["mu"].shape == (C, 20, 1)
    pooled = _calibrate(12, 5, init=src, append=True)
    plain = _calibrate(12, 5, init=src)  # the same chains, its own draws
    assert set(pooled.draws) == set(src.draws)
    for k, v in pooled.draws.items():
        np.testing.assert_array_equal(v, _then(src.draws[k], plain.draws[k], 1))
    s = pooled.settings
    assert (s["n_iter"], s["n_samples"], s["n_burn"]) == (12, 12, 0)
    assert s["appended_to"] is None and s["appended_after"] == 20  # never saved
    assert (s["pooled_sweeps"], s["sweeps_run"]) == (20 + 12, 30 + 12)
    for k, r in s["accept_rate"].items():  # weighted by the parts' sweeps
        want = (src.settings["accept_rate"][k] * 30 + plain.settings["accept_rate"][k] * 12) / 42
        assert r == pytest.approx(want, rel=1e-12)
    assert pooled.convergence["n_draws"] == 32
    chain = pooled.posterior.chains["t.mu"]
    assert chain.shape == (C, 32) and pooled.diagnostics["t.mu"]["mean"] == pytest.approx(
        chain.mean(), rel=1e-12
    )


def test_an_appended_fit_study_pools_the_study_and_its_members(tmp_path, capsys):
    src = _fit_source()
    thin = src.settings["thin"]
    assert thin == 4 and src.draws["theta"].shape == (C, 8, 1)
    pooled = _fit(20, 5, init=src, append=True)
    plain = _fit(20, 5, init=src, n_keep=C * 20)  # the same chains, every sweep kept
    assert plain.settings["thin"] == 1
    for k, v in pooled.draws.items():
        np.testing.assert_array_equal(v, _then(src.draws[k], plain.draws[k], thin))
    for old, new, every in zip(src.members, pooled.members, plain.members, strict=True):
        for part in ("draws", "calibration"):
            assert set(getattr(new, part)) == set(getattr(old, part))
            for k, v in getattr(new, part).items():
                want = _then(_flat(getattr(old, part)[k]), _flat(getattr(every, part)[k]), thin)
                np.testing.assert_array_equal(_flat(v), want, err_msg=k)
        np.testing.assert_array_equal(new.log_post, pooled.draws["log_post"].reshape(-1))
        m = new.settings
        assert (m["n_iter"], m["n_burn"], m["thin"], m["appended_to"]) == (
            20, 0, thin, old.model_sha256)  # fmt: skip
        assert (m["appended_after"], m["pooled_sweeps"], m["sweeps_run"]) == (8, 52, 60)
    s = pooled.settings
    assert (s["n_iter"], s["n_burn"], s["thin"], s["appended_after"]) == (20, 0, thin, 8)
    assert (s["pooled_sweeps"], s["sweeps_run"]) == (32 + 20, 40 + 20)
    path = pooled.save(tmp_path / "p.gpmsa")
    back = gpmsa.load_study(path)
    assert back.settings == pooled.settings and back.draws["theta"].shape == (C, 13, 1)
    for k, v in back.draws.items():
        np.testing.assert_array_equal(v, pooled.draws[k])
    assert main(["info", str(path)]) == 0
    shown = capsys.readouterr().out
    assert "appended_after=8" in shown and "pooled_sweeps=52" in shown
    again = _fit(8, 6, init=back, append=True)  # a loaded appended study appended to
    s = again.settings
    assert s["appended_to"] == back.sha256 is not None
    assert (s["appended_after"], s["pooled_sweeps"], s["sweeps_run"]) == (13, 60, 68)
    np.testing.assert_array_equal(again.draws["theta"][:, :13], back.draws["theta"])


def test_an_appended_calibration_study_saves_and_loads(tmp_path):
    pooled = _calibrate(6, 5, init=_cal_source(), append=True)
    back = gpmsa.load_study(pooled.save(tmp_path / "c.gpmsa"))
    assert back.settings == pooled.settings and back.draws["lam"].shape == (C, 26, 1)
    edited = dict(pooled.settings, appended_after=19)  # the counts are checked
    with pytest.raises(gpmsa.GPMSAError, match="after appended_after=19, but the draws have 26"):
        gpmsa.Study(pooled.kind, pooled.members, pooled.layout, pooled.hyper, pooled.draws,
                    edited).save(tmp_path / "d.gpmsa")  # fmt: skip


def test_what_cannot_be_appended_is_refused_naming_the_argument():
    cal, fit = _cal_source(), _fit_source()
    refused = {
        "pass init=that study": (_calibrate, {"append": True}),
        "n_burn must be 0 or None, got 2": (_calibrate, {"init": cal, "n_burn": 2}),
        "append must be True or False": (_calibrate, {"init": cal, "append": "yes"}),
        "pass tune=False": (_calibrate, {"init": cal, "tune": True}),
        "pass n_chains=2": (_calibrate, {"init": cal, "n_chains": 3}),
        "x 8 sweeps: pass n_keep=4": (_fit, {"init": fit, "n_keep": 16}),
        "n_iter=3 keeps none; pass n_iter >= 4": (_fit, {"init": fit, "n_iter": 3}),
        "init=study is a calibration study": (_fit, {"init": cal}),
    }
    for message, (run, kw) in refused.items():
        args = {"append": True, **kw}
        n = args.pop("n_iter", 8)
        with pytest.raises(gpmsa.GPMSAError, match=message):
            run(n, 1, **args)
    assert _fit(8, 1, init=fit, append=True, n_keep=4).draws["theta"].shape == (C, 10, 1)


def test_the_memory_check_counts_an_appended_studys_pooled_draws(monkeypatch):
    """The draws pooled with the source's are counted before sampling, as gpmsa.fit counts an
    appended fit's (session 67's review: the study's check left them out)."""
    import gpmsa.studies.run as run

    cal_source, fit_source = _cal_source(), _fit_source()  # sampled before the check is watched
    seen = []
    monkeypatch.setattr(run, "check_memory", lambda nbytes, what: seen.append((nbytes, what)))
    _calibrate(6, 2, init=cal_source, tune=False)
    _calibrate(6, 2, init=cal_source, tune=False, append=True)
    _fit(8, 2, init=fit_source, tune=False, append=True)
    (plain, _), (pooled, what), (fitted, fit_what) = seen
    assert pooled > plain and "appending to 26 draws a chain" in what  # 20 + 6 at step 1
    assert "appending to 10 draws a chain" in fit_what  # 8 + 8 // 4
