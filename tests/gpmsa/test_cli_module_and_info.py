"""``python -m gpmsa`` (the ``gpmsa`` command) and what ``gpmsa info`` says of the theta
posterior."""

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
