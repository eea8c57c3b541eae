"""``terrain-replay --version`` prints the library's version as ``gpmsa --version`` does (its
program name, then ``gpmsa.__version__``, the distribution's version), and exits 0 before any
argument check: no bag or --emulator needed, no robot extra."""

import sys

import pytest

import gpmsa
from control.robot import cli
from gpmsa.cli.main import main as gpmsa_main


def test_version_prints_the_library_version_as_gpmsa_does(capsys):
    with pytest.raises(SystemExit) as done:
        cli.main(["--version"])
    assert done.value.code == 0
    out = capsys.readouterr().out
    assert out == f"terrain-replay {gpmsa.__version__}\n"
    with pytest.raises(SystemExit) as done:
        gpmsa_main(["--version"])
    assert done.value.code == 0
    assert capsys.readouterr().out.split() == ["gpmsa", out.split()[1]]


def test_version_is_listed_in_help(capsys, monkeypatch):
    monkeypatch.setattr(sys, "argv", ["terrain-replay", "--help"])
    with pytest.raises(SystemExit):
        cli.main()
    assert "--version" in capsys.readouterr().out
