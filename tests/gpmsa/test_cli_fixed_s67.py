"""``gpmsa calibrate FILE ... --fixed NAME=VALUE``: a calibration parameter (a t_name, or lamOs)
held at a known value on the command line, as ``calibrate(..., fixed=)`` holds it.

Before: the command had no --fixed (argparse refused it: SystemExit 2)."""

import json
import re

import numpy as np
import pytest
from _calib_cases import categorical_emulator

import gpmsa
from gpmsa import GPMSAError
from gpmsa.cli import calibrate as cli_calibrate
from gpmsa.cli.main import main

OBS = ["--x", "v=0.5", "--y", "f=1.4", "--seed", "3"]


def _emulator() -> gpmsa.Emulator:
    """20 runs of f = v + E + 0.5 k (two calibration parameters; one name holds "=")."""
    rng = np.random.default_rng(3)
    x, t = rng.uniform(0, 1, 20), rng.uniform(0, 1, (20, 2))
    sim = gpmsa.SimData(x=x[:, None], t=t, y=(x + t[:, 0] + 0.5 * t[:, 1])[:, None],
                        x_names=["v"], t_names=["E", "k=1"], y_names=["f"])  # fmt: skip
    prm = {"betaU": [[1.0], [1.0], [1.0]], "lamUz": [1.0], "lamWs": [5e3], "lamWOs": [5e3]}
    return gpmsa.Emulator.from_params(sim, prm)


@pytest.fixture(scope="module")
def emu_file(tmp_path_factory):
    return str(_emulator().save(tmp_path_factory.mktemp("emu") / "two.gpmsa"))


def _run(capsys, *args) -> tuple[int, str, str]:
    code = main(["calibrate", *args])
    out, err = capsys.readouterr()
    return code, out, err


def test_a_held_theta_element_chooses_mcmc_and_is_printed_held(emu_file, capsys):
    code, out, err = _run(capsys, emu_file, *OBS, "--fixed", "k=1=0.4")  # name "k=1"
    assert code == 0, err
    assert out.startswith("posterior (mcmc,")  # auto: the grid for q = 2, MCMC with --fixed
    rows = {line.split()[0]: line for line in out.splitlines()[2:]}
    assert rows["k=1"].split()[1:] == ["held", "at", "0.4", "(fixed=)"]
    assert "held" not in rows["E"] and "held" not in rows["lamOs"]
    assert float(rows["E"].split()[2]) > 0  # E sampled: sd > 0


def test_json_marks_the_held_parameters(emu_file, capsys):
    args = [emu_file, *OBS, "--fixed", "lamOs=1000", "--fixed", "E=0.3", "--json"]
    code, out, err = _run(capsys, *args)
    assert code == 0, err
    out = json.loads(out)
    post = out["posterior"]
    assert out["method"] == "mcmc" and out["fixed"] == {"lamOs": 1000.0, "E": 0.3}
    assert post["lamOs"]["held"] and post["lamOs"]["mean"] == 1000.0 and post["lamOs"]["sd"] == 0
    assert post["E"]["held"] and post["E"]["median"] == 0.3 and post["E"]["ess"] is None
    assert not post["k=1"]["held"] and post["k=1"]["sd"] > 0


def test_the_draws_are_those_of_calibrator_with_fixed(emu_file, capsys):
    code, out, _ = _run(capsys, emu_file, *OBS, "--fixed", "lamOs=1000", "--json")
    cal = gpmsa.Calibrator(_emulator(), method="mcmc", seed=3,
                           mcmc_options={"fixed": {"lamOs": 1000.0}})  # fmt: skip
    post = cal.update([[0.5]], [[1.4]])
    assert code == 0 and json.loads(out)["posterior"]["E"]["mean"] == post.mean("E")


def test_without_fixed_the_output_is_as_before(emu_file, capsys):
    code, out, _ = _run(capsys, emu_file, *OBS, "--json")
    out = json.loads(out)
    assert code == 0 and out["method"] == "grid" and "fixed" not in out
    assert not any(s["held"] for s in out["posterior"].values())


@pytest.mark.parametrize(
    ("extra", "match"),
    [
        (["--fixed", "E=0.3", "--method", "grid"], "--fixed holds parameters on the MCMC path, "
         "and --method grid cannot hold them: use --method mcmc"),
        (["--fixed", "G=0.3"], r"--fixed G: not a calibration parameter of the file; give one "
         r"of \['E', 'k=1', 'lamOs'\]"),
        (["--fixed", "lamVz=3"], "--fixed lamVz: not a calibration parameter"),
        (["--fixed", "E=9"], r"--fixed E=9 cannot be held: give a value inside the design's "
         r"open range \(0\.0"),
        (["--fixed", "lamOs=-1"], r"--fixed lamOs=-1 cannot be held: give a value inside its "
         r"prior's bounds \(0, inf\)"),
        (["--fixed", "E=0.3", "--fixed", " E=0.4"], "--fixed E is given twice"),
        (["--fixed", "E=abc"], "--fixed E: 'abc' is not a number"),
        (["--fixed", "E=nan"], "--fixed E: nan is not a finite number"),
        (["--fixed", "E"], "--fixed expects NAME=VALUE, got 'E'"),
    ],
)  # fmt: skip
def test_bad_fixed_is_one_line_and_status_2(emu_file, capsys, extra, match):
    code, out, err = _run(capsys, emu_file, *OBS, *extra)
    assert code == 2 and out == "" and err.count("\n") == 1
    assert re.search(match, err), err


def test_a_categorical_parameter_must_be_held_at_a_level(tmp_path, capsys):
    emu = categorical_emulator()
    with pytest.raises(GPMSAError, match=r"t0=0.5 cannot be held: give a value at one of its "
                                         r"levels \[0.0, 1.0, 2.0\]"):  # fmt: skip
        cli_calibrate._check_held(emu, ("t0",), "t0", 0.5)
    cli_calibrate._check_held(emu, ("t0",), "t0", 1.0)  # a level: held
    # the command takes such a file (session 73) and refuses a value off the levels by name
    path = str(emu.save(tmp_path / "cat.gpmsa"))
    code, _, err = _run(capsys, path, "--x", "x0=0.3", "--y", "y0=1", "--fixed", "t0=0.5")
    assert code == 2 and "t0=0.5 cannot be held: give a value at one of its levels" in err
