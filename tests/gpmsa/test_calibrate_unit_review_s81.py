"""``gpmsa calibrate`` prints a parameter's unit in brackets, as ``gpmsa info`` does ("GD [1e-6
m^3]"): the shipped emulators' GD unit "1e-6 m^3" printed bare after the row's figures read as
one more figure ("576.4 1e-6 m^3"; a script reading the row's numbers took it for one), and a
held row read "GD held at 400 1e-6 m^3". A grid marginal's repr prints a zero end as "0"."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gpmsa.calibration.posterior import GridMarginal
from gpmsa.cli.main import main

WINDOW_A = str(Path(__file__).resolve().parents[2] / "control/emulators/jackal_A_window.gpmsa")
GIVEN = ["--x", "v=1.25", "--y", "log_f=4.3"]  # inside what the emulator has seen


def _figures(tokens: list[str]) -> list[float]:
    out = []
    for token in tokens:
        try:
            out.append(float(token))
        except ValueError:
            pass
    return out


def test_the_unit_is_printed_in_brackets_after_the_figures(capsys):
    assert main(["calibrate", WINDOW_A, *GIVEN]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[1].split()[-1] == "unit", lines[1]
    row = next(line for line in lines if line.split()[0] == "GD")
    assert row.endswith(" [1e-6 m^3]"), row
    assert len(_figures(row.split()[1:])) == 5, row  # mean, sd, q5, median, q95: no "1e-6"


def test_a_held_row_brackets_its_unit(capsys):
    assert main(["calibrate", WINDOW_A, *GIVEN, "--fixed", "GD=400", "--seed", "1"]) == 0
    lines = capsys.readouterr().out.splitlines()
    row = next(line for line in lines if line.split()[0] == "GD")
    assert row.split(maxsplit=1)[1] == "held at 400 [1e-6 m^3] (fixed=)", row


def test_a_grid_marginal_prints_a_zero_end_as_zero():
    gm = GridMarginal.from_log_density(np.array([-0.0, 0.5, 1.0]), np.zeros(3))
    assert repr(gm).startswith("GridMarginal(3 nodes on [0, 1],"), repr(gm)
