"""``python -m gpmsa`` (the ``gpmsa`` command) and what ``gpmsa info`` says of the theta
posterior."""

import io
import json
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
from _calib_cases import road_emulator

import gpmsa
from gpmsa.cli.main import main

ROOT = Path(__file__).resolve().parents[2]


def test_python_dash_m_gpmsa_runs_the_gpmsa_command(tmp_path) -> None:
    path = road_emulator().save(tmp_path / "road.gpmsa")
    done = subprocess.run(
        [sys.executable, "-m", "gpmsa", "info", str(path)], capture_output=True, text=True,
        cwd=tmp_path, env={"PYTHONPATH": str(ROOT), "PATH": ""}, timeout=120,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    assert "content sha256:" in done.stdout and "GD in [" in done.stdout
    usage = subprocess.run(
        [sys.executable, "-m", "gpmsa", "--help"], capture_output=True, text=True,
        cwd=tmp_path, env={"PYTHONPATH": str(ROOT), "PATH": ""}, timeout=120,
    )  # fmt: skip
    assert usage.returncode == 0 and usage.stdout.startswith("usage: gpmsa ")


def test_info_prints_the_theta_posterior_in_native_units(tmp_path, capsys) -> None:
    """The file's diagnostics hold theta on the unit scale; info prints it as the rest of the
    CLI does (``gpmsa calibrate``, a study's info): native, by name."""
    t = np.linspace(2.0, 6.0, 8)
    x = np.linspace(0.0, 1.0, 5)
    xg, tg = (a.reshape(-1, 1) for a in np.meshgrid(x, t, indexing="ij"))
    data = gpmsa.SimData(x=xg, t=tg, y=xg * tg, x_names=["x"], t_names=["k"])
    obs = gpmsa.ObsData(x=[[0.2], [0.5], [0.8]], y=[[0.8], [2.0], [3.2]])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = gpmsa.fit(data, obs, n_iter=100, seed=0, tune=False)
    path = emu.save(tmp_path / "joint.gpmsa")
    assert main(["info", str(path)]) == 0
    line = next(s for s in capsys.readouterr().out.splitlines() if "posterior theta" in s)
    unit = emu.diagnostics["theta"]["mean"][0]
    native = 2.0 + 4.0 * unit
    assert "native" in line and f"k={native:.4g}" in line, line
    assert f"[{unit:.4g}]" not in line  # not the unit-scale mean, unlabelled


def _ab_emulator(x_names=("v",), t_names=("k",), y_names=("f",), x_units=("",)):
    """A small scalar emulator of y = x t at fixed parameters (no fit)."""
    rng = np.random.default_rng(0)
    x, t = rng.uniform(0.0, 1.0, (20, 1)), 2.0 + 4.0 * rng.uniform(0.0, 1.0, (20, 1))
    data = gpmsa.SimData(x=x, t=t, y=x * t, x_names=list(x_names), t_names=list(t_names),
                         y_names=list(y_names), x_units=list(x_units))  # fmt: skip
    params = {"betaU": [[1.0], [1.0]], "lamUz": [1.0], "lamWs": [1000.0], "lamWOs": [1000.0]}
    return gpmsa.Emulator.from_params(data, params)


def test_calibrate_reads_a_name_with_surrounding_spaces_whole(tmp_path, capsys) -> None:
    """Names may end or start with a space (a CSV header's "v "); the given NAME was stripped
    before it was matched, so such an emulator could not be calibrated from the command line."""
    path = _ab_emulator(x_names=["v "], y_names=[" f"]).save(tmp_path / "ws.gpmsa")
    assert main(["calibrate", str(path), "--x", "v =0.5", "--y", " f=2", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["x"] == {"v ": 0.5} and out["y"] == {" f": 2.0}
    path = _ab_emulator().save(tmp_path / "plain.gpmsa")  # a stray space still reads as v
    assert main(["calibrate", str(path), "--x", " v=0.5", "--y", "f =2"]) == 0
    assert main(["calibrate", str(path), "--x", "v=0.5", "--x", " v=0.6", "--y", "f=2"]) == 2
    assert "--x v is given twice" in capsys.readouterr().err


def test_calibrate_without_known_inputs_names_only_the_outputs(tmp_path, capsys) -> None:
    rng = np.random.default_rng(1)
    t = rng.uniform(0.0, 1.0, (20, 1))
    data = gpmsa.SimData(t=t, y=np.sin(3.0 * t), t_names=["k"], y_names=["f"])
    params = {"betaU": [[1.0]], "lamUz": [1.0], "lamWs": [1000.0], "lamWOs": [1000.0]}
    path = gpmsa.Emulator.from_params(data, params).save(tmp_path / "nox.gpmsa")
    assert main(["calibrate", str(path), "--y", "f=0.5"]) == 0
    head = capsys.readouterr().out.splitlines()[0]
    assert head.endswith(" given f=0.5"), head  # not "given ; f=0.5"


def test_output_in_an_encoding_lacking_a_name_is_escaped_not_a_traceback(
    tmp_path, monkeypatch
) -> None:
    """``gpmsa info FILE > out.txt`` on Windows writes cp1252: a parameter named "σ" raised
    UnicodeEncodeError (a traceback); it is written as \\u03c3, as ``safe`` escapes."""
    path = _ab_emulator(t_names=["σ"], x_units=["m/s²"]).save(tmp_path / "uni.gpmsa")
    for argv in (["info", str(path)], ["calibrate", str(path), "--x", "v=0.5", "--y", "f=2"]):
        raw = io.BytesIO()
        out = io.TextIOWrapper(raw, encoding="ascii", newline="\n")
        monkeypatch.setattr(sys, "stdout", out)
        assert main(argv) == 0
        out.flush()
        text = raw.getvalue().decode("ascii")
        assert "\\u03c3" in text and (argv[0] != "info" or "m/s\\xb2" in text), text


def test_info_prints_a_fixed_theta_in_native_units(tmp_path, capsys) -> None:
    """``fit(..., fixed={"theta": 4.0})`` takes native units; the file stores the unit-scale
    value, which info printed as ``theta=[0.5...]`` as if it were the value given."""
    rng = np.random.default_rng(2)
    x, t = rng.uniform(0.0, 1.0, (20, 1)), 2.0 + 4.0 * rng.uniform(0.0, 1.0, (20, 1))
    data = gpmsa.SimData(x=x, t=t, y=x * t, t_names=["k"])
    obs = gpmsa.ObsData(x=[[0.2], [0.5]], y=[[0.8], [2.0]])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        emu = gpmsa.fit(data, obs, n_iter=40, seed=0, tune=False, fixed={"theta": 4.0})
    assert main(["info", str(emu.save(tmp_path / "fixed.gpmsa"))]) == 0
    line = next(s for s in capsys.readouterr().out.splitlines() if s.startswith("fixed:"))
    assert "theta (native)=[k=4]" in line, line


def test_an_unexpected_error_is_one_line_not_a_traceback(tmp_path, capsys, monkeypatch) -> None:
    """A gap in the library's checks is named in one line on stderr, exit status 1. (A study
    file with sd_max = 10**30 made HyperPriors raise TypeError; HyperPriors now takes it, and
    refuses 10**400 as a bad file: status 2.)"""
    from _study_cases import emulator, observations

    from gpmsa.io.container import ENVELOPE, STUDY_FORMAT, read_raw, write_raw

    rng = np.random.default_rng(3)
    data = [observations(0.4, 3, 0.05, rng) for _ in range(2)]
    study = gpmsa.calibrate_study(
        [emulator(None)] * 2, [d[0] for d in data], [d[1] for d in data], shared=["t"],
        n_samples=60, n_burn=20, seed=1, tune=False,
    )  # fmt: skip
    path = study.save(tmp_path / "run.gpmsa")
    manifest, arrays = read_raw(path, formats=(STUDY_FORMAT,))
    manifest = {k: v for k, v in manifest.items() if k not in ENVELOPE}
    manifest["priors"]["hyper"]["sd_max"] = 10**400
    write_raw(path, manifest, arrays, fmt=STUDY_FORMAT)
    assert main(["info", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("gpmsa info: ") and err.count("\n") == 1, err

    def gap(*args, **kwargs):
        raise TypeError("a \x1b[31m gap")

    monkeypatch.setattr(gpmsa.cli.info, "_lines", gap)
    emu_path = _ab_emulator().save(tmp_path / "info.gpmsa")
    assert main(["info", str(emu_path)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "unexpected TypeError (a \\x1b[31m gap)" in err, err

    def broken(self, x_obs, y_obs, **kw):
        raise TypeError("a \x1b[31m message")

    monkeypatch.setattr(gpmsa.Calibrator, "update", broken)
    path = _ab_emulator().save(tmp_path / "ab.gpmsa")
    assert main(["calibrate", str(path), "--x", "v=0.5", "--y", "f=2"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "unexpected TypeError (a \\x1b[31m message)" in err, err


def test_info_prints_the_model_sha256_a_calibration_records(tmp_path, capsys) -> None:
    """``gpmsa info`` shows the emulator's ``model_sha256``: the value a calibration with this
    file's emulator records as info "emulator_sha256", so a shared posterior can be matched to
    its file."""
    path = road_emulator().save(tmp_path / "road.gpmsa")
    assert main(["info", str(path)]) == 0
    line = next(s for s in capsys.readouterr().out.splitlines() if s.startswith("model sha256:"))
    emu = gpmsa.load(path)
    post = gpmsa.Calibrator(emu, method="grid").update([[1.0]], [[emu.y[0, 0]]])
    assert post.info["emulator_sha256"] == emu.model_sha256
    assert line.split()[2] == emu.model_sha256


def test_info_prints_the_priors_a_calibration_uses(tmp_path, capsys) -> None:
    """Session 62: a shared file's calibration priors (set with ``with_calibration_priors``,
    one lamVz prior per group included) were not shown anywhere."""
    emu = _ab_emulator().with_calibration_priors(
        theta_sd=0.2, lamOs=gpmsa.GammaPrior(50.0, 0.5),
        lamVz=[gpmsa.GammaPrior(1.0, 1e-3), gpmsa.GammaPrior(1000.0, 0.1, 10.0, 1e6)],
    )  # fmt: skip
    assert main(["info", str(emu.save(tmp_path / "p.gpmsa"))]) == 0
    out = capsys.readouterr().out
    assert (
        "calibration priors: theta Normal(0.5, 0.2) on (0, 1) (unit scale), lamOs Gamma(50, 0.5), "
        "lamVz [Gamma(1, 0.001), Gamma(1000, 0.1) on (10, 1e+06)] (one per group), betaV as betaU"
    ) in out
    assert "lamUz Gamma(5, 5) on (0.3, inf), lamWs Gamma(3, 0.003) on (60, 100000)" in out
    assert "lamWOs Gamma(5, 0.005) on (60, 100000) (with GPM/SA's data corrections)" in out


def test_ctrl_c_is_one_line_and_exit_status_130(monkeypatch, capsys) -> None:
    """Ctrl-C during a gpmsa command printed a traceback."""

    def interrupted(args):
        raise KeyboardInterrupt

    monkeypatch.setattr(gpmsa.cli.info, "run", interrupted)
    assert main(["info", "x.gpmsa"]) == 130
    assert capsys.readouterr().err == "gpmsa: interrupted (Ctrl-C)\n"
