"""examples/_cli.run where stdout's encoding lacks a character the script prints (on Windows a
redirected stdout is the locale's cp1252; ``PYTHONIOENCODING=cp1252`` does the same here): every
script ends by printing the paths it wrote, e.g. ``--out Łódź``.

Before: ``python examples/roadgen_psd_check.py --out Łódź > log.txt`` under cp1252 wrote its
figures, then ended in a UnicodeEncodeError traceback ('charmap' codec can't encode character
'\\u0141') with exit status 1."""

import io
import sys

from tests._examples import load_example

cli = load_example("_cli")


def test_a_character_the_encoding_lacks_is_escaped_not_a_traceback(monkeypatch):
    raw = io.BytesIO()
    out = io.TextIOWrapper(raw, encoding="cp1252", newline="\n")  # errors="strict", as Python's
    monkeypatch.setattr(sys, "stdout", out)
    cli.run(lambda: print("saved Łódź/roadgen_psd_gd450.png"))
    sys.stdout.flush()
    monkeypatch.undo()
    assert raw.getvalue().decode("cp1252") == "saved \\u0141\xf3d\\u017a/roadgen_psd_gd450.png\n"
