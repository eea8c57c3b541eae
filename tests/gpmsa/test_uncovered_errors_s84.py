"""Error paths of the public API that no test ran before session 84 (a branch-coverage run of
the whole suite): each is reached through the public API and its exception's type and message
checked. One was a defect: a discrepancy basis given as one array of no columns was refused as
"all zeros" (the per-experiment list said "has no columns")."""

import warnings

import numpy as np
import pytest

import gpmsa
from gpmsa.calibration.posterior import LevelMarginal
from gpmsa.plots.emulator import emulator_fit
from gpmsa.plots.prediction import prediction_bands
from gpmsa.plots.sensitivity import main_effect_curves
from tests.gpmsa._study_cases import emulator, observations, sim_data
from tests.gpmsa.test_discrepancy_groups_s61 import BASIS, _data


@pytest.fixture(autouse=True)
def _quiet():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the toys' short chains are not converged
        yield


def _obs():
    return observations(0.4, 3, 0.03, np.random.default_rng(0))


def _fit(**kw):
    return gpmsa.fit(sim_data(), n_iter=3, tune=False, seed=0, **kw)


# --- the defect ----------------------------------------------------------------------------------
def test_a_discrepancy_array_of_no_columns_says_so_not_all_zeros():
    """Before: "discrepancy basis is all zeros" for a (l, 0) basis, which has no values at all;
    the per-experiment list already said "has no columns"."""
    data, obs = _data()
    with pytest.raises(gpmsa.GPMSAError, match="discrepancy basis has no columns: give at least"):
        gpmsa.fit(data, obs, n_iter=3, tune=False, discrepancy=np.ones((10, 0)))
    with pytest.raises(gpmsa.GPMSAError, match=r"discrepancy\[0\] .* has no columns"):
        gpmsa.fit(data, obs, n_iter=3, tune=False, discrepancy=[np.ones((10, 0))] * 5)
    with pytest.raises(gpmsa.GPMSAError, match="discrepancy basis is all zeros"):  # still
        gpmsa.fit(data, obs, n_iter=3, tune=False, discrepancy=np.zeros((10, 2)))


def test_a_non_finite_discrepancy_basis_is_refused():
    data, obs = _data()
    basis = BASIS.copy()
    basis[0, 0] = np.nan
    with pytest.raises(gpmsa.GPMSAError, match="discrepancy basis must be finite"):
        gpmsa.fit(data, obs, n_iter=3, tune=False, discrepancy=basis)


# --- fit ------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"fixed": [1]}, r"fixed must be None or a dict name -> value, got \[1\]"),
        ({"fixed": {"lamUz": float("nan")}}, r"fixed\['lamUz'\] must be finite, got \[nan\]"),
        ({"obs": 5}, "obs must be a gpmsa.ObsData or None, got int"),
        ({"discrepancy_groups": [0]}, "discrepancy_groups needs a discrepancy basis"),
        ({"n_pc": 2}, "n_pc must be 1 for a scalar output, got 2"),
        ({"mean_basis": 5}, "mean_basis must be None, one of .* or a callable, got 5"),
        ({"mean_basis": lambda z: np.ones((len(z), 40))}, "40 columns; it needs fewer than the 35"),
        ({"mean_basis": lambda z: np.ones((len(z), 2))}, "mean basis is collinear .* rank 1"),
    ],
)
def test_fit_refuses_bad_settings_by_name(kw, match):
    with pytest.raises(gpmsa.GPMSAError, match=match):
        _fit(**kw)


def test_a_failing_mean_basis_callable_is_named():
    def boom(z):
        raise RuntimeError("boom")

    with pytest.raises(gpmsa.GPMSAError, match=r"mean_basis callable failed .*: boom"):
        _fit(mean_basis=boom)


def test_metadata_nested_too_deep_is_refused():
    deep: dict = {}
    inner = deep
    for _ in range(70):
        inner["a"] = {}
        inner = inner["a"]
    with pytest.raises(gpmsa.GPMSAError, match="nests deeper than 64 levels"):
        _fit(metadata=deep)


def test_theta_summary_of_a_simulator_only_fit_says_why():
    with pytest.raises(gpmsa.GPMSAError, match="no calibration draws: fit was run without obs="):
        emulator().theta_summary()


def test_simdata_refuses_bad_names_and_categorical_specs():
    data = sim_data()
    x, t, y = data.x, data.t, data.y
    with pytest.raises(gpmsa.GPMSAError, match="y_names must be unique"):
        gpmsa.SimData(x=x, t=t, y=np.hstack([y, 2 * y]), y_names=["a", "a"])
    with pytest.raises(gpmsa.GPMSAError, match="'zz' is not an input; the inputs are"):
        gpmsa.SimData(x=x, t=t, y=y, x_names=["x"], x_categorical=["zz"])
    with pytest.raises(gpmsa.GPMSAError, match="must hold column indices or names, got 1.5"):
        gpmsa.SimData(x=x, t=t, y=y, x_categorical=[1.5])


def test_obsdata_refuses_a_3d_y_and_an_empty_experiment():
    with pytest.raises(gpmsa.GPMSAError, match=r"y_obs must be \(n, l_obs\) .* got \(2, 2, 2\)"):
        gpmsa.ObsData(x=np.zeros((2, 1)), y=np.zeros((2, 2, 2)))
    with pytest.raises(gpmsa.GPMSAError, match=r"y_obs\[1\] is empty"):
        gpmsa.ObsData(y=[[1.0, 2.0], []], index=[[0.0, 1.0], []])


# --- calibrate, Calibrator -----------------------------------------------------------------------
@pytest.mark.parametrize(
    ("kw", "kind", "match"),
    [
        ({"log_prior": 5}, gpmsa.GPMSAError, "log_prior must be a callable of native theta"),
        ({"log_prior": lambda th: "abc"}, gpmsa.ChainError, "log_prior must return real log"),
        ({"emulator_params": "bad"}, gpmsa.GPMSAError, r"one of \('point', 'draws'\), got 'bad'"),
        ({"constraint": 5}, gpmsa.GPMSAError, "constraint must be a callable of native theta"),
        ({"constraint": lambda th: 1.0}, gpmsa.GPMSAError, "must return True or False, got 1.0"),
        (
            {"log_prior": lambda th: 0.0, "discrepancy": np.ones((1, 1))},
            gpmsa.GPMSAError,
            r"needs the fast numpy sampler.*got discrepancy=an array of shape \(1, 1\)",
        ),
    ],
)
def test_calibrate_refuses_bad_options_by_name(kw, kind, match):
    x, y = _obs()
    with pytest.raises(kind, match=match):
        gpmsa.calibrate(emulator(), x, y, n_samples=10, n_burn=5, **kw)


def test_a_calibrator_prior_of_the_wrong_length_is_refused():
    x, y = _obs()
    with pytest.raises(gpmsa.GPMSAError, match=r"one log density per node \(\d+\), got 3"):
        gpmsa.Calibrator(emulator()).update(x, y, prior=lambda th: np.zeros(3))


def test_priors_refuse_a_non_dict_and_an_unknown_name():
    with pytest.raises(gpmsa.GPMSAError, match="Priors.from_dict needs a dict, got list"):
        gpmsa.Priors.from_dict([1])
    with pytest.raises(gpmsa.GPMSAError, match="unknown parameter name 'zz'"):
        gpmsa.Priors().log_prior("zz", 1.0)


def test_level_marginal_checks_and_repr():
    lm = LevelMarginal.from_probabilities([0, 1, 2], [0.2, 0.3, 0.5])
    assert repr(lm) == "LevelMarginal({0: 0.2, 1: 0.3, 2: 0.5})"
    with pytest.raises(gpmsa.GPMSAError, match=r"levels \(3,\) and probabilities \(2,\)"):
        LevelMarginal.from_probabilities([0, 1, 2], [0.2, 0.3])
    with pytest.raises(gpmsa.GPMSAError, match="finite and strictly increasing"):
        LevelMarginal.from_probabilities([0, 2, 1], [0.2, 0.3, 0.5])
    with pytest.raises(gpmsa.GPMSAError, match="finite, non-negative and not all 0"):
        LevelMarginal.from_probabilities([0, 1, 2], [0, 0, 0])


def test_a_grid_posterior_plot_draws_the_exact_density():
    x, y = _obs()
    post = gpmsa.Calibrator(emulator()).update(x, y)
    fig = post.plot("t")
    labels = [line.get_label() for line in fig.axes[0].get_lines()]
    assert "exact (grid)" in labels


# --- plots ----------------------------------------------------------------------------------------
def test_plots_refuse_the_wrong_object():
    with pytest.raises(gpmsa.GPMSAError, match="sens must be a Sensitivity, got str"):
        main_effect_curves("x")
    with pytest.raises(gpmsa.GPMSAError, match="pred must be a FullPrediction, got str"):
        prediction_bands("x")
    with pytest.raises(gpmsa.GPMSAError, match="held-out runs have 10 outputs, the emulator 1"):
        emulator_fit(emulator(), _data()[0])


# --- studies --------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"fixed": "abc"}, "fixed must be None, a dict name -> value .* got str"),
        ({"fixed": [None, 1]}, r"fixed\[1\] must be None or a dict name -> value, got int"),
        ({"n_chains": 0}, "n_chains must be an integer >= 1, got 0"),
    ],
)
def test_calibrate_study_refuses_bad_options(kw, match):
    x, y = _obs()
    emu = emulator()
    with pytest.raises(gpmsa.GPMSAError, match=match):
        gpmsa.calibrate_study([emu, emu], [x, x], [y, y], n_samples=20, n_burn=5, **kw)


def test_study_arguments_and_labels_are_checked():
    with pytest.raises(gpmsa.GPMSAError, match="a study needs at least one model"):
        gpmsa.calibrate_study([], [], [], n_samples=20, n_burn=5)
    data = sim_data()
    with pytest.raises(gpmsa.GPMSAError, match="obs must hold one gpmsa.ObsData per model"):
        gpmsa.fit_study([data, data], [5, 5], n_iter=3)
    x, y = _obs()
    emu = emulator()
    study = gpmsa.calibrate_study(
        [emu, emu], [x, x], [y, y], labels=["a", "b"], n_samples=20, n_burn=5, seed=0
    )
    with pytest.raises(gpmsa.GPMSAError, match=r"unknown model 'zz'; this study has \['a', 'b'\]"):
        study.member_posterior("zz")
