"""After the fit, at the edges: LOO with a mean basis, saving over a study's files, the draws that
n_draws picks, studies' seeds, sensitivity bars and memory, long file names, calibrated
extrapolation, plot name lists and FullPrediction's ``what``."""

from __future__ import annotations

import tracemalloc
import warnings

import numpy as np
import pytest
from scipy.linalg import solve

import gpmsa
from gpmsa.errors import GPMSAError, ResourceLimitError
from gpmsa.io.atomic import atomic_write
from gpmsa.model.correlation import correlation
from gpmsa.model.data import evenly_spaced
from gpmsa.predictive.calibrated import calibrated_predict
from gpmsa.predictive.full import FullPrediction
from gpmsa.predictive.sobol import Sensitivity, _memory_estimate
from tests.gpmsa import _study_cases as sc
from tests.gpmsa._emulator_edit import replaced
from tests.gpmsa._predict_cases import three_input_emulator


def _functional_emulator(mean_basis) -> gpmsa.Emulator:
    """A small functional-output emulator (l_sim 6, p_u 2) at fixed parameters."""
    rng = np.random.default_rng(7)
    x, t = rng.uniform(size=(18, 1)), rng.uniform(size=(18, 1))
    s = np.linspace(0.0, 1.0, 6)
    y = np.sin(3.0 * x) * (1.0 + s) + np.outer(t[:, 0] ** 2, s) + 2.0 * x
    data = gpmsa.SimData(x=x, t=t, y=y, index=s, x_names=["x"], t_names=["t"])
    params = {"betaU": [[2.0, 1.0], [0.5, 3.0]], "lamUz": [1.0, 2.0], "lamWs": [200.0, 50.0],
              "lamWOs": [300.0]}  # fmt: skip
    return gpmsa.Emulator.from_params(data, params, n_pc=2, mean_basis=mean_basis)


def _refit_without(emu: gpmsa.Emulator, j: int, i: int) -> tuple[float, float]:
    """Mean and variance of weight j of run i from the GP (and its GLS mean, refitted) of the
    other runs, at the same parameters: the brute-force leave-one-out."""
    prm, zt, w = emu.params, emu.zt, emu.w[:, j]
    S = correlation(zt, None, prm["betaU"][:, j]) / prm["lamUz"][j]
    S[np.diag_indices(emu.m)] += 1 / (emu.lam_sim[j] * prm["lamWOs"][0]) + 1 / prm["lamWs"][j]
    k = np.arange(emu.m) != i
    Sk, r, wk = S[np.ix_(k, k)], S[i, k], w[k]
    mean, var = r @ solve(Sk, wk), S[i, i] - r @ solve(Sk, r)
    if emu.mean_basis is not None:
        H = emu.mean_basis.matrix(zt)
        M = H[k].T @ solve(Sk, H[k])
        c = solve(M, H[k].T @ solve(Sk, wk))
        g = H[i] - H[k].T @ solve(Sk, r)
        mean, var = H[i] @ c + r @ solve(Sk, wk - H[k] @ c), var + g @ solve(M, g)
    return mean, var


@pytest.mark.parametrize("mean_basis", [None, "constant", "linear"])
def test_loo_equals_refits_without_each_run(mean_basis):
    """With a mean basis, loo() used diag(S^-1) and not the projected precision: its means and
    variances were not those of the GLS refitted without the run (off by 4 % and 11 %)."""
    emu = _functional_emulator(mean_basis)
    loo = emu.loo()
    mean_w, var_w = np.zeros((emu.m, emu.p_u)), np.zeros((emu.m, emu.p_u))
    for j in range(emu.p_u):
        for i in range(emu.m):
            mean_w[i, j], var_w[i, j] = _refit_without(emu, j, i)
    s = emu.standardizer
    mean = s.y_from_std(mean_w @ emu.K.T)
    # the outputs: the weights' own variance (w-hat's, less its projection noise) through K,
    # plus the residual once (test_predict_crossval checks this against output-space solves)
    lam = emu.params["lamWOs"][0]
    var = s.var_from_std((var_w - 1.0 / (emu.lam_sim * lam)) @ (emu.K**2).T + 1.0 / lam)
    np.testing.assert_allclose(loo.mean, mean, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(loo.var, var, rtol=1e-9)


def test_cross_validate_with_a_mean_basis_equals_loo():
    """cross_validate refused a mean basis (pointing to loo()); it now takes it, its
    leave-one-out at the point estimate equal to loo() (functional output, p_u = 2)."""
    emu = _functional_emulator("linear")
    cv, loo = gpmsa.cross_validate(emu, draws=False), emu.loo()
    np.testing.assert_allclose(cv.mean, loo.mean, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(cv.var, loo.var, rtol=1e-10)


@pytest.fixture(scope="module")
def saved_study(tmp_path_factory):
    rng = np.random.default_rng(0)
    x, y = sc.observations(0.5, 4, 0.05, rng)
    emu = sc.emulator()
    study = gpmsa.calibrate_study([emu, emu], [x, x], [y, y], shared=["t"], n_samples=150,
                                  n_burn=50, seed=1, tune_rounds=3)  # fmt: skip
    return study.save(tmp_path_factory.mktemp("study") / "s.gpmsa")


def test_emulator_save_refuses_a_study_file(saved_study):
    """Emulator.save wrote over a study file, which then no longer loaded."""
    emu = sc.emulator()
    before = {p.name: p.read_bytes() for p in saved_study.parent.iterdir()}
    with pytest.raises(GPMSAError, match=r"refusing to write .*s\.gpmsa: it holds a study file, "
                                         r"which an emulator file would replace"):  # fmt: skip
        emu.save(saved_study)
    assert {p.name: p.read_bytes() for p in saved_study.parent.iterdir()} == before
    assert gpmsa.load_study(saved_study).labels == ("model0", "model1")


def test_emulator_save_refuses_a_study_file_of_a_newer_schema(saved_study, tmp_path):
    """A study this version cannot read (written by a newer gpmsa) is still a study: an
    emulator saved there replaced it (the kind came from the full manifest check, which
    refuses a newer schema)."""
    import json
    import zipfile

    newer = tmp_path / "newer.gpmsa"
    with zipfile.ZipFile(saved_study) as src, zipfile.ZipFile(newer, "w") as dst:
        for name in src.namelist():
            data = src.read(name)
            if name == "manifest.json":
                manifest = json.loads(data)
                manifest["schema_version"] += 1
                data = json.dumps(manifest).encode()
            dst.writestr(name, data)
    with pytest.raises(GPMSAError, match="newer than this library reads"):
        gpmsa.load_study(newer)
    before = newer.read_bytes()
    with pytest.raises(GPMSAError, match=r"it holds a study file, which an emulator file"):
        sc.emulator().save(newer)
    assert newer.read_bytes() == before


def test_emulator_save_still_replaces_an_emulator_file(tmp_path):
    """As documented: an emulator file (a study's model file too) is replaced."""
    emu = sc.emulator()
    path = tmp_path / "emu.gpmsa"
    emu.save(path)
    emu.save(path)
    assert gpmsa.load(path).m == emu.m


def _with_draws(scales) -> gpmsa.Emulator:
    emu = gpmsa.Emulator.from_params(sc.sim_data(), sc.PARAMS)
    draws = {k: np.stack([np.asarray(v) * f for f in scales]) for k, v in emu.params.items()}
    return replaced(emu, draws=draws, log_post=np.zeros(len(scales)))


def test_n_draws_picks_the_same_draws_everywhere():
    """Emulator.predict and calibrated_predict took floor(linspace) and the predictive module
    round(linspace): n_draws=4 of 5 draws were [0, 1, 2, 4] in one, [0, 1, 3, 4] in the other."""
    emu = _with_draws([0.5, 0.8, 1.0, 1.5, 3.0])
    assert list(evenly_spaced(5, 4)) == [0, 1, 3, 4]
    x, t = [[0.3]], [[0.4]]
    pred = gpmsa.emulator_prediction(emu, x, t, n_draws=4, seed=0)
    assert list(pred.draw_index) == [0, 1, 3, 4]
    mean, var = emu.predict(x, t, draws=True, n_draws=4)
    np.testing.assert_allclose(mean, pred.mean(), rtol=1e-12)
    np.testing.assert_allclose(var, pred.var(), rtol=1e-12)
    theta = np.array([0.1, 0.3, 0.5, 0.7, 0.9])
    cal = calibrated_predict(emu, gpmsa.Posterior({"t": theta}), [[0.4]], n_theta=4)
    expect = [emu.predict([[0.4]], [[th]])[0][0, 0] for th in theta[[0, 1, 3, 4]]]
    np.testing.assert_allclose(cal.comp_mean[:, 0, 0], expect, rtol=1e-12)


def test_studies_record_the_seed_they_ran_with():
    """calibrate_study and fit_study with seed=None recorded None: a run could not be repeated."""
    rng = np.random.default_rng(0)
    x, y = sc.observations(0.5, 4, 0.05, rng)
    emu = sc.emulator()
    kw = {"shared": ["t"], "n_samples": 80, "n_burn": 20, "tune_rounds": 3}
    first = gpmsa.calibrate_study([emu, emu], [x, x], [y, y], **kw)
    seed = first.settings["seed"]
    assert isinstance(seed, int)
    again = gpmsa.calibrate_study([emu, emu], [x, x], [y, y], seed=seed, **kw)
    assert np.array_equal(first.draws["theta"], again.draws["theta"])
    obs = [gpmsa.ObsData(x=[[0.5]], y=[[1.0]]), gpmsa.ObsData(x=[[0.2]], y=[[0.3]])]
    sim = sc.sim_data()
    fitted = gpmsa.fit_study([sim, sim], obs, shared=["t"], n_iter=60, tune_rounds=2)
    seed = fitted.settings["seed"]
    assert isinstance(seed, int)
    assert [m.settings["seed"] for m in fitted.members] == [seed, seed]


def _sensitivity(main: np.ndarray) -> Sensitivity:
    S, d = main.shape
    per = main[:, None, :]
    return Sensitivity(names=tuple("ab"[:d]), bounds={}, fixed={}, draw_index=np.arange(S),
                       grid=np.zeros(1), main=per, total=per, main_pc=per, total_pc=per,
                       main_aggregated=main, total_aggregated=main, variance=np.ones((S, 1)),
                       mean=np.ones((S, 1)))  # fmt: skip


def test_sensitivity_bars_draw_the_interval_when_the_mean_lies_outside_it():
    """yerr = [mean - lo, hi - mean] was negative for a skewed spread (mean outside the
    interval) and matplotlib refused it."""
    main = np.array([[0.0, 0.1], [0.0, 0.1], [0.0, 0.1], [0.0, 0.1], [1.0, 0.1]])
    fig = gpmsa.plots.sensitivity_bars(_sensitivity(main), level=0.1)
    ax = fig.axes[0]
    lo, hi = np.quantile(main, [0.45, 0.55], axis=0)
    assert [p.get_height() for p in ax.patches][:2] == pytest.approx(main.mean(axis=0))
    segments = ax.containers[1][2][0].get_segments()  # the main effect's error bars
    np.testing.assert_allclose([s[:, 1] for s in segments], np.column_stack([lo, hi]))


def test_sensitivity_checks_its_memory_before_allocating(monkeypatch):
    """sensitivity() allocated its pairwise m x m integrals without gpmsa.limits; the estimate
    it is now checked against bounds the memory it takes."""
    emu = three_input_emulator()
    need = _memory_estimate(150, 3, 1, 1, 1)
    monkeypatch.setattr(gpmsa.limits, "MAX_MEMORY_BYTES", need - 1)
    with pytest.raises(
        ResourceLimitError,
        match=r"sensitivity\(\) of an emulator of 150 runs "
        r"x 1 basis components over 3 varied inputs",
    ):
        gpmsa.sensitivity(emu, draws=False)
    monkeypatch.setattr(gpmsa.limits, "MAX_MEMORY_BYTES", need)
    tracemalloc.start()
    try:
        gpmsa.sensitivity(emu, draws=False)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < need


def test_a_file_name_too_long_is_refused_naming_it(tmp_path):
    """A 306-byte file name gave a bare OSError from Path.is_symlink inside atomic_group."""
    path = tmp_path / ("a" * 300 + ".gpmsa")
    match = r"a\.gpmsa: cannot write \(.*the file name is 306 bytes, the file system allows"
    with pytest.raises(GPMSAError, match=match):
        sc.emulator().save(path)
    with pytest.raises(GPMSAError, match=match), atomic_write(path) as fh:
        fh.write(b"never")
    assert list(tmp_path.iterdir()) == []


def test_calibrated_predict_extrapolates_as_far_as_asked():
    """extrapolate=True allowed x_new only 10 % beyond the domain (Emulator.predict refused
    beyond, without naming x_new); the docstring allows it, as gpmsa.calibrate does x_obs."""
    emu = sc.emulator()
    post = gpmsa.Posterior({"t": np.linspace(0.3, 0.7, 20)})
    with pytest.warns(UserWarning, match=r"x_new x=1\.3 lies outside"):
        far = calibrated_predict(emu, post, [[1.3]], extrapolate=True)
    assert np.all(np.isfinite(far.mean)) and np.all(far.var > 0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        near = calibrated_predict(emu, post, [[1.0999999]], extrapolate=True)  # predict's rule
        past = calibrated_predict(emu, post, [[1.1000001]], extrapolate=True)  # beyond it
    np.testing.assert_allclose(past.mean, near.mean, rtol=1e-5)
    np.testing.assert_allclose(past.var, near.var, rtol=1e-5)
    with pytest.raises(GPMSAError, match=r"x_new x=1\.3 lies outside .*extrapolate=True"):
        calibrated_predict(emu, post, [[1.3]])


def test_calibrated_predict_refuses_a_new_observation_without_its_discrepancy():
    """noise=True on a posterior with discrepancy draws (calibrate(..., discrepancy=...), a joint
    fit's, a study member's) gave the emulator plus 1/lamOs: a new observation's predictive
    silently without the fitted discrepancy. The simulator output (noise=False) stays."""
    emu = sc.emulator()
    n = 20
    post = gpmsa.Posterior({"t": np.linspace(0.3, 0.7, n), "lamOs": np.full(n, 400.0),
                            "betaV": np.full(n, 0.5), "lamVz": np.full(n, 10.0)})  # fmt: skip
    with pytest.raises(GPMSAError, match=r"discrepancy .*gpmsa\.full_prediction"):
        calibrated_predict(emu, post, [[0.5]], noise=True)
    eta = calibrated_predict(emu, post, [[0.5]])
    assert np.all(np.isfinite(eta.mean)) and np.all(eta.var > 0)


@pytest.mark.parametrize(
    ("plot", "names", "match"),
    [
        ("traces", 3, r"names must be a parameter name \(str\) or a sequence of names, got 3"),
        ("theta_pairs", 0.5, r"names must be a parameter name \(str\) or a sequence of names"),
        ("traces", [1], r"names must hold parameter names \(str\), got 1 \(int\)"),
        ("theta_pairs", ["a", None], r"names must hold parameter names \(str\), got None"),
    ],
)
def test_plot_names_that_are_not_strings_are_refused(plot, names, match):
    """traces(names=3) and theta_pairs(names=0.5) raised TypeError: 'int' object is not
    iterable."""
    post = gpmsa.Posterior({"a": np.arange(20.0), "b": np.arange(20.0) ** 2})
    with pytest.raises(GPMSAError, match=match):
        getattr(gpmsa.plots, plot)(post, names=names)


def test_full_prediction_what_must_be_one_string():
    """mean/var/interval(what=<array>) raised numpy's 'truth value of an array is ambiguous'
    (or, for a 1-element array, took it as the string)."""
    z = np.zeros
    fp = FullPrediction(
        x=z((1, 1)), grid=z(1), draw_index=np.arange(2), theta=z((2, 1)), lamOs=np.ones(2),
        mu=z((2, 1, 1)), cov=np.ones((2, 1, 1, 1)), u=z((2, 1, 1)), v=z((2, 1, 0)),
        eta=z((2, 1, 1)), delta=z((2, 1, 1)), y=z((2, 1, 1)), K=np.ones((1, 1)), D=z((1, 0)),
        y_mean=z(1), y_sd=1.0,
    )  # fmt: skip
    for call in (fp.mean, fp.var, fp.interval):
        for what in (np.array(["y", "eta"]), np.array(["y"]), ["y"]):
            with pytest.raises(GPMSAError, match=r"what must be one of .*\(one str\), got"):
                call(what)
    assert fp.mean("y").shape == (1, 1)
