"""Exact checks of full_prediction found by mutation testing, the rest of its sites (session 93).

A one-component functional emulator on the grid [0, 1/3, 2/3, 1] (`one_component_functional`)
with a hand-made Posterior: the output grid full_prediction chooses or refuses, the
discrepancy basis on it (hand-normalised), the per-experiment bases' choice, the messages'
wording, the defaults and checks, and the maths of bigger cases (two calibration parameters in
a joint fit, categorical draws, two components with a discrepancy, a memory estimate over
several outputs).
"""

from __future__ import annotations

import typing
import warnings

import numpy as np
import pytest
from _calib_cases import (
    categorical_emulator,
    one_component_functional,
    two_param_emulator,
    vector_emulator,
)

import gpmsa
from gpmsa import GPMSAError
from gpmsa.fitting.emulator import Emulator
from gpmsa.predictive import full, full_prediction

Y = [[1.5, 2.0, 2.5, 3.0], [1.8, 2.4, 3.0, 3.6]]
X_OBS = [[0.3], [0.6]]
SAMPLES = {
    "t": np.array([0.3, 0.5, 0.7]),
    "lamOs": np.array([4.0, 5.0, 6.0]),
    "betaV": np.array([1.0, 2.0, 3.0]),
    "lamVz": np.array([3.0, 4.0, 5.0]),
}
PARAMS = {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [1e3], "lamWOs": [1e3]}
pytestmark = pytest.mark.filterwarnings("ignore::gpmsa.ConvergenceWarning")


def _predict(obs=None, emu=None, *, posterior=None, **kw):
    """full_prediction of the functional case at x = 0.4 ('constant' discrepancy, seed 0)."""
    emu = one_component_functional()[0] if emu is None else emu
    obs = gpmsa.ObsData(x=X_OBS, y=Y) if obs is None else obs
    post = gpmsa.Posterior(dict(SAMPLES)) if posterior is None else posterior
    kw = {"discrepancy": "constant", "seed": 0, **kw}
    return full_prediction(emu, obs, [[0.4]], posterior=post, **kw)


def _joint(emu: Emulator, calibration: dict, settings: dict, draws=None, bases=None):
    """``emu`` as a joint fit's emulator: its ``calibration`` draws and ``settings`` record."""
    return Emulator(
        standardizer=emu.standardizer, x_unit=emu.x_unit, t_unit=emu.t_unit, y=emu.y, K=emu.K,
        w=emu.w, index=emu.index, params=emu.params, priors=emu.priors,
        names={"x": emu.x_names, "t": emu.t_names, "y": emu.y_names},
        units={"x": emu.x_units, "t": emu.t_units, "y": emu.y_units}, draws=draws,
        levels=emu.levels, mean_basis=emu.mean_basis, settings=settings, calibration=calibration,
        discrepancy_bases=bases,
    )  # fmt: skip


CAL = {"theta": np.array([[0.3], [0.5]]), "lamOs": np.array([[4.0], [5.0]]),
       "betaV": np.array([[1.0], [2.0]]), "lamVz": np.array([[3.0], [4.0]])}  # fmt: skip


def _points_emulator() -> Emulator:
    """The functional case's runs on an index of 4 (a, b) points, the unit square's corners."""
    emu, _ = one_component_functional()
    corners = np.array([[0.0, 0.0], [0.0, 1.0], [1.0, 0.0], [1.0, 1.0]])
    sim = gpmsa.SimData(x=emu.x_unit, t=emu.t_unit, y=emu.y, index=corners, x_names=["x"],
                        t_names=["t"])  # fmt: skip
    return Emulator.from_params(sim, dict(emu.params), n_pc=1)


# --- the output grid ---------------------------------------------------------------------------


def test_points_grid_one_point_as_a_row_and_none_refused():
    emu = _points_emulator()
    pred = _predict(emu=emu, grid=[0.5, 0.25])  # d = 2 values: one point
    np.testing.assert_array_equal(pred.grid, [[0.5, 0.25]])
    assert pred.eta.shape == (3, 1, 1)
    with pytest.raises(GPMSAError, match=r"^grid must be finite, got nan at index \(0, 1\)$"):
        _predict(emu=emu, grid=[0.5, np.nan])  # (not "outside the convex hull")
    with pytest.raises(GPMSAError, match="^grid must hold at least one point$"):
        _predict(emu=emu, grid=np.empty((0, 2)))


def test_one_dimensional_grid_row_single_value_and_refusals():
    np.testing.assert_array_equal(_predict(grid=[[0.25, 0.5]]).grid, [0.25, 0.5])
    np.testing.assert_array_equal(_predict(grid=[0.5]).grid, [0.5])
    with pytest.raises(GPMSAError, match=r"^grid must be non-empty and lie within the "
                                         r"simulation grid \[0, 1\]$"):  # fmt: skip
        _predict(grid=[])
    with pytest.raises(GPMSAError, match=r"^grid must be finite, got nan at index \(1,\)$"):
        _predict(grid=[0.5, np.nan])
    np.testing.assert_array_equal(_predict(grid=[[0.25], [0.5]]).grid, [0.25, 0.5])


def test_grid_outside_a_non_round_range_is_named_with_the_digits_that_tell_them_apart():
    """0.12345679 lies just past 0.1234567891: both read 0.123457 at six digits."""
    emu, grid = one_component_functional()
    c = 0.1234567891
    sim = gpmsa.SimData(x=emu.x_unit, t=emu.t_unit, y=emu.y, index=grid * c, x_names=["x"],
                        t_names=["t"])  # fmt: skip
    scaled = Emulator.from_params(sim, dict(emu.params), n_pc=1)
    with pytest.raises(GPMSAError, match=r"simulation grid \[0, 0\.1234567891\]$"):
        _predict(emu=scaled, grid=[0.12345679])


def test_default_grid_is_the_shared_observation_grid_else_the_simulation_grid():
    shared = gpmsa.ObsData(x=X_OBS, y=[[1.5, 2.0], [1.8, 2.4]], index=[0.0, 0.5])
    np.testing.assert_array_equal(_predict(shared).grid, [0.0, 0.5])
    apart = gpmsa.ObsData(x=X_OBS, y=[[1.5, 2.0], [1.8, 2.4]], index=[[0.0, 0.5], [0.5, 1.0]])
    np.testing.assert_array_equal(_predict(apart).grid, one_component_functional()[1])


# --- the discrepancy basis on the prediction grid ----------------------------------------------


def test_linear_basis_keeps_the_observation_grids_normalisation():
    """On [0, 0.5] 'linear' is [1, g] / sqrt(1 + 0.5^2); on the simulation grid the same (the
    experiments' scale carried over)."""
    obs = gpmsa.ObsData(x=X_OBS, y=[[1.5, 2.0], [1.8, 2.4]], index=[0.0, 0.5])
    grid = one_component_functional()[1]
    pred = _predict(obs, discrepancy="linear", grid=grid)
    want = np.column_stack([np.ones(4), grid]) / np.sqrt(1.25)
    np.testing.assert_allclose(pred.D, want, rtol=1e-12)


def test_linear_basis_on_a_large_index_is_the_fits_basis():
    """Index 0 .. 2e12 (millisecond stamps): the fit's 'linear' basis is [1, g] / sqrt(1 +
    4e24); predicted on the observations' own grid, delta's basis must be that one. Before
    session 93 its scale 5e-13 was rounded to 12 decimals, 0: an all-zero basis."""
    emu, grid = one_component_functional()
    big = grid * 2e12
    sim = gpmsa.SimData(x=emu.x_unit, t=emu.t_unit, y=emu.y, index=big, x_names=["x"],
                        t_names=["t"])  # fmt: skip
    scaled = Emulator.from_params(sim, dict(emu.params), n_pc=1)
    obs = gpmsa.ObsData(x=X_OBS, y=Y, index=big)
    pred = _predict(obs, scaled, discrepancy="linear")
    want = np.column_stack([np.ones(4), big]) / np.sqrt(1.0 + 4e24)
    np.testing.assert_allclose(pred.D, want, rtol=1e-12)


def test_array_basis_on_another_grid_of_the_same_size_is_refused():
    with pytest.raises(GPMSAError, match="known on the observations' grid only"):
        _predict(discrepancy=np.array([[1.0], [2.0], [3.0], [4.0]]), grid=[0.0, 0.2, 0.4, 1.0])


def test_grid_discrepancy_one_column_wrong_shapes_and_kinds():
    basis = np.array([[1.0], [2.0], [3.0], [4.0]])  # largest row norm 4: the fit's divisor
    pred = _predict(discrepancy=basis, grid=[0.25, 0.5], grid_discrepancy=np.array([8.0, 2.0]))
    np.testing.assert_array_equal(pred.D, [[2.0], [0.5]])
    with pytest.raises(GPMSAError, match=r"must be \(2, 1\): .* vector; got \(3, 1\)$"):
        _predict(discrepancy=basis, grid=[0.25, 0.5], grid_discrepancy=np.ones((3, 1)))
    two = np.column_stack([np.ones(4), np.arange(4.0)])
    with pytest.raises(GPMSAError, match=r"got \(2, 3\); SEPIA stores D as \(p_v, l\): pass "):
        _predict(discrepancy=two, grid=[0.2, 0.25, 0.5], grid_discrepancy=np.ones((2, 3)))
    with pytest.raises(GPMSAError, match="goes with a discrepancy basis given as an array"):
        _predict(grid_discrepancy=np.ones(4))
    with pytest.raises(GPMSAError, match=r"^grid_discrepancy must be finite, got nan at "):
        _predict(discrepancy=basis, grid=[0.25, 0.5], grid_discrepancy=np.array([8.0, np.nan]))
    with pytest.raises(GPMSAError, match="^grid_discrepancy= and experiment= both choose"):
        _predict(discrepancy=basis, grid_discrepancy=np.ones(4), experiment=0)


# --- per-experiment bases ----------------------------------------------------------------------


def test_experiment_takes_its_grid_given_as_a_row_and_refuses_another():
    obs = gpmsa.ObsData(x=X_OBS, y=[[1.5, 2.0], [1.8, 2.4]], index=[[0.0, 0.5], [0.5, 1.0]])
    bases = [np.array([[1.0], [2.0]]), np.array([[3.0], [1.0]])]  # jointly divided by 3
    pred = _predict(obs, discrepancy=bases, experiment=0, grid=[[0.0, 0.5]])
    np.testing.assert_array_equal(pred.grid, [0.0, 0.5])
    np.testing.assert_allclose(pred.D, [[1 / 3], [2 / 3]], rtol=1e-15)
    with pytest.raises(GPMSAError, match=r"^experiment=0 predicts on its grid \(obs.grids\[0\], "):
        _predict(obs, discrepancy=bases, experiment=0, grid=[0.5, 1.0])


def test_no_experiment_on_the_grid_names_the_first_six():
    obs = gpmsa.ObsData(x=[[0.1 * k + 0.1] for k in range(7)], y=[[2.0]] * 7,
                        index=[[0.1 * k + 0.05] for k in range(7)])  # fmt: skip
    with pytest.raises(GPMSAError) as err:
        _predict(obs, discrepancy=[np.array([[1.0]])] * 7)
    sizes = ", ".join(f"{j}: 1 values" for j in range(6))
    assert f"experiments {sizes}, ...), whose basis" in str(err.value)


# --- messages, defaults and checks -------------------------------------------------------------


def test_the_fitted_array_and_the_calibrations_are_named_by_their_source():
    emu = one_component_functional()[0]
    obs = gpmsa.ObsData(x=X_OBS, y=Y)
    given = _joint(emu, CAL, {"discrepancy": "given"})
    with pytest.raises(GPMSAError, match=r"default \(or pass the fit's array again\)$"):
        full_prediction(given, obs, [[0.4]], discrepancy="constant")
    with pytest.raises(GPMSAError, match="^the joint fit used a discrepancy basis given as an"):
        full_prediction(given, obs, [[0.4]])
    const = _joint(emu, CAL, {"discrepancy": "constant"})
    with pytest.raises(GPMSAError, match=r"\('constant'\); .* at its default$"):
        full_prediction(const, obs, [[0.4]], discrepancy=None)
    post = gpmsa.Posterior(dict(SAMPLES), info={"discrepancy": "given"})
    with pytest.raises(GPMSAError, match="^the calibration used a discrepancy basis given as an"):
        _predict(posterior=post, discrepancy=full.AS_FITTED)


def test_recorded_groups_are_taken_with_a_discrepancy_and_ignored_without():
    two = {"t": SAMPLES["t"], "lamOs": SAMPLES["lamOs"], "betaV[0,0]": SAMPLES["betaV"],
           "betaV[0,1]": 2 * SAMPLES["betaV"], "lamVz[0]": SAMPLES["lamVz"],
           "lamVz[1]": 3 * SAMPLES["lamVz"]}  # fmt: skip
    info = {"discrepancy": "linear", "discrepancy_groups": [0, 1]}
    pred = _predict(posterior=gpmsa.Posterior(two, info=info), discrepancy="linear")
    assert pred.mu.shape == (3, 1, 3)
    bare = gpmsa.Posterior({"t": SAMPLES["t"], "lamOs": SAMPLES["lamOs"]}, info=info)
    assert _predict(posterior=bare, discrepancy=None).mu.shape == (3, 1, 1)
    with pytest.raises(GPMSAError, match="^discrepancy_groups must be a sequence of 1 integer"):
        _predict(discrepancy_groups="as recorded")


def test_per_group_priors_are_checked_against_the_groups_with_a_discrepancy_only():
    emu = one_component_functional()[0]
    lam_vz = emu.priors.lamVz
    two = Emulator.from_params(
        gpmsa.SimData(x=emu.x_unit, t=emu.t_unit, y=emu.y, index=emu.index, x_names=["x"],
                      t_names=["t"]),
        dict(emu.params), n_pc=1, priors=gpmsa.Priors(lamVz=(lam_vz, lam_vz)),
    )  # fmt: skip
    with pytest.raises(GPMSAError, match="^Priors.lamVz gives 2 per-group prior"):
        _predict(emu=two)
    bare = gpmsa.Posterior({"t": SAMPLES["t"], "lamOs": SAMPLES["lamOs"]})
    assert _predict(emu=two, posterior=bare, discrepancy=None).p_v == 0


def test_observations_far_outside_are_refused_unless_extrapolating():
    far = gpmsa.ObsData(x=[[3.0], [0.6]], y=Y)
    with pytest.raises(GPMSAError, match=r"^obs x=3 lies outside the emulator's domain \[0, 1\]"):
        _predict(far)
    assert _predict(far, extrapolate=True).grid.size == 4


def test_no_progress_bar_by_default(capfd):
    _predict()
    assert capfd.readouterr().err == ""


def test_the_helpers_hints_resolve():
    for f in (full._posterior_sets, full._given_on_grid, full._grid_divisor):
        assert typing.get_type_hints(f)  # (a | None, never a & None)
    assert typing.get_type_hints(full._grid_divisor)["return"] == float | None


# --- maths of bigger cases ---------------------------------------------------------------------


def test_joint_fit_with_two_calibration_parameters_and_no_emulator_draws():
    emu = two_param_emulator()
    cal = {"theta": np.array([[0.3, 0.6], [0.5, 0.2]]), "lamOs": np.array([[4.0], [5.0]])}
    joint = _joint(emu, cal, {})
    obs = gpmsa.ObsData(x=[[0.3]], y=[[0.5]])
    pred = full_prediction(joint, obs, [[0.4]], draws=False)
    std = emu.standardizer
    np.testing.assert_array_equal(pred.theta, cal["theta"] * (std.t_max - std.t_min) + std.t_min)
    with pytest.raises(GPMSAError, match="^the emulator kept no posterior draws of its own"):
        full_prediction(joint, obs, [[0.4]], draws=True)


def test_categorical_draws_are_exactly_their_level_codes():
    """Codes 0 .. 25: 7 / 25 * 25 is 7.000000000000001 in floating point."""
    rng = np.random.default_rng(0)
    x, t = rng.random(30), np.arange(30) % 26
    emu = Emulator.from_params(gpmsa.SimData(x, t, x + 0.1 * t, t_categorical=[0]), PARAMS)
    post = gpmsa.Posterior({"t0": np.array([7.0, 14.0]), "lamOs": np.array([4.0, 5.0])})
    pred = full_prediction(emu, gpmsa.ObsData(x=[[0.3]], y=[[1.5]]), [[0.4]], posterior=post,
                           discrepancy=None)  # fmt: skip
    assert pred.theta[:, 0].tolist() == [7.0, 14.0]
    assert categorical_emulator().levels[1] == (0, 1, 2)  # (the shared case: exact anyway)


def test_two_components_and_a_discrepancy_keep_the_discrepancys_prior_without_data():
    """lamOs = 1e-12: the observations carry no information, so v at a new point keeps its
    prior, variance 1 / lamVz and mean 0, beside the emulator's two components."""
    emu = vector_emulator()
    grid = emu.standardizer.grid
    obs = gpmsa.ObsData(x=[[0.5]], y=[np.sin(np.pi * grid)])
    post = gpmsa.Posterior({"t": np.array([0.4, 0.6]), "lamOs": np.array([1e-12, 1e-12]),
                            "betaV": np.array([1.0, 2.0]),
                            "lamVz": np.array([3.0, 8.0])})  # fmt: skip
    pred = full_prediction(emu, obs, [[0.2]], posterior=post, discrepancy="constant", seed=0)
    assert pred.cov.shape == (2, 1, 3, 3)
    np.testing.assert_allclose(pred.cov[:, 0, 0, 0], [1 / 3, 1 / 8], rtol=1e-9)
    np.testing.assert_allclose(pred.cov[:, 0, 0, 1:], 0.0, atol=1e-9)
    np.testing.assert_allclose(pred.mu[:, 0, 0], 0.0, atol=1e-5)


def test_memory_estimate_counts_every_output(monkeypatch):
    """3 draws x 2 realizations at 3 points, 4 outputs, n_c = 2: 8 S (n_rlz N (n_c + 4 l) +
    N n_c^2) + 32 (n_c N)^2 = 24 (6 * 18 + 12) + 32 * 36 = 4032 bytes."""
    import gpmsa.limits

    def run():
        emu = one_component_functional()[0]
        obs = gpmsa.ObsData(x=X_OBS, y=Y)
        post = gpmsa.Posterior(dict(SAMPLES))
        return full_prediction(emu, obs, [[0.1], [0.4], [0.9]], discrepancy="constant",
                               posterior=post, n_rlz=2, seed=0)  # fmt: skip

    monkeypatch.setattr(gpmsa.limits, "MAX_MEMORY_BYTES", 4032)
    assert run().y.shape == (6, 3, 4)
    monkeypatch.setattr(gpmsa.limits, "MAX_MEMORY_BYTES", 4031)
    with pytest.raises(gpmsa.limits.ResourceLimitError, match=r"at 3 points x 3 draws x 4 out"):
        run()


def test_a_posteriors_recorded_kind_and_emulator_are_taken_or_refused():
    post = gpmsa.Posterior(dict(SAMPLES), info={"discrepancy": "constant"})
    assert _predict(posterior=post, discrepancy=full.AS_FITTED).p_v == 1
    with pytest.raises(GPMSAError, match="^posterior= has discrepancy draws .* records no disc"):
        _predict(discrepancy=full.AS_FITTED)
    other = gpmsa.Posterior(dict(SAMPLES), info={"emulator_sha256": "f" * 64})
    with pytest.raises(GPMSAError, match=r"^posterior= was drawn with another emulator \(mod"):
        _predict(posterior=other)
    with pytest.raises(GPMSAError, match="^full_prediction needs a gpmsa.Emulator, got str$"):
        full_prediction("emu", gpmsa.ObsData(x=X_OBS, y=Y), [[0.4]])


def test_a_kept_list_is_taken_for_a_posterior_only_with_its_digest():
    emu = one_component_functional()[0]
    record = {"discrepancy": "list", "discrepancy_sha256": "a" * 64, "discrepancy_scale": 3.0}
    joint = _joint(emu, CAL, record, bases=[np.ones((4, 1))])
    other = gpmsa.Posterior(dict(SAMPLES), info={**record, "discrepancy_sha256": "b" * 64})
    with pytest.raises(GPMSAError, match=r"^the calibration used per-experiment discrepancy "):
        full_prediction(joint, gpmsa.ObsData(x=X_OBS, y=Y), [[0.4]], posterior=other)


def test_kinds_and_flags_refused_by_name():
    with pytest.raises(GPMSAError, match="^extrapolate must be True or False"):
        _predict(extrapolate="yes")
    with pytest.raises(GPMSAError, match="^experiment= chooses among per-experiment discrep"):
        _predict(experiment=0)


def test_observations_slightly_outside_are_not_warned_of_again():
    """The calibration warned of obs x = 1.05 (within 10 % of the range): not repeated here."""
    near = gpmsa.ObsData(x=[[1.05], [0.6]], y=Y)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert _predict(near).grid.size == 4


def test_the_result_compares_by_identity_and_hashes():
    """eq=False: no field-wise == over arrays (which numpy would refuse to reduce to a bool)."""
    import dataclasses

    pred = _predict()
    assert pred == pred and pred != dataclasses.replace(pred)
    assert hash(pred) == hash(pred)
