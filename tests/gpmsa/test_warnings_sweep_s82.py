"""gpmsa's warnings as a user meets them: each points at the user's call (not at a line inside
gpmsa, nor dataclasses.py) and has a category of gpmsa's own, so that a filter on it catches
gpmsa's warning and nothing else (each still a UserWarning, or a RuntimeWarning where it was
one, so that existing filters and ``pytest.warns`` catches keep working)."""

import dataclasses
import warnings
from concurrent.futures import Executor, Future, ThreadPoolExecutor

import matplotlib
import numpy as np
import pytest
from _calib_cases import road_emulator, road_obs, with_draws
from test_calib_grid_posterior import peaks_data, symmetric_two_param_emulator

import gpmsa
from gpmsa.fitting import fit as fit_module

matplotlib.use("Agg")


def caught(call) -> list[warnings.WarningMessage]:
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        call()
    return got


def sites(got) -> set[tuple[str, str]]:
    return {(w.category.__name__, w.filename) for w in got}


def test_a_prediction_plots_few_realizations_warning_points_at_the_users_call():
    emu = with_draws(road_emulator(), 2)
    x, y = road_obs()
    post = gpmsa.Calibrator(emu).update(x, y)
    obs = gpmsa.ObsData(x=np.array(x), y=np.array(y))
    pred = gpmsa.full_prediction(emu, obs, x, posterior=post, n_draws=2, seed=0)
    got = caught(lambda: gpmsa.plots.prediction_bands(pred))
    assert sites(got) == {("FewDrawsWarning", __file__)}, [(w.filename, w.lineno) for w in got]
    assert "draw more (full_prediction's n_draws or n_rlz)" in str(got[0].message)
    got = caught(lambda: pred.interval("y"))
    assert sites(got) == {("FewDrawsWarning", __file__)}
    assert issubclass(gpmsa.FewDrawsWarning, UserWarning)


def test_a_calibrator_updates_outside_warning_points_at_the_users_call():
    emu = road_emulator()
    x, y = road_obs()
    far = [[y[0][0] * 50]]
    for call in (
        lambda: gpmsa.Calibrator(emu).update(x, far),
        lambda: gpmsa.Calibrator(emu).log_likelihood_grid(x, far),
    ):
        got = caught(call)
        assert sites(got) == {("OutsideEmulatorWarning", __file__)}, [
            (w.filename, w.lineno) for w in got
        ]


def test_the_grid_warnings_have_a_class_of_their_own():
    got = caught(lambda: gpmsa.Calibrator(symmetric_two_param_emulator()).update(*peaks_data()))
    assert sites(got) == {("GridResolutionWarning", __file__)}
    assert "does not resolve the posterior of a" in str(got[0].message)
    assert issubclass(gpmsa.GridResolutionWarning, UserWarning)
    narrow = road_emulator().with_calibration_priors(theta_sd=1e-150)
    got = caught(lambda: gpmsa.Calibrator(narrow).update(*road_obs()))
    assert sites(got) == {("GridResolutionWarning", __file__)}
    cal = gpmsa.Calibrator(road_emulator())
    prior = -0.5 * ((cal.theta_grid - 400.0) / 0.01) ** 2
    got = caught(lambda: cal.update(*road_obs(), prior=prior))
    assert sites(got) == {("GridResolutionWarning", __file__)}
    assert "prior= given on the grid is narrower" in str(got[0].message)


def test_an_unused_hyperprior_setting_warns_at_the_users_line_also_through_replace():
    got = caught(lambda: gpmsa.HyperPriors(lam_a=2.0))
    assert sites(got) == {("UnusedSettingWarning", __file__)}
    got = caught(lambda: dataclasses.replace(gpmsa.HyperPriors(), lam_b=1.0))
    assert sites(got) == {("UnusedSettingWarning", __file__)}, [(w.filename, w.lineno) for w in got]
    assert issubclass(gpmsa.UnusedSettingWarning, UserWarning)


class _LosesTheFirstChain(Executor):
    """An executor whose first task's worker is lost (as a cluster's may be)."""

    def __init__(self):
        self.pool, self.calls = ThreadPoolExecutor(2), 0

    def submit(self, fn, /, *args, **kwargs):
        self.calls += 1
        if self.calls == 1:
            lost = Future()
            lost.set_exception(OSError("worker lost"))
            return lost
        return self.pool.submit(fn, *args, **kwargs)

    def shutdown(self, wait=True, **kwargs):
        self.pool.shutdown(wait)


def test_a_retried_chains_warning_points_at_the_fit_and_is_gpmsas():
    rng = np.random.default_rng(0)
    x, t = rng.uniform(size=(20, 1)), rng.uniform(size=(20, 1))
    sim = gpmsa.SimData(x=x, t=t, y=np.sin(3 * x) + t)
    executor = _LosesTheFirstChain()
    got = caught(lambda: gpmsa.fit(sim, n_iter=10, tune=False, seed=1, n_chains=2,
                                   executor=executor))  # fmt: skip
    executor.shutdown()
    retry = [w for w in got if "running it again" in str(w.message)]
    assert sites(retry) == {("ChainRetryWarning", __file__)}, [(w.filename, w.lineno) for w in got]
    assert issubclass(gpmsa.ChainRetryWarning, RuntimeWarning)


@pytest.mark.filterwarnings("ignore::gpmsa.ConvergenceWarning")
def test_a_fit_whose_point_estimate_does_not_factor_warns_with_a_class_of_gpmsa(monkeypatch):
    real = fit_module.point_estimate

    def beyond_float64(*args):
        lam = np.array([1e16])
        return {**real(*args), "betaU": np.full((2, 1), 0.01), "lamUz": np.ones(1),
                "lamWs": lam, "lamWOs": lam}  # fmt: skip

    monkeypatch.setattr(fit_module, "point_estimate", beyond_float64)
    rng = np.random.default_rng(0)
    x, t = rng.random((100, 1)), rng.random((100, 1))
    got = caught(lambda: gpmsa.fit(gpmsa.SimData(x=x, t=t, y=x + t), n_iter=5, tune=False,
                                   seed=0))  # fmt: skip
    bad = [w for w in got if "refuse this emulator" in str(w.message)]
    assert sites(bad) == {("NuggetWarning", __file__)}
    assert issubclass(gpmsa.NuggetWarning, UserWarning)


def _warn_categories() -> list[tuple[str, int, str]]:
    """(file, line, category expression) of every ``warnings.warn`` call in gpmsa's source."""
    import ast
    from pathlib import Path

    root = Path(gpmsa.__file__).parent
    out = []
    for path in sorted(root.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            func = getattr(node, "func", None)
            if not (isinstance(func, ast.Attribute) and func.attr == "warn"
                    and getattr(func.value, "id", None) == "warnings"):  # fmt: skip
                continue
            cat = node.args[1] if len(node.args) > 1 else next(
                (k.value for k in node.keywords if k.arg == "category"), None)  # fmt: skip
            out.append((path.name, node.lineno, "UserWarning" if cat is None else ast.unparse(cat)))
    return out


def test_every_gpmsa_warning_derives_from_gpmsa_warning_and_keeps_its_builtin_base():
    classes = [c for c in vars(gpmsa.errors).values()
               if isinstance(c, type) and issubclass(c, Warning)]  # fmt: skip
    assert len(classes) >= 14
    for cls in classes:
        assert issubclass(cls, gpmsa.GPMSAWarning), cls
        if cls is not gpmsa.GPMSAWarning:
            assert issubclass(cls, UserWarning | RuntimeWarning), cls
    assert issubclass(gpmsa.ChainRetryWarning, RuntimeWarning)
    calls = _warn_categories()
    assert len(calls) >= 20
    for name, line, cat in calls:
        if cat == "w.category":  # a study re-issues a member's caught gpmsa warning
            continue
        assert issubclass(getattr(gpmsa.errors, cat, Warning), gpmsa.GPMSAWarning), (name, line)


def test_one_filter_on_gpmsa_warning_turns_a_fits_warning_into_an_error():
    t = np.linspace(0, 1, 12)[:, None]
    y = np.sin(3 * t[:, 0])[:, None]
    y[4] = -999.0  # a missing-value code: OutlierRunWarning before sampling
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        warnings.filterwarnings("error", category=gpmsa.GPMSAWarning)
        with pytest.raises(gpmsa.OutlierRunWarning):
            gpmsa.fit(gpmsa.SimData(t=t, y=y), n_iter=20, seed=0)
