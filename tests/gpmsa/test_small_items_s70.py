"""Small defects of the session 70 walkthrough: metadata integers a reader cannot parse, a file
path given as init, ``gpmsa --version``, theta priors float64 cannot evaluate (refused naming
the field; a flat prior's normaliser without RuntimeWarnings), and ``plots.data``'s unit labels."""

import io
import json
import warnings
import zipfile

import numpy as np
import pytest

import gpmsa
from gpmsa.calibration.calibrator import log_theta_norm
from gpmsa.cli.main import main
from gpmsa.errors import EmulatorFileError, GPMSAError
from gpmsa.io import container
from tests.gpmsa._emulator_edit import replaced
from tests.gpmsa._study_cases import emulator, observations, sim_data

PARAMS = {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [5000.0], "lamWOs": [5000.0]}


def _sim() -> gpmsa.SimData:
    rng = np.random.default_rng(1)
    x, t = rng.random((8, 1)), rng.random((8, 1))
    return gpmsa.SimData(x=x, t=t, y=np.sin(3 * x) + t, x_names=["v"], t_names=["GD"])


# 1. metadata: an integer longer than a reader's json parses -----------------------------------
def test_a_metadata_integer_too_long_for_a_reader_is_refused_by_fit_naming_its_path():
    """fit accepted {"a": 10**5000}; save then failed with Python's 'Exceeds the limit (4300
    digits)', naming no key."""
    with pytest.raises(GPMSAError, match=r"metadata\['a'\]: an integer of more than 4300 digits"):
        gpmsa.fit(_sim(), n_iter=10, seed=0, metadata={"a": 10**5000})
    with pytest.raises(GPMSAError, match=r"metadata\['x'\]\[1\]\['y'\]: an integer"):
        gpmsa.Emulator.from_params(_sim(), PARAMS, metadata={"x": [1, {"y": -(10**4300)}]})


def test_save_names_the_path_and_the_longest_integer_a_reader_parses_round_trips(tmp_path):
    emu = gpmsa.Emulator.from_params(_sim(), PARAMS)
    with pytest.raises(GPMSAError, match=r"metadata\['a'\]: an integer of more than 4300"):
        replaced(emu, metadata={"a": 10**5000}).save(tmp_path / "big.gpmsa")
    longest = {"pos": 10**4300 - 1, "neg": -(10**4300 - 1)}  # 4300 digits: json reads them
    path = gpmsa.Emulator.from_params(_sim(), PARAMS, metadata=longest).save(tmp_path / "e.gpmsa")
    assert gpmsa.load(path).metadata == longest


# 2. init: a path is not a start rule --------------------------------------------------------
@pytest.mark.parametrize("init", ["file.gpmsa", "prior "])
def test_fit_with_a_path_as_init_says_to_load_the_file(init, tmp_path):
    with pytest.raises(GPMSAError, match="init must be one of") as err:
        gpmsa.fit(_sim(), n_iter=10, seed=0, init=init)
    assert "to continue from a saved file pass init=gpmsa.load(path)" in str(err.value)
    with pytest.raises(GPMSAError, match=r"init=gpmsa\.load\(path\)"):
        gpmsa.fit(_sim(), n_iter=10, seed=0, init=tmp_path / "file.gpmsa")


def test_the_studies_say_load_study_and_calibrate_keeps_the_plain_message():
    rng = np.random.default_rng(4)
    data = [observations(th, 3, 0.03, rng) for th in (0.35, 0.5)]
    hint = r"; to continue from a saved file pass init=gpmsa\.load_study\(path\)$"
    with pytest.raises(GPMSAError, match="init must be one of.*'run.gpmsa'" + hint):
        gpmsa.calibrate_study([emulator(None)] * 2, [d[0] for d in data], [d[1] for d in data],
                              n_samples=20, n_burn=10, init="run.gpmsa")  # fmt: skip
    obs = [gpmsa.ObsData(x=d[0], y=d[1]) for d in data]
    with pytest.raises(GPMSAError, match=hint):
        gpmsa.fit_study([sim_data()] * 2, obs, n_iter=20, init="run.gpmsa")
    # calibrate continues nothing from a file: the shared check's message, without the hint
    with pytest.raises(GPMSAError, match=r"init must be one of .*'x.gpmsa'$"):
        gpmsa.calibrate(emulator(None), data[0][0], data[0][1], n_samples=20, n_burn=10,
                        fast=False, init="x.gpmsa")  # fmt: skip


# 3. gpmsa --version -------------------------------------------------------------------------
def test_the_cli_prints_the_library_version_and_exits_0(capsys):
    with pytest.raises(SystemExit) as done:
        main(["--version"])
    assert done.value.code == 0
    assert capsys.readouterr().out == f"gpmsa {gpmsa.__version__}\n"


# 4. theta priors float64 cannot evaluate ----------------------------------------------------
def _edited(tmp_path, **priors):
    """A saved emulator whose manifest's priors are edited, re-hashed so that it loads."""
    path = gpmsa.Emulator.from_params(_sim(), PARAMS).save(tmp_path / "e.gpmsa")
    with zipfile.ZipFile(path) as zf:
        members = {n: zf.read(n) for n in zf.namelist()}
    manifest = json.loads(members.pop("manifest.json"))
    arrays = {n[7:-4]: np.load(io.BytesIO(b), allow_pickle=False) for n, b in members.items()}
    manifest["priors"].update(priors)
    manifest["content_sha256"] = container.content_hash(arrays, manifest)
    out = tmp_path / "edited.gpmsa"
    with zipfile.ZipFile(out, "w") as zf:
        zf.writestr("manifest.json", json.dumps(manifest))
        for k, b in members.items():
            zf.writestr(k, b)
    return out


@pytest.mark.parametrize(
    ("priors", "field"),
    [
        ({"theta_sd": 1e-300}, "priors.theta_sd: 1e-300 is too small"),
        ({"theta_mean": 1e300}, "priors.theta_mean: 1e[+]300 is too far from"),
        ({"theta_mean": -1e200, "theta_sd": 1e30}, "priors.theta_mean"),
    ],
)
def test_a_file_with_a_theta_prior_float64_cannot_evaluate_is_refused_naming_it(
    tmp_path, priors, field
):
    """It loaded; `gpmsa calibrate` then said 'no mass on the grid' after numpy's overflow and
    divide RuntimeWarnings."""
    with pytest.raises(EmulatorFileError, match=field):
        gpmsa.load(_edited(tmp_path, **priors))
    emu = gpmsa.Emulator.from_params(_sim(), PARAMS)
    with pytest.raises(GPMSAError, match=f"Priors.{field.split('.')[1].split(':')[0]} = "):
        emu.with_calibration_priors(**priors)


def test_extreme_theta_priors_that_float64_evaluates_load_and_calibrate_without_warnings(
    tmp_path,
):
    """A flat prior (theta_sd 1e300: its normaliser's ndtr difference was 0, a 'divide by zero'
    RuntimeWarning and log_evidence inf), a narrow one and a far mean stay accepted."""
    posts = []
    for priors in ({"theta_sd": 1e300}, {"theta_sd": 1e-150}, {"theta_mean": 1e100}):
        emu = gpmsa.load(_edited(tmp_path, **priors))
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)  # 1e-150: narrower than the grid
            warnings.simplefilter("error", RuntimeWarning)
            posts.append(gpmsa.Calibrator(emu).update([[0.5]], [[1.0]]))
        assert np.isfinite(posts[-1].info["log_evidence"]) and np.isfinite(posts[-1].mean("GD"))
    flat = gpmsa.Calibrator(gpmsa.Emulator.from_params(_sim(), PARAMS).with_calibration_priors(
        theta_sd=1e6)).update([[0.5]], [[1.0]])  # fmt: skip
    assert posts[0].info["log_evidence"] == pytest.approx(flat.info["log_evidence"], abs=1e-9)


@pytest.mark.parametrize(
    ("mean", "sd", "want"),
    # references: mpmath at 60 digits of log(sd sqrt(2 pi) (Phi((1-m)/sd) - Phi(-m/sd)))
    # (the last: -a**2 / 2 to 1e-9, a = 1e99 standard deviations from 0)
    [
        (0.5, 10.0, -0.00041659722773437479),
        (0.5, 1e20, 1.2179977468644358e-42),
        (0.3, 1e5, -6.1666666666430558e-12),
        (1e3, 10.0, -4992.3067303507914),
        (0.5, 0.02, -2.9930844722234733),
        (-1e100, 10.0, -5e197),
    ],  # fmt: skip
)
def test_the_theta_prior_normaliser_is_finite_and_accurate(mean, sd, want):
    assert log_theta_norm(mean, sd) == pytest.approx(want, rel=1e-9, abs=1e-20)


# 5. plots.data labels name (unit) as every other plot ---------------------------------------
def test_data_plot_labels_read_name_unit_in_parentheses():
    pytest.importorskip("matplotlib")
    x, t = np.random.default_rng(2).random((2, 6, 1))
    sim = gpmsa.SimData(x=x, t=t, y=x + t, x_names=["v"], t_names=["GD"], x_units=["m/s"],
                        t_units=["1e-6 m^3"], y_units=["m/s^2"])  # fmt: skip
    fig = gpmsa.plots.data(sim)
    assert [a.get_xlabel() for a in fig.axes] == ["v (m/s)", "GD (1e-6 m^3)"]
    assert fig.axes[0].get_ylabel() == "y0 (m/s^2)"
