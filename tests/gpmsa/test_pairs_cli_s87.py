"""``gpmsa calibrate``'s --x and --y values that are no finite number, and --x given to a file
without known inputs, are refused naming the option (all-pairs sweep of the CLI's options).

Before: ``--x v=inf`` and ``--y f=nan`` reached the library, which named ``x_obs`` and
``y_obs`` ("y_obs must be finite, got nan at index (0, 0)"), not the option or the name, while
``--fixed E=nan`` and a CSV file's NaN were named; ``--x v=0.5`` to a file with no x said
"--x needs exactly the names []; unknown ['v'], missing []"."""

import numpy as np
import pytest

import gpmsa
from gpmsa.cli.main import main


def _emulator(p: int) -> gpmsa.Emulator:
    """12 runs of f = v + t (p = 1) or f = t (p = 0), at fixed parameters."""
    rng = np.random.default_rng(0)
    x, t = rng.uniform(0, 1, (12, p)), rng.uniform(0, 1, (12, 1))
    y = t + x.sum(axis=1, keepdims=True)
    sim = gpmsa.SimData(x=x if p else None, t=t, y=y, x_names=["v"] if p else None,
                        t_names=["t"], y_names=["f"])  # fmt: skip
    prm = {"betaU": [[1.0]] * (p + 1), "lamUz": [1.0], "lamWs": [5e3], "lamWOs": [5e3]}
    return gpmsa.Emulator.from_params(sim, prm)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("emu")
    return {p: str(_emulator(p).save(folder / f"p{p}.gpmsa")) for p in (0, 1)}


@pytest.mark.parametrize(
    ("given", "message"),
    [
        (["--x", "v=inf", "--y", "f=1"], "--x v: inf is not a finite number"),
        (["--x", "v=1e400", "--y", "f=1"], "--x v: 1e400 is not a finite number (beyond float64"),
        (["--x", "v=0.5", "--y", "f=nan"], "--y f: nan is not a finite number"),
        (["--x", "v=0.5", "--y", "f=-Infinity"], "--y f: -Infinity is not a finite number"),
    ],
)
def test_a_value_that_is_no_finite_number_names_the_option(files, capsys, given, message):
    code = main(["calibrate", files[1], *given, "--seed", "1"])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert message in err and "x_obs" not in err and "y_obs" not in err
    assert ("beyond float64" in err) == ("1e400" in message)  # only an overflow says so


def test_x_for_a_file_without_known_inputs_says_so(files, capsys):
    code = main(["calibrate", files[0], "--x", "v=0.5", "--y", "f=1", "--seed", "1"])
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert "--x v: the file has no known inputs (x); leave --x out" in err
    assert main(["calibrate", files[0], "--y", "f=0.5", "--seed", "1"]) == 0
