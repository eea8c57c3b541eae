"""Regressions of the input audit: each bad input is refused with a GPMSAError naming the
problem (never a crash deep in numpy, a silently wrong result or lost data)."""

import os
import re
import warnings

import numpy as np
import pytest
from _calib_cases import road_emulator, vector_emulator
from _study_cases import PARAMS, sim_data

import gpmsa
from gpmsa import GPMSAError, Posterior
from gpmsa.calibration.calibrate import _tuning_options
from gpmsa.cli.main import main
from gpmsa.errors import EmulatorFileError
from gpmsa.fitting.validation import check_record
from gpmsa.model.basis import interpolate_basis
from gpmsa.model.data import as_float, as_real, check_flag
from gpmsa.model.problem import reduce_obs
from gpmsa.predictive.calibrated import calibrated_predict
from gpmsa.predictive.sobol import _mean_gauss
from gpmsa.studies.layout import build_layout, check_study_names
from tests.gpmsa._emulator_edit import replaced


def _functional_sim(index: np.ndarray, reverse: bool = False) -> dict:
    rng = np.random.default_rng(0)
    x, t = rng.uniform(0, 1, (30, 1)), rng.uniform(0, 1, (30, 1))
    y = x * index + np.sin(2 * t * index) + 0.5 * t + index**2
    return {"x": x, "t": t, "y": y[:, ::-1] if reverse else y, "index": index}


# --- 1: the simulation grid must be increasing ----------------------------------------------------
@pytest.mark.parametrize("order", ["descending", "unsorted", "repeated"])
def test_a_simulation_index_that_is_not_increasing_is_refused(order):
    s = np.linspace(0.0, 1.0, 12)
    index = {"descending": s[::-1], "unsorted": np.r_[s[1], s[0], s[2:]],
             "repeated": np.r_[s[0], s[:-1]]}[order]  # fmt: skip
    with pytest.raises(GPMSAError, match="index must be strictly increasing"):
        gpmsa.SimData(**_functional_sim(index))


def test_an_observation_grid_in_any_order_gives_the_same_reduced_data():
    emu = vector_emulator()
    grid = np.array([0.05, 0.3, 0.52, 0.77, 0.95])
    y = np.sin(3 * grid)[None, :]
    ob_sorted, _ = reduce_obs(gpmsa.ObsData(x=[[0.4]], y=y, index=grid), emu.standardizer,
                              emu.K, None, emu.x_names)  # fmt: skip
    back = gpmsa.ObsData(x=[[0.4]], y=y[:, ::-1], index=grid[::-1])
    ob_back, _ = reduce_obs(back, emu.standardizer, emu.K, None, emu.x_names)
    assert np.allclose(ob_back.z, ob_sorted.z, rtol=1e-12, atol=1e-12)


def test_a_prediction_grid_in_any_order_gives_the_same_values():
    post = Posterior({"t": np.full(2, 0.5), "lamOs": np.full(2, 50.0)})
    kw = {"posterior": post, "discrepancy": None, "seed": 0}
    grid = np.array([0.9, 0.1, 0.5])
    back = gpmsa.full_prediction(vector_emulator(), _vector_obs(), [[0.3]], grid=grid, **kw)
    fwd = gpmsa.full_prediction(vector_emulator(), _vector_obs(), [[0.3]], grid=grid[[1, 2, 0]],
                                **kw)  # fmt: skip
    assert np.allclose(back.mean("eta"), fwd.mean("eta")[:, [2, 0, 1]], rtol=1e-12)


def test_a_file_or_a_basis_with_a_descending_grid_is_refused():
    emu = vector_emulator()
    manifest, arrays = emu.to_record()
    arrays = {**arrays, "grid": arrays["grid"][::-1].copy(), "index": arrays["index"][::-1].copy()}
    with pytest.raises(EmulatorFileError, match="arrays/grid: must be strictly increasing"):
        check_record(manifest, arrays)
    with pytest.raises(GPMSAError, match="the simulation grid must be strictly increasing"):
        interpolate_basis(emu.K, emu.standardizer.grid[::-1], np.array([0.5]))


# --- 2: a refused or failed Study.save keeps the existing study -----------------------------------
def _study(lam_uz: float, **kw) -> gpmsa.Study:
    emu = gpmsa.Emulator.from_params(sim_data(t_name="E"), {**PARAMS, "lamUz": [lam_uz]})
    return gpmsa.calibrate_study([emu, emu], [[[0.5]], [[0.2]]], [[1.5], [1.2]], shared=["E"],
                                 n_samples=60, n_burn=10, seed=1, tune=False, **kw)  # fmt: skip


def test_calibrate_study_refuses_non_finite_metadata_up_front():
    with pytest.raises(GPMSAError, match=r"metadata\['note'\] = nan"):
        _study(1.0, metadata={"note": float("nan")})


def test_a_refused_study_save_leaves_the_existing_study_loadable(tmp_path):
    path = tmp_path / "beam.gpmsa"
    _study(1.0).save(path)
    before = gpmsa.load_study(path).posterior.mean("E")
    files = sorted(os.listdir(tmp_path))
    bad = _study(2.0)
    bad.metadata["note"] = float("nan")  # set after the run: only save can refuse it
    with pytest.raises(GPMSAError, match=r"metadata\['note'\] = nan"):
        bad.save(path)
    assert sorted(os.listdir(tmp_path)) == files  # no member replaced, no temporary left
    again = gpmsa.load_study(path)
    assert again.posterior.mean("E") == before and again.members[0].params["lamUz"][0] == 1.0


def test_a_study_save_failing_part_way_leaves_the_existing_study_loadable(tmp_path, monkeypatch):
    import gpmsa.studies.study as study_mod

    path = tmp_path / "beam.gpmsa"
    _study(1.0).save(path)
    files = sorted(os.listdir(tmp_path))
    real, calls = study_mod.write_sealed, []

    def fail_on_second(*args, **kw):  # the disk fills up while the second member is written
        calls.append(args[0])
        if len(calls) == 2:
            raise OSError("No space left on device")
        return real(*args, **kw)

    monkeypatch.setattr(study_mod, "write_sealed", fail_on_second)
    with pytest.raises(OSError, match="No space"):
        _study(2.0).save(path)
    assert sorted(os.listdir(tmp_path)) == files
    assert gpmsa.load_study(path).members[1].params["lamUz"][0] == 1.0
    monkeypatch.undo()
    _study(2.0).save(path)
    assert gpmsa.load_study(path).members[1].params["lamUz"][0] == 2.0


def test_a_study_is_not_saved_over_another_studys_model_file(tmp_path):
    """A study saved to the path of another study's model file (or whose model files would
    replace a study file) overwrote it, and the other study no longer loaded."""
    first = tmp_path / "beam.gpmsa"
    _study(1.0).save(first)
    names = sorted(os.listdir(tmp_path))
    label = gpmsa.load_study(first).labels[0]
    member = tmp_path / f"beam.{label}.gpmsa"
    assert member.exists()
    with pytest.raises(
        GPMSAError,
        match=rf"refusing to write .*beam\.{label}\.gpmsa: it holds an "
        r"emulator file \(another study's model\?\)",
    ):
        _study(2.0).save(member)
    # a study file at "x.m0.gpmsa" would be replaced by model m0 of a study saved at "x.gpmsa"
    other = tmp_path / "plate.gpmsa"
    _study(1.0).save(tmp_path / f"plate.{label}.gpmsa")
    with pytest.raises(GPMSAError, match=rf"plate\.{label}\.gpmsa: it holds a study file"):
        _study(2.0).save(other)
    assert not other.exists()
    assert gpmsa.load_study(first).members[0].params["lamUz"][0] == 1.0
    assert gpmsa.load_study(tmp_path / f"plate.{label}.gpmsa").members[0].params["lamUz"][0] == 1.0
    assert set(names) <= set(os.listdir(tmp_path))
    # saving over a study of its own kind goes on; over a file that is no gpmsa file it is
    # refused (that file's content would be lost: tests/gpmsa/test_fit_and_save_guards.py)
    _study(2.0).save(first)
    (tmp_path / "notes.gpmsa").write_text("not a zip")
    with pytest.raises(GPMSAError, match=r"notes\.gpmsa: it holds a file that is not a gpmsa"):
        _study(2.0).save(tmp_path / "notes.gpmsa")
    assert (tmp_path / "notes.gpmsa").read_text() == "not a zip"
    assert gpmsa.load_study(first).members[0].params["lamUz"][0] == 2.0


# --- 3: reserved and colliding parameter names ----------------------------------------------------
@pytest.mark.parametrize("name", ["lamOs", "lamVz", "betaV", "betaV[0]", "betaV[12]"])
def test_a_calibration_parameter_with_a_reserved_name_is_refused(name):
    match = rf"t_names: '{re.escape(name)}' is a reserved name.*lamOs, lamVz, betaV"
    with pytest.raises(GPMSAError, match=match):
        sim_data(t_name=name)


def test_calibrate_refuses_an_emulator_whose_parameter_has_a_reserved_name():
    emu = replaced(gpmsa.Emulator.from_params(sim_data(), PARAMS), t_names=("lamOs",))  # as an
    # older file could hold it
    with pytest.raises(GPMSAError, match="the emulator's t_names: 'lamOs' is a reserved name"):
        gpmsa.calibrate(emu, [[0.5]], [[1.0]], n_samples=20, n_burn=0, tune=False)


@pytest.mark.parametrize(
    ("names", "shared", "hier", "match"),
    [([("E", "E.mu"), ("E", "E.mu")], ["E.mu"], ["E"], r"several quantities \['E.mu'\]"),
     ([("E[b]",), ("E",)], [], [], r"'E\[b\]': a study's parameter names may not hold"),
     ([("lamOs[a]",), ("E",)], [], [], "may not hold")],
)  # fmt: skip
def test_a_study_refuses_names_its_posterior_would_confuse(names, shared, hier, match):
    bounds = [(np.zeros(len(n)), np.ones(len(n))) for n in names]
    layout = build_layout(("a", "b"), names, bounds, [(0.5, 10.0)] * 2, shared, hier)
    with pytest.raises(GPMSAError, match=match):
        check_study_names(layout)


# --- 4: tuning options reach the torch backend; pyro refuses them ---------------------------------
def test_tuning_options_go_to_torch_and_are_refused_by_pyro():
    assert _tuning_options("numpy", None, None) == {"tune_rounds": 50, "tune_levels": 20}
    assert _tuning_options("torch", None, None) == {}  # torch's own default rounds
    assert _tuning_options("torch", 3, 4) == {"tune_rounds": 3, "tune_levels": 4}
    with pytest.raises(GPMSAError, match="tune_rounds must be an integer"):
        _tuning_options("torch", 0, None)
    with pytest.raises(GPMSAError, match="backend 'pyro'.*takes no tune_levels="):
        _tuning_options("pyro", None, 5)
    assert _tuning_options("pyro", None, None) == {}


def test_pyro_calibrate_refuses_tuning_options():
    pytest.importorskip("pyro")
    with pytest.raises(GPMSAError, match="backend 'pyro' .* takes no tune_rounds="):
        gpmsa.calibrate(road_emulator(), [[1.25]], [[12.1]], backend="pyro", tune_rounds=3)


def test_torch_calibrate_uses_tune_rounds_and_levels():
    pytest.importorskip("torch")
    emu = road_emulator()
    kw = {"seed": 0, "n_samples": 30, "n_burn": 5, "backend": "torch"}
    a = gpmsa.calibrate(emu, [[1.25]], [[12.1]], tune_rounds=1, tune_levels=2, **kw)
    b = gpmsa.calibrate(emu, [[1.25]], [[12.1]], tune_rounds=2, tune_levels=3, **kw)
    assert a.info["step_widths"] != b.info["step_widths"]  # were identical: both ignored


# --- 5: posterior draws outside the emulator's domain, or with a bad lamOs ------------------------
def _vector_obs() -> gpmsa.ObsData:
    grid = np.linspace(0.0, 1.0, 8)
    return gpmsa.ObsData(x=[[0.4]], y=np.sin(np.pi * grid)[None, :] + 0.2, index=grid)


@pytest.mark.parametrize(
    ("theta", "lam", "match"),
    [(5.0, 1.0, "posterior theta: t reaches"), (0.5, -1.0, "lamOs draws must be finite and > 0"),
     (0.5, 0.0, r"lamOs draws must be finite and > 0 \(a precision\), got 0.0")],
)  # fmt: skip
def test_full_prediction_refuses_a_posterior_outside_the_emulator(theta, lam, match):
    post = Posterior({"t": np.full(3, theta), "lamOs": np.full(3, lam)})
    with pytest.raises(GPMSAError, match=match):
        gpmsa.full_prediction(vector_emulator(), _vector_obs(), [[0.3]], posterior=post,
                              discrepancy=None, seed=0)  # fmt: skip
    ok = Posterior({"t": np.full(3, 0.5), "lamOs": np.full(3, 50.0)})
    pred = gpmsa.full_prediction(vector_emulator(), _vector_obs(), [[0.3]], posterior=ok,
                                 discrepancy=None, seed=0)  # fmt: skip
    assert np.all(np.isfinite(pred.var("y"))) and np.all(pred.var("y") > 0)


@pytest.mark.parametrize("lam", [-1.0, 0.0, np.inf])
def test_calibrated_predict_refuses_a_lamos_that_is_not_a_precision(lam):
    post = Posterior({"GD": np.full(4, 300.0), "lamOs": np.full(4, 1.0)})
    post.samples["lamOs"][:] = lam  # Posterior refuses inf itself: set it past the check
    with pytest.raises(GPMSAError, match="lamOs draws must be finite and > 0"):
        calibrated_predict(road_emulator(), post, [[1.5]], noise=True)
    bad_theta = Posterior({"GD": np.full(4, 5000.0), "lamOs": np.ones(4)})
    with pytest.raises(GPMSAError, match="posterior theta: GD reaches"):
        calibrated_predict(road_emulator(), bad_theta, [[1.5]])


# --- 6: strings and bools are not numbers; flags are bools ---------------------------------------
@pytest.mark.parametrize(
    ("value", "shown"),
    [(["1.5", "2.5"], "str '1.5'"), ([[True], [False]], "bool True"), ([1.0, True], "bool True"),
     (np.array([True, False]), "bool True"), ([np.bool_(False), 2.0], "bool False"),
     ([1.0, None], "None"), (np.array(["1.5"]), "str '1.5'"),
     (np.array([1.0, "2"], dtype=object), "str '2'"), ("3", "str '3'")],
)  # fmt: skip
def test_as_float_refuses_strings_bools_and_none(value, shown):
    with pytest.raises(GPMSAError, match=f"v must be a numeric array, got {shown} \\(text, bools"):
        as_float(value, "v")


def test_numpy_numbers_stay_numbers():
    assert as_float([np.float32(1.5), np.int64(2), np.array(3.0)], "v").tolist() == [1.5, 2, 3]
    assert as_real(np.array(2.5), "v") == 2.5 and as_real(np.int16(4), "v") == 4.0
    assert check_flag(np.bool_(True), "f") is True
    with pytest.raises(GPMSAError, match="v must be a single number, got"):
        as_real([2.5], "v")


@pytest.mark.parametrize(
    ("call", "match"),
    [(lambda e: gpmsa.calibrate(e, [["1.25"]], [[12.1]]), "x_obs must be a numeric array"),
     (lambda e: gpmsa.calibrate(e, [[True]], [[12.1]]), "x_obs must be a numeric array"),
     (lambda e: gpmsa.calibrate(e, [[1.25]], [[12.1]], extrapolate="no"), "extrapolate must be"),
     (lambda e: gpmsa.calibrate(e, [[1.25]], [[12.1]], fast="no"), "fast must be True or False"),
     (lambda e: gpmsa.calibrate(e, [[1.25]], [[12.1]], tune="no"), "tune must be True or False"),
     (lambda e: gpmsa.emulator_prediction(e, [[1.0]], [[300.0]], draws="False"), "draws must be"),
     (lambda e: gpmsa.sensitivity(e, bounds={"GD": ("300", "400")}, draws=False),
      r"bounds\['GD'\] must be a number, got str '300'"),
     (lambda e: gpmsa.Calibrator(e).update([[1.25]], [[12.1]]).quantile("GD", True), "q must be"),
     (lambda e: gpmsa.ObsData(x=[[1.0]], y=[["12.1"]]), "y_obs must be a numeric array"),
     (lambda e: gpmsa.SimData(**{**_functional_sim(np.linspace(0, 1, 12)), "index": "3"}),
      "index must be a numeric array, got str '3'")],
)  # fmt: skip
def test_entry_points_refuse_text_and_bools_for_numbers_and_flags(call, match):
    with pytest.raises(GPMSAError, match=match):
        call(road_emulator())


# --- 7: Sobol indices of a narrow box ------------------------------------------------------------
@pytest.mark.parametrize("width", [1e-3, 1e-6, 1e-9])
def test_mean_gauss_is_exact_on_a_narrow_interval(width):
    c = np.array([0.2, 0.5, 0.9])
    a, gamma = 0.3, 4.0
    nodes, weights = np.polynomial.legendre.leggauss(40)  # the reference: a fine rule
    z = a + 0.5 * width * (nodes + 1.0)
    ref = 0.5 * weights @ np.exp(-gamma * (z[:, None] - c) ** 2)
    assert np.allclose(_mean_gauss(gamma, c, a, a + width), ref, rtol=1e-13, atol=0)


def test_sensitivity_indices_of_a_narrow_box_stay_in_the_unit_interval():
    emu = road_emulator()
    sens = gpmsa.sensitivity(emu, bounds={"GD": (300.0, 300.0 + 1e-6)}, draws=False)
    main, total = sens.main[0, 0], sens.total[0, 0]
    assert np.all((main >= 0) & (main <= 1)) and np.all((total >= 0) & (total <= 1))
    assert main[0] == pytest.approx(1.0, abs=1e-8) and main[1] == pytest.approx(0.0, abs=1e-8)


# --- 8, 9: a scalar precision; n_pc ---------------------------------------------------------------
def test_a_scalar_precision_applies_to_every_experiment():
    obs = gpmsa.ObsData(x=[[1.0], [2.0]], y=[[12.0, 1.0], [13.0, 2.0]], precision=5.0)
    assert all(np.array_equal(p, 5.0 * np.eye(2)) for p in obs.precisions)
    with pytest.raises(GPMSAError, match=r"precision\[0\] must be a numeric array, got None"):
        gpmsa.ObsData(x=[[1.0]], y=[[12.0]], precision=[None])  # said "finite, got nan"


@pytest.mark.parametrize(("n_pc", "shown"), [(2.0, "2.0"), (True, "True"), ("1", "'1'")])
def test_n_pc_must_be_an_integer(n_pc, shown):
    sim = gpmsa.SimData(**_functional_sim(np.linspace(0, 1, 12)))
    # a float below 1 is a variance fraction (SEPIA's n_pc < 1); 2.0 is neither
    with pytest.raises(GPMSAError, match=rf"n_pc must be an integer >= 1.*, got {shown}"):
        gpmsa.fit(sim, n_iter=5, tune=False, n_pc=n_pc)


# --- 10: Posterior and CalibratedPrediction arguments -------------------------------------------
@pytest.fixture(scope="module")
def posteriors():
    grid = gpmsa.Calibrator(road_emulator(), seed=0).update([[1.25]], [[12.1]])
    draws = Posterior({"GD": grid.samples["GD"], "lamOs": grid.samples["lamOs"]})
    return {"grid": grid, "draws": draws}


@pytest.mark.parametrize("kind", ["grid", "draws"])
def test_posterior_methods_name_a_bad_argument_alike_for_grid_and_draws(posteriors, kind):
    post = posteriors[kind]
    for value in ("300", None, [300.0, 400.0], [300.0]):
        with pytest.raises(GPMSAError, match="value must be"):
            post.prob_above("GD", value)
    assert post.prob_above("GD", np.array(350.0)) == post.prob_above("GD", 350.0)
    assert post.prob_above("GD", np.float32(350.0)) == post.prob_above("GD", 350.0)
    with pytest.raises(GPMSAError, match="q must be a numeric array, got str 'x'"):
        post.quantile("GD", "x")
    with pytest.raises(GPMSAError, match=r"name must be a parameter name \(str\), got \['GD'\]"):
        post.mean(["GD"])
    assert np.shape(post.quantile("GD", [0.1, 0.5])) == (2,)  # documented to vectorise


def test_calibrated_prediction_quantile_takes_one_probability(posteriors):
    pred = calibrated_predict(road_emulator(), posteriors["grid"], [[1.5], [1.0]])
    with pytest.raises(GPMSAError, match=r"q must be a single number, got \[0.1, 0.5\]"):
        pred.quantile([0.1, 0.5])
    assert pred.quantile(np.float64(0.5)).shape == (2, 1)


def test_repr_of_a_one_draw_posterior_does_not_raise():
    assert repr(Posterior({"a": [1.0]})) == "Posterior(a=1, method=?)"


# --- 11: arguments checked before use ------------------------------------------------------------
@pytest.mark.parametrize(
    ("call", "match"),
    [(lambda e, s: gpmsa.fit(s, n_iter=5, backend=["numpy"]), r"unknown backend \['numpy'\]"),
     (lambda e, s: gpmsa.calibrate(e, [[1.25]], [[12.1]], backend=["numpy"]), "unknown backend"),
     (lambda e, s: gpmsa.Calibrator(e, backend=["numpy"]), "unknown backend"),
     (lambda e, s: gpmsa.fit(s, n_iter=5, priors="x"), "priors must be a gpmsa.Priors or None"),
     (lambda e, s: gpmsa.fit(s, n_iter=5, priors={}), r"priors must be .*, got \{\}"),
     (lambda e, s: gpmsa.fit(s, n_iter=5, metadata=[1, 2]), "metadata must be None or a dict"),
     (lambda e, s: gpmsa.fit(s, n_iter=5, point=np.array(["mean", "map"])), "point must be"),
     (lambda e, s: gpmsa.Calibrator(e, emulator_params="draws", n_emulator_draws=None),
      "n_emulator_draws must be an integer >= 1, got None"),
     (lambda e, s: gpmsa.sensitivity(e, bounds="GD"), "bounds must be None or a dict"),
     (lambda e, s: gpmsa.sensitivity(e, bounds=[1, 2]), "bounds must be None or a dict"),
     (lambda e, s: gpmsa.cross_validate(e, folds=[None] * 100 + ["a"] * 98),
      "every run needs a label"),
     (lambda e, s: gpmsa.cross_validate(e, folds=np.array([1] * 100 + ["a"] * 98, dtype=object)),
      "labels must be of one kind"),
     (lambda e, s: gpmsa.load(5), "path must be a file name"),
     (lambda e, s: gpmsa.load(None), "path must be a file name"),
     (lambda e, s: gpmsa.load(b"road.gpmsa"), "path must be a file name"),
     (lambda e, s: gpmsa.load_study(None), "path must be a file name")],
)  # fmt: skip
def test_arguments_are_checked_before_use(call, match):
    sim = gpmsa.SimData(**_functional_sim(np.linspace(0, 1, 12)))
    with pytest.raises(GPMSAError, match=match):
        call(road_emulator(), sim)


def test_fit_study_and_a_string_discrepancy_basis_are_refused():
    sim = gpmsa.SimData(**_functional_sim(np.linspace(0, 1, 12)))
    obs = gpmsa.ObsData(x=[[0.5]], y=np.ones((1, 12)))
    with pytest.raises(GPMSAError, match="priors must be a gpmsa.Priors or None, got 'x'"):
        gpmsa.fit_study([sim, sim], [obs, obs], priors="x", n_iter=5)
    with pytest.raises(GPMSAError, match="discrepancy basis must be a numeric array"):
        gpmsa.fit(sim, obs, n_iter=5, discrepancy=[["a"]] * 12)


# --- 12: messages name the right thing -----------------------------------------------------------
def test_messages_name_the_argument_at_fault():
    sim = gpmsa.SimData(**_functional_sim(np.linspace(0, 1, 12)))
    obs = gpmsa.ObsData(x=[[0.5]], y=np.ones((1, 12)))
    with pytest.raises(GPMSAError, match=r"fixed\['theta'\] t0=3 lies outside"):
        gpmsa.fit(sim, obs, n_iter=5, fixed={"theta": [3.0]})
    post = Posterior({"GD": np.full(4, 300.0), "lamOs": np.ones(4)})
    with pytest.raises(GPMSAError, match="x_new v=3 lies outside"):
        calibrated_predict(road_emulator(), post, [[3.0]])
    case = _functional_sim(np.linspace(0, 1, 12))
    case["x"][:2, 0] = -1e308, 1e308
    with pytest.raises(GPMSAError, match=r"design column x\[:, 0\] spans .* overflows float64"):
        gpmsa.SimData(**case)
    tiny = _functional_sim(np.linspace(0, 1, 12))
    tiny["y"] = tiny["y"] * 1e-300
    with pytest.raises(GPMSAError, match="y's spread .* is too small to standardise"):
        gpmsa.SimData(**tiny)


def test_a_prior_whose_bounds_exclude_the_start_starts_inside_them_or_is_named():
    """GPM/SA's start lamUz = 1 outside the prior's bounds (0.3, 0.31): the chain starts inside
    them (session 67; refused before); a start the user gives there is still refused by name."""
    sim = gpmsa.SimData(**_functional_sim(np.linspace(0, 1, 12)))
    priors = gpmsa.Priors(lamUz=gpmsa.GammaPrior(5.0, 5.0, 0.3, 0.31))
    emu = gpmsa.fit(sim, n_iter=5, tune=False, priors=priors, seed=0)
    assert np.all((emu.draws["lamUz"] > 0.3) & (emu.draws["lamUz"] < 0.31))
    start = {"lamUz": np.ones(emu.draws["lamUz"].shape[1])}
    with pytest.raises(GPMSAError, match=r"start lamUz = \[1.0.*bounds \(0.3, 0.31\) of Priors"):
        gpmsa.fit(sim, n_iter=5, tune=False, priors=priors, init=start)


# --- 13, 14: the CLI's NAME=VALUE; metadata tuples ----------------------------------------------
def test_cli_takes_an_input_name_holding_an_equals_sign(tmp_path, capsys):
    case = _functional_sim(np.linspace(0, 1, 12))
    sim = gpmsa.SimData(x=case["x"], t=case["t"], y=case["y"][:, 3], x_names=["v=w"],
                        t_names=["k"], y_names=["f"])  # fmt: skip
    prm = {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [1e4], "lamWOs": [1e4]}
    path = gpmsa.Emulator.from_params(sim, prm).save(tmp_path / "eq.gpmsa")
    y = float(case["y"][0, 3])
    assert main(["calibrate", str(path), "--x", "v=w=0.5", "--y", f"f={y}", "--json"]) == 0
    assert '"v=w": 0.5' in capsys.readouterr().out


def test_metadata_tuples_come_back_as_lists(tmp_path):
    emu = gpmsa.Emulator.from_params(sim_data(), PARAMS, metadata={"pair": (1, 2), "n": 3})
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        back = gpmsa.load(emu.save(tmp_path / "m.gpmsa"))
    assert back.metadata == {"pair": [1, 2], "n": 3}  # as docs/emulator-file.md says
