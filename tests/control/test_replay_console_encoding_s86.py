"""``terrain-replay`` whose output goes to a file or pipe in an encoding that lacks a character
of what it prints (on Windows a redirected stdout is the locale's cp1252; ``PYTHONIOENCODING=
cp1252`` does the same here): the paths of its outputs, after a bag or folder named "Łódź".

Before: the command wrote its outputs, then ended in a UnicodeEncodeError traceback ('charmap'
codec can't encode character '\\u0141') with exit status 1 at its "wrote ..." line; `gpmsa`'s
own command escaped such a character already."""

import io
import sys

import numpy as np
import pytest

pytest.importorskip("rosbags")
pytest.importorskip("mcap")

from control.robot import cli, write_sensor_bag  # noqa: E402


def test_a_path_the_output_encoding_lacks_is_escaped_not_a_traceback(tmp_path, monkeypatch):
    t = 1.0 + np.arange(400) / 120.0
    accel = np.random.default_rng(1).normal(size=t.size)
    bag = write_sensor_bag(tmp_path / "Łódź_drive", t, accel, t, t - 1.0, np.ones(t.size))
    raw = io.BytesIO()
    out = io.TextIOWrapper(raw, encoding="cp1252", newline="\n")  # errors="strict", as Python's
    monkeypatch.setattr(sys, "stdout", out)
    code = cli.main([str(bag), "--emulator", "A", "--out", str(tmp_path / "Łódź_out")])
    out.flush()
    monkeypatch.undo()
    assert code == 0
    text = raw.getvalue().decode("cp1252")
    assert "\\u0141\xf3d\\u017a_out" in text and "estimates.csv" in text, text
    assert sorted(p.name for p in (tmp_path / "Łódź_out").iterdir()) == sorted(cli.OUTPUTS)
