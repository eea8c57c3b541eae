"""Calibration inputs read by name and checked, and what a calibration records (each once
wrong): tables of outputs and Series read by position, a discrepancy's betaV per known input
dropped, masked arrays unmasked, colliding summary keys, unchecked Posterior arguments, a
calibration's own x_obs refused by full_prediction, and an unchecked n_emulator_draws."""

import warnings

import numpy as np
import pandas as pd
import pytest
from _calib_cases import road_emulator, road_obs, vector_emulator

import gpmsa
from gpmsa import GPMSAError, Posterior
from gpmsa.calibration.posterior import GridMarginal
from gpmsa.model.discrepancy import to_samples
from gpmsa.predictive.calibrated import calibrated_predict

PARAMS = {"betaU": [[1.0], [1.0], [1.0]], "lamUz": [1.0], "lamWs": [5000.0], "lamWOs": [5000.0]}


def _two_input_emulator() -> gpmsa.Emulator:
    """Scalar output, known inputs a and b, one calibration parameter t."""
    rng = np.random.default_rng(5)
    x, t = rng.uniform(0, 1, (40, 2)), rng.uniform(0, 1, (40, 1))
    y = np.sin(2 * x[:, :1] + t) + 0.5 * x[:, 1:]
    sim = gpmsa.SimData(x=x, t=t, y=y, x_names=["a", "b"], t_names=["t"])
    return gpmsa.Emulator.from_params(sim, PARAMS)


def _two_input_obs(n: int = 6) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(1)
    x = rng.uniform(0.1, 0.9, (n, 2))
    y = np.sin(2 * x[:, :1] + 0.4) + 0.5 * x[:, 1:] + 0.01 * rng.standard_normal((n, 1))
    return x, y


def _vector_obs() -> tuple[np.ndarray, np.ndarray]:
    grid = np.linspace(0, 1, 8)
    x = np.array([[0.3], [0.6]])
    return x, 1.5 * np.sin(np.pi * grid[None, :] * (0.5 + x)) + 0.15


def test_a_table_of_outputs_is_read_by_the_emulators_y_names():
    emu = vector_emulator()
    x, y = _vector_obs()
    cal = gpmsa.Calibrator(emu)
    _, ref = cal.log_likelihood_grid(x, y)
    table = pd.DataFrame(y, columns=emu.y_names)
    for cols in (list(emu.y_names), list(emu.y_names)[::-1]):  # any order: the same
        np.testing.assert_array_equal(cal.log_likelihood_grid(x, table[cols])[1], ref)
    with pytest.raises(GPMSAError, match=r"y_obs has the columns \['z0', .*expected \['y0'"):
        cal.log_likelihood_grid(x, table.rename(columns={"y0": "z0"}))
    with pytest.raises(GPMSAError, match=r"y_obs has the columns .*'extra'\]; expected"):
        cal.log_likelihood_grid(x, table.assign(extra=1.0))
    # calibrate's backend path (with a discrepancy) reads them by name too
    from gpmsa.calibration.calibrate import calibration_problem

    a = calibration_problem(emu, x, y, discrepancy="constant")
    b = calibration_problem(emu, x, table[list(emu.y_names)[::-1]], discrepancy="constant")
    np.testing.assert_array_equal(a.obs.z, b.obs.z)


def test_a_series_is_matched_by_its_labels_never_by_position():
    emu = _two_input_emulator()
    x, y = _two_input_obs(1)
    row = pd.Series({"b": x[0, 1], "a": x[0, 0]})  # a table's row, columns in another order
    cal = gpmsa.Calibrator(emu)
    np.testing.assert_array_equal(cal.log_likelihood_grid(row, y)[1],
                                  cal.log_likelihood_grid(x, y)[1])  # fmt: skip
    m_ref, _ = emu.predict(x, [[0.4]])
    np.testing.assert_array_equal(emu.predict(row, [[0.4]])[0], m_ref)
    with pytest.raises(GPMSAError, match=r"x_obs is a pandas Series named 'b'"):
        cal.log_likelihood_grid(pd.DataFrame(x, columns=["a", "b"])["b"], y)
    with pytest.raises(GPMSAError, match=r"x is a pandas Series named None with the index "
                                         r"\['a', 'c'\]"):  # fmt: skip
        emu.predict(pd.Series({"a": 0.2, "c": 0.3}), [[0.4]])
    # one input: a Series named as it is its column; one without names is a plain vector
    road = road_emulator()
    xr, yr = road_obs()
    ref = gpmsa.Calibrator(road).log_likelihood_grid(xr, yr)[1]
    for series in (pd.Series(xr[0], name="v"), pd.Series(xr[0])):
        np.testing.assert_array_equal(gpmsa.Calibrator(road).log_likelihood_grid(series, yr)[1],
                                      ref)  # fmt: skip
    with pytest.raises(GPMSAError, match=r"Series named 'speed' .*a Series named 'v'"):
        gpmsa.Calibrator(road).log_likelihood_grid(pd.Series(xr[0], name="speed"), yr)
    y_row = pd.Series({"f": yr[0][0]})  # outputs by name as well
    np.testing.assert_array_equal(gpmsa.Calibrator(road).log_likelihood_grid(xr, y_row)[1], ref)


def test_discrepancy_draws_keep_betaV_of_every_known_input():
    raw = {"betaV": np.arange(2 * 3 * 2, dtype=float).reshape(2, 3, 2, 1),
           "lamVz": np.full((2, 3, 1), 7.0)}  # fmt: skip
    out = to_samples(raw["betaV"], raw["lamVz"])
    assert list(out) == ["betaV[0]", "betaV[1]", "lamVz"]
    np.testing.assert_array_equal(out["betaV[0]"], raw["betaV"][:, :, 0, 0])
    np.testing.assert_array_equal(out["betaV[1]"], raw["betaV"][:, :, 1, 0])
    one = to_samples(raw["betaV"][:, :, :1], raw["lamVz"])
    assert list(one) == ["betaV", "lamVz"] and one["betaV"].shape == (2, 3)


def test_calibrate_with_a_discrepancy_and_two_inputs_feeds_full_prediction():
    emu = _two_input_emulator()
    x, y = _two_input_obs()
    post = gpmsa.calibrate(emu, x, y, n_samples=60, n_burn=10, seed=0, tune=False,
                           discrepancy="constant")  # fmt: skip
    assert post.names == ("t", "lamOs", "betaV[0]", "betaV[1]", "lamVz")
    for k in range(2):
        assert post.chains[f"betaV[{k}]"].shape == (1, 50)
        assert np.all(post.samples[f"betaV[{k}]"] > 0)
    assert not np.array_equal(post.samples["betaV[0]"], post.samples["betaV[1]"])
    pred = gpmsa.full_prediction(emu, gpmsa.ObsData(x=x, y=y), [[0.3, 0.4]], posterior=post,
                                 discrepancy="constant", n_draws=3, seed=0)  # fmt: skip
    assert pred.delta.shape == (3, 1, 1) and np.all(np.isfinite(pred.y))


def test_a_masked_array_is_refused_not_unmasked():
    emu = vector_emulator()
    x, y = _vector_obs()
    masked = np.ma.masked_array(y, mask=np.zeros(y.shape, bool))
    masked[0, 3] = np.ma.masked
    with pytest.raises(GPMSAError, match="y_obs is a numpy masked array"):
        gpmsa.Calibrator(emu).update(x, masked)
    road, (xr, yr) = road_emulator(), road_obs()
    with pytest.raises(GPMSAError, match="y_obs is a numpy masked array"):
        gpmsa.calibrate(road, xr, np.ma.masked_array(yr), n_samples=20, n_burn=5, tune=False)
    with pytest.raises(GPMSAError, match="x_obs is a numpy masked array"):
        gpmsa.calibrate(road, np.ma.masked_array(xr), yr, n_samples=20, n_burn=5, tune=False)


def test_summary_keys_are_unique_and_exact_for_close_levels():
    post = Posterior({"a": np.random.default_rng(0).normal(size=200)})
    assert list(post.summary()["a"]) == ["mean", "sd", "q5", "median", "q95", "n_draws",
                                         "exact_grid", "held"]  # fmt: skip
    assert {"q2.5", "q97.5"} <= set(post.summary(0.95)["a"])
    row = post.summary(1e-7)["a"]
    assert row["q49.999995"] <= row["median"] <= row["q50.000005"]
    near_one = set(post.summary(0.9999999999)["a"])  # :g printed its upper end as "q100"
    assert {"q5e-09", "q99.999999995"} <= near_one
    with pytest.raises(GPMSAError, match="level=1e-17 is too small"):
        post.summary(1e-17)
    with pytest.raises(GPMSAError, match="level must be a number in"):
        post.summary(1.5)


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"info": [1, 2]}, r"info must be a dict .*got list"),
        ({"info": {1: "x"}}, r"info: keys must be strings, got 1"),
        ({"info": {"names": "a"}}, r"info\['names'\] must be a list of parameter names"),
        ({"grids": [1]}, r"grids must be a dict name -> GridMarginal, got list"),
        ({"grids": {"a": 3}}, r"grids\['a'\] must be a GridMarginal, got int"),
        ({"grids": {"zz": None}}, r"grids\['zz'\] must be a GridMarginal"),
        ({"draw": lambda: {}}, r"samples or a draw callable, not both"),
    ],
)
def test_posterior_arguments_are_checked_on_construction(kwargs, match):
    with pytest.raises(GPMSAError, match=match):
        Posterior({"a": np.arange(5.0)}, **kwargs)


def test_posterior_grids_must_name_its_parameters():
    nodes = np.linspace(-3, 3, 31)
    g = GridMarginal.from_log_density(nodes, -0.5 * nodes**2)
    with pytest.raises(GPMSAError, match=r"grids\['b'\] is not a parameter of the posterior"):
        Posterior({"a": np.arange(5.0)}, grids={"b": g})
    with pytest.raises(GPMSAError, match=r"grids\['b'\] is not a parameter"):
        Posterior(grids={"b": g}, draw=lambda: {}, info={"names": ["a"]})
    with pytest.raises(GPMSAError, match="draw must be a callable"):
        Posterior(draw=3)
    assert Posterior({"a": np.arange(5.0)}, grids={"a": g}).mean("a") == g.mean()


def test_full_prediction_takes_the_table_calibrate_took():
    emu = _two_input_emulator()
    x, y = _two_input_obs()
    table = pd.DataFrame({"b": x[:, 1], "a": x[:, 0]})  # columns not in x_names' order
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        post = gpmsa.calibrate(emu, table, y, n_samples=60, n_burn=10, seed=0, tune=False)
    assert gpmsa.ObsData(x=table, y=y).values_digest(emu.x_names) == post.info["obs_values_sha256"]
    kw = {"posterior": post, "discrepancy": None, "n_draws": 3, "seed": 0}
    ref = gpmsa.full_prediction(emu, gpmsa.ObsData(x=x, y=y), [[0.3, 0.4]], **kw)
    same = gpmsa.full_prediction(emu, gpmsa.ObsData(x=table, y=y), [[0.3, 0.4]], **kw)
    np.testing.assert_array_equal(same.y, ref.y)
    with pytest.raises(GPMSAError, match="obs holds other observations"):
        gpmsa.full_prediction(emu, gpmsa.ObsData(x=table, y=y + 0.1), [[0.3, 0.4]], **kw)
    with pytest.raises(GPMSAError, match="obs holds other observations"):  # by position: other
        gpmsa.full_prediction(emu, gpmsa.ObsData(x=table.to_numpy(), y=y), [[0.3, 0.4]], **kw)


@pytest.mark.parametrize("n", [0, -1, 2.5, True, "3", None])
def test_calibrate_checks_n_emulator_draws_in_point_mode(n):
    emu, (x, y) = road_emulator(), road_obs()
    with pytest.raises(GPMSAError, match=r"n_emulator_draws must be an integer >= 1"):
        gpmsa.calibrate(emu, x, y, n_samples=20, n_burn=5, tune=False, n_emulator_draws=n)


def test_an_obsdata_is_taken_alone_and_refused_with_arrays_or_as_x_new():
    """calibrate and Calibrator.update take a gpmsa.ObsData alone in place of the arrays (the
    same posterior); given with the other array too it is refused naming that, not as a
    missing y_obs or a non-numeric x_obs; as calibrated_predict's x_new it is refused."""
    emu = road_emulator()
    x, y = road_obs()
    obs = gpmsa.ObsData(x=x, y=y)
    a = gpmsa.calibrate(emu, obs, n_samples=30, n_burn=0, tune=False, seed=1)
    b = gpmsa.calibrate(emu, x, y, n_samples=30, n_burn=0, tune=False, seed=1)
    np.testing.assert_array_equal(a.samples["GD"], b.samples["GD"])
    assert gpmsa.Calibrator(emu).update(obs).mean("GD") == gpmsa.Calibrator(emu).update(x, y).mean(
        "GD"
    )
    want = r"x_obs is a gpmsa.ObsData, which holds both x and y: pass it alone \(y_obs=None\)"
    with pytest.raises(GPMSAError, match=want):
        gpmsa.calibrate(emu, obs, y, n_samples=10, n_burn=0, tune=False)
    with pytest.raises(GPMSAError, match=r"y_obs is a gpmsa.ObsData, which holds both x and y"):
        gpmsa.Calibrator(emu).update(x, obs)
    with pytest.raises(GPMSAError, match=want):
        gpmsa.calibrate(emu, obs, y, discrepancy="constant", n_samples=10, n_burn=0)
    post = gpmsa.Calibrator(emu).update(x, y)
    with pytest.raises(GPMSAError, match=r"x_new is a gpmsa.ObsData: pass its inputs, x_new=obs.x"):
        calibrated_predict(emu, post, obs)
