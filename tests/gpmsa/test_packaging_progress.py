"""Packaging (py.typed for type checkers) and the fit's progress bar naming its phases."""

import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

import gpmsa

REPO = Path(__file__).resolve().parents[2]
PACKAGES = ("gpmsa", "roadgen", "vehicle", "control")


def test_every_package_ships_py_typed():
    tomllib = pytest.importorskip("tomllib")
    data = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]
    for pkg in PACKAGES:
        assert (REPO / pkg / "py.typed").is_file()
        assert "py.typed" in data["package-data"][pkg]


@pytest.mark.slow
def test_the_wheel_holds_py_typed_and_the_emulators(tmp_path):
    src = tmp_path / "src"  # a copy: setuptools writes build/ and *.egg-info beside the sources
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc")
    for pkg in PACKAGES:
        shutil.copytree(REPO / pkg, src / pkg, ignore=ignore)
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(REPO / name, src / name)
    done = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", str(src), "--no-deps", "--no-build-isolation",
         "-w", str(tmp_path), "-q"],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    (wheel,) = tmp_path.glob("*.whl")
    names = set(zipfile.ZipFile(wheel).namelist())
    for pkg in PACKAGES:
        assert f"{pkg}/py.typed" in names
    assert any(n.startswith("control/emulators/") and n.endswith(".gpmsa") for n in names)


def test_fit_progress_bar_names_tuning_then_sampling(capsys):
    rng = np.random.default_rng(0)
    sim = gpmsa.SimData(x=rng.random((8, 1)), t=rng.random((8, 1)), y=rng.random((8, 1)))
    gpmsa.fit(sim, n_iter=30, seed=0, progress=True, tune_rounds=2, tune_levels=3)
    err = capsys.readouterr().err
    tuning, sampling = err.find("chain 1/1: tuning step widths"), err.rfind("chain 1/1: sampling")
    assert 0 <= tuning < sampling
    gpmsa.fit(sim, n_iter=30, seed=0, progress=True, tune=False)
    err = capsys.readouterr().err
    assert "sampling" in err and "tuning" not in err


def test_calibrate_progress_bar_names_tuning_then_sampling(capsys):
    rng = np.random.default_rng(1)
    x, t = rng.random((12, 1)), rng.random((12, 1))
    sim = gpmsa.SimData(x=x, t=t, y=(x + t) ** 2)
    emu = gpmsa.Emulator.from_params(sim, {"betaU": [[1.0], [1.0]], "lamUz": [1.0],
                                           "lamWs": [1e4], "lamWOs": [1e4]})  # fmt: skip
    gpmsa.calibrate(emu, [[0.5]], [[1.0]], n_samples=50, n_burn=10, progress=True, seed=0,
                    tune_rounds=2, tune_levels=3)  # fmt: skip
    err = capsys.readouterr().err
    assert 0 <= err.find("calibrate: tuning step widths") < err.rfind("calibrate: sampling")
