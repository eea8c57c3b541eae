"""SimData(y_mean=, y_sd=): the output centring and scale the user gives (SEPIA's
standardize_y(y_mean=, y_sd=)) instead of the runs' own, through the fit, predictions,
calibration, full prediction, sensitivity, the file and continuations."""

import json

import numpy as np
import pytest

import gpmsa
from gpmsa.cli.main import main

RNG = np.random.default_rng(7)
X, T = RNG.uniform(size=(24, 1)), RNG.uniform(size=(24, 1))
S = np.array([0.0, 0.5, 1.0])
C = np.array([1.0, -2.0, 5.0])  # the given centring and scale, one per output element
SD = np.array([0.5, 2.0, 10.0])


def simulate(x, t):
    return 3.0 + np.sin(2 * x + S) * 4.0 * t + 8.0 * x * S


Y = simulate(X, T)
X_OBS = np.array([[0.3], [0.7]])
Y_OBS = simulate(X_OBS, 0.4) + 0.01 * RNG.standard_normal((2, 3))


def _sim(y=Y, **kw) -> gpmsa.SimData:
    return gpmsa.SimData(x=X, t=T, y=y, x_names=["x"], t_names=["t"], **kw)


@pytest.fixture(scope="module")
def pair():
    """The fit with the given scale, and the default-path fit of y pre-scaled by hand."""
    given = gpmsa.fit(_sim(y_mean=C, y_sd=SD), n_iter=40, n_chains=1, seed=0)
    scaled = gpmsa.fit(_sim((Y - C) / SD, y_mean=0.0, y_sd=1.0), n_iter=40, n_chains=1, seed=0)
    return given, scaled


def test_a_given_scale_fits_as_the_prescaled_outputs(pair):
    given, scaled = pair
    std = given.standardizer
    assert std.y_given == ("y_mean", "y_sd")
    np.testing.assert_array_equal(std.y_mean, C)
    np.testing.assert_array_equal(std.y_sd, SD)
    for k in given.params:  # the standardised runs agree to the bit: so do the chains
        np.testing.assert_array_equal(given.params[k], scaled.params[k])
        np.testing.assert_array_equal(given.draws[k], scaled.draws[k])
    x, t = np.array([[0.2], [0.9]]), np.array([[0.5], [0.1]])
    mean, var = given.predict(x, t)
    mean_s, var_s = scaled.predict(x, t)
    np.testing.assert_allclose(mean, mean_s * SD + C, rtol=1e-12)
    np.testing.assert_allclose(var, var_s * SD**2, rtol=1e-12)


def test_calibration_full_prediction_and_sensitivity_follow(pair):
    given, scaled = pair
    y_obs_s = (Y_OBS - C) / SD
    lam = np.diag(1e4 / SD**2)  # native precisions; standardised, lam * sd_l sd_k: 1e4 I
    a = gpmsa.Calibrator(given).update(gpmsa.ObsData(x=X_OBS, y=Y_OBS, precision=[lam] * 2))
    b = gpmsa.Calibrator(scaled).update(gpmsa.ObsData(x=X_OBS, y=y_obs_s, precision=1e4))
    assert abs(a.mean("t") - b.mean("t")) < 1e-9 and abs(a.sd("t") - b.sd("t")) < 1e-9
    assert abs(a.mean("t") - 0.4) < 0.05
    post_a = gpmsa.calibrate(given, x_obs=X_OBS, y_obs=Y_OBS, n_samples=80, n_burn=20, seed=1)
    post_b = gpmsa.calibrate(scaled, x_obs=X_OBS, y_obs=y_obs_s, n_samples=80, n_burn=20, seed=1)
    np.testing.assert_allclose(post_a.samples["t"], post_b.samples["t"], rtol=1e-9)
    obs_a, obs_b = gpmsa.ObsData(x=X_OBS, y=Y_OBS), gpmsa.ObsData(x=X_OBS, y=y_obs_s)
    full_a = gpmsa.full_prediction(given, obs_a, X_OBS, posterior=post_a, n_draws=5, seed=0)
    full_b = gpmsa.full_prediction(scaled, obs_b, X_OBS, posterior=post_b, n_draws=5, seed=0)
    np.testing.assert_allclose(full_a.mean("eta"), full_b.mean("eta") * SD + C, rtol=1e-9)
    np.testing.assert_allclose(full_a.var("y"), full_b.var("y") * SD**2, rtol=1e-9)
    sens_a, sens_b = gpmsa.sensitivity(given, draws=False), gpmsa.sensitivity(scaled, draws=False)
    np.testing.assert_allclose(sens_a.main, sens_b.main, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(sens_a.variance, sens_b.variance * SD**2, rtol=1e-9)


def test_the_file_keeps_and_checks_the_given_scale(pair, tmp_path, capsys):
    given, _ = pair
    back = gpmsa.load(given.save(tmp_path / "given.gpmsa"))
    assert back.model_sha256 == given.model_sha256
    assert back.standardizer.y_given == ("y_mean", "y_sd")
    x, t = [[0.3]], [[0.4]]
    np.testing.assert_array_equal(back.predict(x, t)[0], given.predict(x, t)[0])
    main(["info", str(tmp_path / "given.gpmsa")])
    out = capsys.readouterr().out
    assert "centred by the given y_mean, divided by the given y_sd (one per output" in out
    manifest, arrays = given.to_record()
    assert manifest["model"]["y_given"] == ["y_mean", "y_sd"]
    model = {k: v for k, v in manifest["model"].items() if k != "y_given"}  # an older reader
    with pytest.raises(gpmsa.EmulatorFileError, match="arrays/y_mean: differs from the mean"):
        gpmsa.Emulator.from_record(dict(manifest, model=model), arrays)
    only_mean = dict(manifest, model=dict(model, y_given=["y_mean"]))
    with pytest.raises(gpmsa.EmulatorFileError, match=r"arrays/y_sd: \[0\] = 0.5, but the sd"):
        gpmsa.Emulator.from_record(only_mean, arrays)
    for bad in (["y_sd", "y_sd"], ["y_scale"], [], "y_mean"):
        edited = dict(manifest, model=dict(model, y_given=bad))
        with pytest.raises(gpmsa.EmulatorFileError, match="model.y_given: must be a non-empty"):
            gpmsa.Emulator.from_record(edited, arrays)
    with pytest.raises(gpmsa.EmulatorFileError, match="arrays/w: differs from the projection"):
        gpmsa.Emulator.from_record(manifest, dict(arrays, y_sd=SD * 1.5))
    json.dumps(manifest)  # the field is plain JSON


def test_default_files_carry_no_field_and_one_given_part_checks_the_other():
    prm = {"betaU": [[1.0, 1.0], [1.0, 1.0]], "lamUz": [1.0, 1.0], "lamWs": [1e3, 1e3],
           "lamWOs": [1e3]}  # fmt: skip
    default = gpmsa.Emulator.from_params(_sim(), prm)
    manifest, _ = default.to_record()
    assert "y_given" not in manifest["model"] and default.standardizer.y_given == ()
    mean_only = gpmsa.Emulator.from_params(_sim(y_mean=C), prm)
    std = mean_only.standardizer
    assert std.y_given == ("y_mean",) and std.y_sd == default.standardizer.y_sd
    manifest, arrays = mean_only.to_record()
    assert manifest["model"]["y_given"] == ["y_mean"]
    with pytest.raises(gpmsa.EmulatorFileError, match="arrays/y_sd: .*training outputs' sd"):
        gpmsa.Emulator.from_record(manifest, dict(arrays, y_sd=arrays["y_sd"] * 2))
    cw = _sim(y_mean=2.0, y_scale="columnwise")  # a given centring with each element's own sd
    assert cw.y_mean.shape == (3,) and cw.y_sd is None
    scalar = gpmsa.Emulator.from_params(_sim(y_mean=2.0, y_sd=3.0), prm).standardizer
    assert scalar.y_sd == 3.0 and not scalar.columnwise


def test_a_continuation_with_another_given_scale_names_it(pair):
    given, _ = pair
    emu = gpmsa.fit(_sim(y_mean=C, y_sd=SD), n_iter=10, n_chains=1, seed=1, init=given)
    assert emu.standardizer.y_given == ("y_mean", "y_sd")
    with pytest.raises(gpmsa.GPMSAError, match=r"y_mean: \[1, -2, 5\] \(given\) in init=emulator's "
                       r"fit, \[2, -1, 6\] \(given\) here"):  # fmt: skip
        gpmsa.fit(_sim(y_mean=C + 1, y_sd=SD), n_iter=10, n_chains=1, seed=1, init=given)
    match = (
        r"y_mean: .*\(the runs' own\) here; y_sd: \[0.5, 2, 10\] \(given\) in "
        r"init=emulator's fit, .* \(the runs' own\) here"
    )
    with pytest.raises(gpmsa.GPMSAError, match=match):
        gpmsa.fit(_sim(), n_iter=10, n_chains=1, seed=1, init=given)


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"y_mean": [1.0, 2.0]}, r"y_mean must be a number or an array \(3,\).* got shape \(2,\)"),
        ({"y_sd": np.ones((3, 1))}, r"y_sd must be a number or an array \(3,\).*shape \(3, 1\)"),
        ({"y_sd": -1.0}, r"y_sd must be positive, got y_sd = -1.0"),
        ({"y_sd": [1.0, 0.0, 1.0]}, r"y_sd must be positive, got y_sd\[1\] = 0.0"),
        ({"y_sd": np.nan}, "y_sd must be finite"),
        ({"y_mean": [0.0, np.inf, 0.0]}, r"y_mean must be finite, got inf at index \(1,\)"),
        ({"y_sd": "2"}, "y_sd must be a numeric array, got str"),
        ({"y_mean": None, "y_sd": 1e-200}, "y_sd = 1e-200: its square is not a normal float64"),
        ({"y_mean": 1e308, "y_sd": 1e-100}, "y standardised by the given y_mean and y_sd over"),
        ({"y_sd": 2.0, "y_scale": "columnwise"}, "y_sd is given and y_scale='columnwise'"),
    ],
)  # fmt: skip
def test_bad_given_scales_are_refused_by_name(kw, match):
    with pytest.raises(gpmsa.GPMSAError, match=match):
        _sim(**kw)
