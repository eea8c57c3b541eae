"""``gpmsa info`` and the record checks show distinct values distinctly (session 76).

An emulator whose known input spans [1000000.003, 1000000.935] printed "v in [1e+06, 1e+06]",
a continuation whose range differed in the 7th digit "[1e+06, 1e+06] in init=emulator's fit,
[1e+06, 1e+06] here", and a unit-scale array 2e-9 above 1 "spans [0, 1]": they now take more
digits where two values would read alike (``gpmsa.errors.numbers_text``), ordinary values as
before. ``gpmsa info --json`` printed the raw manifest; it prints the facts that ``gpmsa info``
shows under documented keys (the manifest under "manifest"), strict JSON (no NaN token).
"""

import json
import warnings

import numpy as np
import pytest
from _study_cases import emulator, observations

import gpmsa
from gpmsa.cli.info import _gamma
from gpmsa.cli.main import main
from gpmsa.errors import EmulatorFileError
from gpmsa.fitting.validation import _in_unit
from tests.gpmsa._emulator_edit import replaced

X = 1e6 + np.linspace(0.003, 0.935, 12)[:, None]
T = np.random.default_rng(0).random((12, 1))
Y = np.sin(3 * (X[:, 0] - 1e6)) + T[:, 0] ** 2
PRM = {"betaU": np.ones((2, 1)), "lamUz": [1.0], "lamWs": [1e4], "lamWOs": [1e4]}


def _strict(text: str):
    """``text`` parsed as RFC 8259 JSON: a NaN, Infinity or -Infinity token raises."""

    def refuse(token):
        raise ValueError(f"not JSON: {token}")

    return json.loads(text, parse_constant=refuse)


@pytest.fixture(scope="module")
def offset_file(tmp_path_factory):
    sim = gpmsa.SimData(x=X, t=T, y=Y, x_names=["v"], t_names=["a"])
    emu = gpmsa.Emulator.from_params(sim, PRM)
    return emu, str(emu.save(tmp_path_factory.mktemp("emu") / "offset.gpmsa"))


@pytest.fixture(scope="module")
def study_file(tmp_path_factory):
    rng = np.random.default_rng(4)
    data = [observations(th, 3, 0.03, rng) for th in (0.35, 0.5)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # short chains: not converged
        study = gpmsa.calibrate_study(
            [emulator(None)] * 2, [d[0] for d in data], [d[1] for d in data], labels=["a", "b"],
            hierarchical=["t"], n_chains=2, fixed=[{"lamOs": 1.0}, None], n_samples=60,
            n_burn=20, tune=False, seed=0,
        )  # fmt: skip
    return study, str(study.save(tmp_path_factory.mktemp("study") / "s.gpmsa"))


def test_info_shows_a_narrow_range_at_a_large_offset(offset_file, capsys):
    assert main(["info", offset_file[1]]) == 0
    out = capsys.readouterr().out
    assert "known inputs:    v in [1000000.003, 1000000.935]" in out
    assert "parameters:      a in [0.0027385, 0.935072]" in out  # ordinary: as before
    assert "lamWs Gamma(3, 0.003) on (60, 100000)" in out


def test_a_prior_whose_bounds_read_alike_shows_them_apart():
    g = {"a": 5.0, "b": 5.0, "lower": 1e6 + 0.1, "upper": 1e6 + 0.9}
    assert _gamma(g) == "Gamma(5, 5) on (1000000.1, 1000000.9)"
    assert _gamma({"a": 1.0, "b": 0.001, "lower": 0.3, "upper": "inf"}) == (
        "Gamma(1, 0.001) on (0.3, inf)"
    )


def test_a_continuation_whose_range_differs_in_the_7th_digit_says_how(offset_file):
    sim = gpmsa.SimData(x=X, t=T, y=Y, x_names=["v"], t_names=["a"], x_range=[(1e6, 1e6 + 1.5)])
    with pytest.raises(gpmsa.GPMSAError) as err:
        gpmsa.fit(sim, n_iter=10, n_chains=1, seed=1, init=offset_file[0])
    assert "v: [1000000.003, 1000000.935] in init=emulator's fit, [1000000, 1000001.5] here" in (
        str(err.value)
    )


def test_a_unit_array_just_past_1_is_not_said_to_span_0_to_1():
    with pytest.raises(EmulatorFileError, match=r"spans \[0, 1.000000002\]"):
        _in_unit({"x_unit": np.array([[0.0], [1.0 + 2e-9]])}, "x_unit", True)
    with pytest.raises(EmulatorFileError, match=r"spans \[-0.5, 1\]"):  # ordinary: as before
        _in_unit({"x_unit": np.array([[-0.5], [1.0]])}, "x_unit", True)
    with pytest.raises(EmulatorFileError, match=r"column 0 spans \[0, 0.999999998\]"):
        _in_unit({"x_unit": np.array([[0.0], [1.0 - 2e-9]])}, "x_unit", True)


def test_info_json_gives_the_facts_under_documented_keys(offset_file, capsys):
    emu, path = offset_file
    assert main(["info", "--json", path]) == 0
    out = _strict(capsys.readouterr().out)
    assert out["info_format"] == "gpmsa-info/1" and out["kind"] == "emulator"
    assert out["known_inputs"] == [{"name": "v", "unit": "", "range": [1e6 + 0.003, 1e6 + 0.935],
                                    "range_given": False, "levels": None}]  # fmt: skip
    assert out["model"] == {"m": 12, "p": 1, "q": 1, "l_sim": 1, "p_u": 1}
    assert out["model_sha256"] == emu.model_sha256 and out["converged"] is None
    assert out["priors"]["lamUz"] == {"a": 5.0, "b": 5.0, "lower": 0.3, "upper": None}
    assert out["basis"] == {"source": "pca", "vectors": 1, "variance_share": 1.0}
    assert out["manifest"]["domain"]["v"] == [1e6 + 0.003, 1e6 + 0.935]  # the raw one kept
    assert out["array_values"] == 61


def test_info_json_of_non_finite_diagnostics_is_strict_json(tmp_path, capsys):
    sim = gpmsa.SimData(x=X, t=T, y=Y, x_names=["v"], t_names=["a"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", gpmsa.ConvergenceWarning)
        emu = gpmsa.fit(sim, n_iter=30, n_chains=2, n_jobs=1, seed=0, tune=False)
    stuck = {"mean": [1.0], "ess": [float("nan")], "rhat": [float("inf")]}
    worst = {"max_rhat": ["lamUz[0]", float("inf")], "flagged": {"lamUz[0]": "R-hat inf"}}
    emu = replaced(emu, diagnostics={**emu.diagnostics, "lamUz": stuck},
                   convergence={**emu.convergence, **worst})  # fmt: skip
    path = str(emu.save(tmp_path / "stuck.gpmsa"))
    assert main(["info", "--json", path]) == 0
    out = _strict(capsys.readouterr().out)
    assert out["posterior"]["lamUz"] == {"mean": [1.0], "ess": [None], "rhat": [None], "held": [],
                                         "rhat_inf": [0]}  # fmt: skip
    assert out["convergence"]["max_rhat"] == ["lamUz[0]", None] and out["converged"] is False
    assert out["posterior"]["lamWs"]["held"] == [] and out["settings"]["n_chains"] == 2


def test_info_of_a_study_file_as_text_and_strict_json(study_file, capsys):
    study, path = study_file
    assert main(["info", path]) == 0
    text = capsys.readouterr().out
    assert "posterior lamOs[a]: held at 1 (fixed=)" in text and "parameters t in [0, 1]" in text
    assert main(["info", "--json", path]) == 0
    out = _strict(capsys.readouterr().out)  # the held lamOs[a]'s ESS and R-hat are NaN
    assert out["kind"] == "study" and out["study"]["hierarchical"] == ["t"]
    held = out["posterior"]["lamOs[a]"]
    assert held["held"] is True and held["ess"] is None and held["rhat"] is None
    assert out["models"][0]["parameters"] == [{"name": "t", "unit": "", "range": [0.0, 1.0]}]
    assert out["converged"] is False and out["manifest"]["study"]["kind"] == "calibration"


@pytest.mark.parametrize(
    ("content", "said"),
    [
        (None, "cannot read (No such file or directory)"),
        (b"PK\x03\x04junk", "not a gpmsa emulator file"),
        ("npz", "a zip without manifest.json; its first member 'settings.npy': a numpy .npz"),
    ],
)
def test_info_of_what_is_no_gpmsa_file_is_one_line_and_status_2(tmp_path, capsys, content, said):
    path = tmp_path / "f.gpmsa"
    if content == "npz":  # as a vehicle campaign file is written
        with open(path, "wb") as fh:
            np.savez(fh, settings=np.asarray(json.dumps({"format": "vehicle.campaign/1"})))
    elif content is not None:
        path.write_bytes(content)
    for args in (["info", str(path)], ["info", "--json", str(path)]):
        assert main(args) == 2
        captured = capsys.readouterr()
        assert captured.out == "" and said in captured.err and captured.err.count("\n") == 1


def test_a_study_draw_just_past_1_is_not_said_to_lie_at_1(study_file):
    from gpmsa.studies.record import check_study_arrays

    study = study_file[0]
    manifest, arrays = study.to_record(["s.a.gpmsa", "s.b.gpmsa"], ["0" * 64] * 2)
    inputs = tuple(e.p for e in study.members)
    arrays = {**arrays, "theta": arrays["theta"].copy()}
    arrays["theta"][0, 0, 0] = 1.0 + 1e-9
    with pytest.raises(EmulatorFileError, match=r"got 0\.\d+\.\.1\.000000001$"):
        check_study_arrays(manifest, arrays, study.layout, inputs)
