"""``gpmsa`` used in odd but valid ways.

Before: ``python -m gpmsa.cli.main ...`` (the console script's module, run as one) did nothing
and exited 0, whatever the arguments: the module defined ``main`` and never called it; and
``gpmsa calibrate FILE --y-csv=~/y.csv`` (the shell leaves a ``~`` after ``=`` alone, as it
leaves one in quotes) looked for a folder named "~", while FILE in the same form was read
from the home folder."""

import json
import runpy
import shutil
import sys
import warnings
from pathlib import Path

import pytest

from gpmsa._version import __version__
from gpmsa.cli.main import main

ROOT = Path(__file__).resolve().parents[2]
EMULATOR = ROOT / "control" / "emulators" / "jackal_A.gpmsa"


def test_the_console_scripts_module_runs_as_one(monkeypatch, capsys):
    monkeypatch.setattr(sys, "argv", ["gpmsa", "--version"])
    with warnings.catch_warnings():  # runpy: the module is imported already (by this test)
        warnings.simplefilter("ignore", RuntimeWarning)
        with pytest.raises(SystemExit) as done:
            runpy.run_module("gpmsa.cli.main", run_name="__main__")
    assert done.value.code == 0
    assert capsys.readouterr().out == f"gpmsa {__version__}\n"


def test_a_y_csv_path_from_the_home_folder(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("HOME", str(tmp_path))
    shutil.copy(EMULATOR, tmp_path / "jackal A.gpmsa")
    names = ("logP_1p5_4p5Hz", "logP_4p5_7Hz", "logP_7_10Hz", "logP_10_14Hz", "logP_14_20Hz",
             "logP_20_30Hz", "logP_30_45Hz", "logP_45_60Hz", "q90_minus_mean",
             "q98_minus_mean")  # fmt: skip
    values = (0.2, 3.0, 3.5, 2.5, 2.0, 0.6, -0.5, -1.4, 1.4, 2.2)
    (tmp_path / "y é.csv").write_text(
        ",".join(names) + "\n" + ",".join(map(str, values)) + "\n", encoding="utf-8"
    )
    common = ["calibrate", "~/jackal A.gpmsa", "--x", "v=1.0", "--json", "--seed", "1"]
    assert main([*common, "--y-csv=~/y é.csv"]) == 0, capsys.readouterr().err
    from_csv = json.loads(capsys.readouterr().out)
    pairs = [f"--y={n}={v}" for n, v in zip(names, values, strict=True)]
    assert main([*common, *pairs]) == 0
    given = json.loads(capsys.readouterr().out)
    assert from_csv["y"] == given["y"] == dict(zip(names, values, strict=True))
    assert from_csv["posterior"] == given["posterior"]
